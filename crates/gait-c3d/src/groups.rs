//! Which parameters the file carries: POINT, ANALOG, TRIAL, EVENT (as Vicon Nexus writes gait
//! events, which Mokka and other gait tools expect) and MANUFACTURER.

use crate::error::C3dError;
use crate::parameters::{Group, Parameter};
use crate::validate::Checked;
use crate::{C3dData, EventKind};

/// POINT:SCALE and the header's scale: negative means float storage; with float storage the
/// magnitude only scales the residual, so 1 keeps the coordinates exactly as given.
pub(crate) const SCALE: f32 = -1.0;

/// Describes every marker: they are image keypoints, so z is always 0.
const MARKER_DESCRIPTION: &str = "2-D keypoint (z = 0)";

/// All groups, with POINT:DATA_START = `data_start_block` (1-based block number).
pub(crate) fn groups(
    data: &C3dData,
    c: &Checked,
    data_start_block: u16,
) -> Result<Vec<Group>, C3dError> {
    Ok(vec![
        point(data, c, data_start_block)?,
        analog(c),
        trial(c)?,
        event(data)?,
        manufacturer()?,
    ])
}

fn point(data: &C3dData, c: &Checked, data_start_block: u16) -> Result<Group, C3dError> {
    let labels: Vec<&str> = data.markers.iter().map(|m| m.label.as_str()).collect();
    let descriptions = vec![MARKER_DESCRIPTION; labels.len()];
    Ok(Group {
        name: "POINT",
        description: "3-D point parameters",
        parameters: vec![
            Parameter::int("USED", "Number of points", labels.len() as i16),
            frames(c.frames),
            Parameter::float("SCALE", "Negative: float32 data", SCALE),
            Parameter::float("RATE", "Frames per second", c.rate_hz),
            Parameter::int("DATA_START", "First data block", data_start_block as i16),
            Parameter::text("UNITS", "Coordinate units", &data.units)?,
            Parameter::texts("LABELS", "Point labels", &labels)?,
            Parameter::texts("DESCRIPTIONS", "Point descriptions", &descriptions)?,
            // Image axes: x to the right, y downwards, so the screen's up is -Y. Viewers that
            // honour these show the keypoints the way the video does.
            Parameter::text("X_SCREEN", "Screen right", "+X")?,
            Parameter::text("Y_SCREEN", "Screen up", "-Y")?,
        ],
    })
}

/// POINT:FRAMES is an int16 parameter that readers such as ezc3d take as unsigned, which is how
/// counts up to 65535 fit: past 32767 the bits are those of the u16 count (ezc3d writes it so,
/// and refuses a float FRAMES). The validator keeps `n` <= 65535.
fn frames(n: usize) -> Parameter {
    Parameter::int("FRAMES", "Number of frames", n as u16 as i16)
}

/// No analog channels; the rate equals the point rate, as the header's one sample per frame says.
fn analog(c: &Checked) -> Group {
    Group {
        name: "ANALOG",
        description: "Analog data parameters",
        parameters: vec![
            Parameter::int("USED", "Number of analog channels", 0),
            Parameter::float("RATE", "Analog samples per second", c.rate_hz),
        ],
    }
}

/// The frame range again, as two 16-bit halves (low, high) of a 32-bit frame number.
fn trial(c: &Checked) -> Result<Group, C3dError> {
    let halves = |frame: u16| vec![frame as i16, 0];
    Ok(Group {
        name: "TRIAL",
        description: "Trial parameters",
        parameters: vec![
            Parameter::ints(
                "ACTUAL_START_FIELD",
                "First frame (low, high word)",
                halves(c.first_frame),
            )?,
            Parameter::ints(
                "ACTUAL_END_FIELD",
                "Last frame (low, high word)",
                halves(c.last_frame),
            )?,
        ],
    })
}

/// Events as Vicon writes them: context "Left"/"Right", label "Foot Strike"/"Foot Off", its
/// description and icon id, and times as [minutes, seconds] pairs from the recording's start.
fn event(data: &C3dData) -> Result<Group, C3dError> {
    let events = &data.events;
    let mut parameters = vec![Parameter::int(
        "USED",
        "Number of events",
        events.len() as i16,
    )];
    // Arrays of length 0 would need a zero dimension, which not every reader takes.
    if !events.is_empty() {
        let contexts: Vec<&str> = events.iter().map(|e| e.context.label()).collect();
        let labels: Vec<&str> = events.iter().map(|e| e.kind.label()).collect();
        let descriptions: Vec<&str> = events.iter().map(|e| e.kind.description()).collect();
        let subjects = vec![""; events.len()];
        let times: Vec<f32> = events
            .iter()
            .flat_map(|e| minutes_seconds(e.time_s))
            .collect();
        let icons: Vec<i16> = events.iter().map(|e| e.kind.icon_id()).collect();
        parameters.extend([
            Parameter::texts("CONTEXTS", "Event contexts", &contexts)?,
            Parameter::texts("LABELS", "Event labels", &labels)?,
            Parameter::texts("DESCRIPTIONS", "Event descriptions", &descriptions)?,
            Parameter::texts("SUBJECTS", "Event subjects", &subjects)?,
            Parameter::floats(
                "TIMES",
                "Event times: minutes, seconds",
                &[2, events.len()],
                times,
            )?,
            Parameter::ints("ICON_IDS", "Event icon ids", icons)?,
            // 0: a named event of its context, not a "General" one.
            Parameter::ints(
                "GENERIC_FLAGS",
                "Event generic flags",
                vec![0; events.len()],
            )?,
        ]);
    }
    Ok(Group {
        name: "EVENT",
        description: "Event parameters",
        parameters,
    })
}

