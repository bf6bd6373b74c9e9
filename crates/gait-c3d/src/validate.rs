//! Checks of the caller's data against what a C3D file can hold, before anything is encoded.

use std::collections::HashSet;

use crate::C3dData;
use crate::error::C3dError;

/// Largest frame number the header's 16-bit words can hold.
const MAX_FRAME: usize = u16::MAX as usize;
/// Parameter dimensions are one byte: at most 255 labels or events in one array.
const MAX_ARRAY: usize = 255;

/// What the encoders need once the data passed the checks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Checked {
    pub frames: usize,
    pub first_frame: u16,
    pub last_frame: u16,
    pub rate_hz: f32,
}

/// Checks everything but the coordinates themselves (the point encoder checks those as it goes).
pub(crate) fn check(data: &C3dData) -> Result<Checked, C3dError> {
    let rate_hz = data.rate_hz as f32;
    if !(data.rate_hz.is_finite() && rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(C3dError::InvalidRate(data.rate_hz));
    }
    let first = data.markers.first().ok_or(C3dError::NoMarkers)?;
    if data.markers.len() > MAX_ARRAY {
        return Err(C3dError::TooManyMarkers(data.markers.len()));
    }
    let frames = first.xy.len();
    if frames == 0 {
        return Err(C3dError::NoFrames);
    }
    let mut seen = HashSet::new();
    for m in &data.markers {
        if m.xy.len() != frames {
            return Err(C3dError::FrameCountMismatch {
                label: m.label.clone(),
                got: m.xy.len(),
                first: first.label.clone(),
                expected: frames,
            });
        }
        text_rule(&m.label).map_err(|reason| C3dError::InvalidLabel {
            label: m.label.clone(),
            reason,
        })?;
        if !seen.insert(m.label.as_str()) {
            return Err(C3dError::DuplicateLabel(m.label.clone()));
        }
    }
    text_rule(&data.units).map_err(|reason| C3dError::InvalidUnits {
        units: data.units.clone(),
        reason,
    })?;
    if data.first_frame == 0 {
        return Err(C3dError::InvalidFirstFrame(0));
    }
    let last = data.first_frame.saturating_add(frames - 1);
    if last > MAX_FRAME {
        return Err(C3dError::TooManyFrames {
            first: data.first_frame,
            last,
        });
    }
    if data.events.len() > MAX_ARRAY {
        return Err(C3dError::TooManyEvents(data.events.len()));
    }
    for (index, e) in data.events.iter().enumerate() {
        let ok = e.time_s.is_finite() && e.time_s >= 0.0 && ((e.time_s / 60.0) as f32).is_finite();
        if !ok {
            return Err(C3dError::InvalidEventTime {
                index,
                time_s: e.time_s,
            });
        }
    }
    Ok(Checked {
        frames,
        first_frame: data.first_frame as u16,
        last_frame: last as u16,
        rate_hz,
    })
}

/// Labels and units are stored as space-padded ASCII and read back trimmed, so they must be
/// non-empty printable ASCII without spaces at either end, and fit a one-byte dimension.
fn text_rule(s: &str) -> Result<(), &'static str> {
    if s.is_empty() {
        return Err("empty");
    }
    if !s.bytes().all(|b| (0x20..0x7f).contains(&b)) {
        return Err("only printable ASCII characters are allowed");
    }
    if s.starts_with(' ') || s.ends_with(' ') {
        return Err("leading or trailing spaces would be lost (readers trim them)");
    }
    if s.len() > MAX_ARRAY {
        return Err("longer than 255 characters");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Context, Event, EventKind, Marker};

    fn data() -> C3dData {
        C3dData {
            rate_hz: 30.0,
            first_frame: 1,
            units: "px".into(),
            markers: vec![
                Marker {
                    label: "LHeel".into(),
                    xy: vec![Some([1.0, 2.0]), None],
                },
                Marker {
                    label: "RHeel".into(),
                    xy: vec![None, Some([3.0, 4.0])],
                },
            ],
            events: vec![Event {
                context: Context::Left,
                kind: EventKind::FootStrike,
                time_s: 0.5,
            }],
        }
    }

    #[test]
    fn accepts_good_data() {
        let c = check(&data()).unwrap();
        assert_eq!(
            c,
            Checked {
                frames: 2,
                first_frame: 1,
                last_frame: 2,
                rate_hz: 30.0
            }
        );
    }

    #[test]
    fn rejects_bad_rates() {
        for rate in [0.0, -30.0, f64::NAN, f64::INFINITY, 1e300, 1e-300] {
            let mut d = data();
            d.rate_hz = rate;
            assert!(matches!(check(&d), Err(C3dError::InvalidRate(_))), "{rate}");
        }
    }

    #[test]
    fn rejects_bad_shapes() {
        let mut d = data();
        d.markers.clear();
        assert!(matches!(check(&d), Err(C3dError::NoMarkers)));

        let mut d = data();
        d.markers.iter_mut().for_each(|m| m.xy.clear());
        assert!(matches!(check(&d), Err(C3dError::NoFrames)));

        let mut d = data();
        d.markers[1].xy.push(None);
        let e = check(&d).unwrap_err();
        assert!(
            matches!(
                e,
                C3dError::FrameCountMismatch {
                    got: 3,
                    expected: 2,
                    ..
                }
            ),
            "{e}"
        );

        let mut d = data();
        d.markers = (0..256)
            .map(|i| Marker {
                label: format!("M{i}"),
                xy: vec![None],
            })
            .collect();
        assert!(matches!(check(&d), Err(C3dError::TooManyMarkers(256))));
    }

    #[test]
    fn rejects_bad_labels_and_units() {
        for label in [
            "",
            " LHeel",
            "LHeel ",
            "Ferse\u{e9}",
            "a\tb",
            &"x".repeat(256),
        ] {
            let mut d = data();
            d.markers[0].label = label.to_string();
            assert!(
                matches!(check(&d), Err(C3dError::InvalidLabel { .. })),
                "{label:?}"
            );
        }
        let mut d = data();
        d.markers[1].label = "LHeel".into();
        assert!(matches!(check(&d), Err(C3dError::DuplicateLabel(l)) if l == "LHeel"));

        let mut d = data();
        d.units = String::new();
        assert!(matches!(check(&d), Err(C3dError::InvalidUnits { .. })));
    }

    #[test]
    fn rejects_frame_numbers_past_the_header() {
        let mut d = data();
        d.first_frame = 0;
        assert!(matches!(check(&d), Err(C3dError::InvalidFirstFrame(0))));

        let mut d = data();
        d.first_frame = 65535;
        assert!(matches!(
            check(&d),
            Err(C3dError::TooManyFrames {
                first: 65535,
                last: 65536
            })
        ));
        d.first_frame = 65534;
        assert_eq!(check(&d).unwrap().last_frame, 65535);

        let mut d = data();
        d.first_frame = usize::MAX;
        assert!(matches!(check(&d), Err(C3dError::TooManyFrames { .. })));
    }

    #[test]
    fn rejects_bad_events() {
        for t in [-0.1, f64::NAN, f64::INFINITY, 1e300] {
            let mut d = data();
            d.events.push(Event {
                context: Context::Right,
                kind: EventKind::FootOff,
                time_s: t,
            });
            assert!(
                matches!(check(&d), Err(C3dError::InvalidEventTime { index: 1, .. })),
                "{t}"
            );
        }
        let mut d = data();
        let e = d.events[0].clone();
        d.events = vec![e; 256];
        assert!(matches!(check(&d), Err(C3dError::TooManyEvents(256))));
    }
}