/// Splits a time into whole minutes and the remaining seconds: the float32 seconds then keep
/// sub-microsecond resolution however long the recording.
fn minutes_seconds(t: f64) -> [f32; 2] {
    let mut minutes = (t / 60.0).floor();
    let mut seconds = t - minutes * 60.0;
    if seconds < 0.0 {
        // t / 60 rounded up to a whole number.
        minutes -= 1.0;
        seconds += 60.0;
    }
    [minutes as f32, seconds as f32]
}

fn manufacturer() -> Result<Group, C3dError> {
    Ok(Group {
        name: "MANUFACTURER",
        description: "Software that wrote the file",
        parameters: vec![
            Parameter::text("COMPANY", "", "gait")?,
            Parameter::text("SOFTWARE", "", "gait-c3d")?,
            Parameter::text("VERSION_LABEL", "", env!("CARGO_PKG_VERSION"))?,
        ],
    })
}

impl EventKind {
    /// Vicon's description of the event.
    fn description(self) -> &'static str {
        match self {
            EventKind::FootStrike => "The instant the heel strikes the ground",
            EventKind::FootOff => "The instant the toe leaves the ground",
        }
    }

    /// Vicon's icon id (Mokka and Nexus draw strikes and offs differently by it).
    fn icon_id(self) -> i16 {
        match self {
            EventKind::FootStrike => 1,
            EventKind::FootOff => 2,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parameters::Data;
    use crate::{Context, Event, Marker};

    fn find<'a>(g: &'a Group, name: &str) -> &'a Parameter {
        g.parameters.iter().find(|p| p.name == name).unwrap()
    }

    #[test]
    fn times_split_into_minutes_and_seconds() {
        assert_eq!(minutes_seconds(0.0), [0.0, 0.0]);
        assert_eq!(minutes_seconds(12.5), [0.0, 12.5]);
        assert_eq!(minutes_seconds(60.0), [1.0, 0.0]);
        assert_eq!(minutes_seconds(125.25), [2.0, 5.25]);
        let [m, s] = minutes_seconds(3600.0 + 1.0 / 30.0);
        assert_eq!(m, 60.0);
        assert!((f64::from(s) - 1.0 / 30.0).abs() < 1e-8);
    }

    #[test]
    fn event_group_as_vicon_writes_it() {
        let data = C3dData {
            rate_hz: 100.0,
            first_frame: 1,
            units: "mm".into(),
            markers: vec![Marker {
                label: "A".into(),
                xy: vec![None],
            }],
            events: vec![
                Event {
                    context: Context::Right,
                    kind: EventKind::FootOff,
                    time_s: 61.5,
                },
                Event {
                    context: Context::Left,
                    kind: EventKind::FootStrike,
                    time_s: 0.25,
                },
            ],
        };
        let g = event(&data).unwrap();
        assert_eq!(find(&g, "USED").data, Data::Int16(vec![2]));
        assert_eq!(
            find(&g, "CONTEXTS").data,
            Data::Char(b"RightLeft ".to_vec())
        );
        assert_eq!(find(&g, "LABELS").dims, vec![11, 2]);
        assert_eq!(
            find(&g, "LABELS").data,
            Data::Char(b"Foot Off   Foot Strike".to_vec())
        );
        assert_eq!(find(&g, "TIMES").dims, vec![2, 2]);
        assert_eq!(
            find(&g, "TIMES").data,
            Data::Float(vec![1.0, 1.5, 0.0, 0.25])
        );
        assert_eq!(find(&g, "ICON_IDS").data, Data::Int16(vec![2, 1]));
        assert_eq!(find(&g, "GENERIC_FLAGS").data, Data::Int16(vec![0, 0]));

        let none = C3dData {
            events: vec![],
            ..data
        };
        let g = event(&none).unwrap();
        assert_eq!(g.parameters.len(), 1);
        assert_eq!(find(&g, "USED").data, Data::Int16(vec![0]));
    }

    #[test]
    fn frames_past_i16_keep_their_u16_bits() {
        assert_eq!(frames(300).data, Data::Int16(vec![300]));
        assert_eq!(frames(40_000).data, Data::Int16(vec![40_000u16 as i16]));
    }

    #[test]
    fn trial_halves() {
        let c = Checked {
            frames: 100,
            first_frame: 40_000,
            last_frame: 40_099,
            rate_hz: 50.0,
        };
        let g = trial(&c).unwrap();
        assert_eq!(
            find(&g, "ACTUAL_START_FIELD").data,
            Data::Int16(vec![40_000u16 as i16, 0])
        );
        assert_eq!(
            find(&g, "ACTUAL_END_FIELD").data,
            Data::Int16(vec![40_099u16 as i16, 0])
        );
    }
}
