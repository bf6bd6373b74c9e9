//! What each frame shows, decided from a run folder's outputs.
//!
//! - Poses: `keypoints_filtered.csv`, the keypoints the angles, events and
//!   cycles were computed from. Keypoints the filter dropped (low likelihood,
//!   too long a gap) stay undrawn rather than being taken from the raw
//!   `keypoints.csv`: the overlay shows what the analysis used. Only when the
//!   filtered file is missing (a run without kinematics) is `keypoints.csv`
//!   shown, with a warning.
//! - Events (`events.csv`): labelled from their frame for [`LABEL_SECONDS`].
//! - Dimming: a frame outside every walking bout (`bouts.csv`) is "outside
//!   walking bout"; a frame inside a bout that lies in a rejected cycle
//!   (`cycle_quality.csv`, `accepted` false) and in no accepted cycle of
//!   either side is "rejected cycle (side: reasons)". A frame in an accepted
//!   cycle of one side counts, whatever the other side's cycle.

use std::path::Path;

use gait_core::PoseSequence;

use crate::{EventKind, EventMark, FrameMarks, OverlayError, Side};

/// How long an event's label and marker stay on screen.
pub const LABEL_SECONDS: f64 = 0.3;

/// A gait event at an input frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EventAt {
    pub side: Side,
    pub kind: EventKind,
    pub frame: usize,
}

/// One stride of `cycle_quality.csv`: inclusive input frames and verdict.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CycleSpan {
    pub side: Side,
    pub first: usize,
    pub last: usize,
    pub accepted: bool,
    /// Why it was rejected (e.g. `stride_time`); empty when accepted.
    pub reasons: Vec<String>,
}

/// The marks of a run folder, ready to push frame by frame.
#[derive(Debug, Clone, PartialEq)]
pub struct RunMarks {
    pub fps: f64,
    /// Keypoint names of the poses (for [`crate::OverlayWriter::start`]).
    pub names: Vec<String>,
    /// One entry per frame analysed, in input order.
    pub marks: Vec<FrameMarks>,
    /// Outputs that were missing, and what the overlay lacks because of it.
    pub warnings: Vec<String>,
}

/// Builds the marks of every pose of `seq`. `bouts` are inclusive frame
/// ranges (`None`: unknown, nothing is dimmed for being outside one).
pub fn plan_marks(
    seq: &PoseSequence,
    events: &[EventAt],
    bouts: Option<&[[usize; 2]]>,
    cycles: &[CycleSpan],
) -> Vec<FrameMarks> {
    let fps = if seq.fps.is_finite() && seq.fps > 0.0 {
        seq.fps
    } else {
        30.0
    };
    let label_frames = ((LABEL_SECONDS * fps).round() as usize).max(1);
    let mut events = events.to_vec();
    events.sort_by_key(|e| e.frame);
    seq.frames
        .iter()
        .zip(&seq.poses)
        .map(|(&frame, pose)| FrameMarks {
            frame,
            time_s: frame as f64 / fps,
            // A pose without any keypoint (nobody found) draws nothing.
            pose: pose
                .keypoints
                .iter()
                .any(|k| k.is_found())
                .then(|| pose.clone()),
            events: events
                .iter()
                .filter(|e| e.frame <= frame && frame - e.frame < label_frames)
                .map(|e| EventMark {
                    side: e.side,
                    kind: e.kind,
                    age_frames: frame - e.frame,
                })
                .collect(),
            dim: dim_reason(frame, bouts, cycles),
        })
        .collect()
}

fn dim_reason(frame: usize, bouts: Option<&[[usize; 2]]>, cycles: &[CycleSpan]) -> Option<String> {
    if let Some(b) = bouts
        && !b.iter().any(|r| (r[0]..=r[1]).contains(&frame))
    {
        return Some("outside walking bout".into());
    }
    let covering = || {
        cycles
            .iter()
            .filter(|c| (c.first..=c.last).contains(&frame))
    };
    if covering().any(|c| c.accepted) {
        return None;
    }
    let why: Vec<String> = covering()
        .map(|c| {
            let reasons: Vec<String> = c.reasons.iter().map(|r| r.replace('_', " ")).collect();
            if reasons.is_empty() {
                c.side.name().to_string()
            } else {
                format!("{}: {}", c.side.name(), reasons.join(", "))
            }
        })
        .collect();
    (!why.is_empty()).then(|| format!("rejected cycle ({})", why.join("; ")))
}

/// Reads a run folder (see the module docs for which files and how they are
/// used) into the marks of every frame analysed.
pub fn marks_from_run_dir(dir: &Path) -> Result<RunMarks, OverlayError> {
    let mut warnings = Vec::new();
    let fps = read_fps(&dir.join("run.json"))?;
    let filtered = dir.join("keypoints_filtered.csv");
    let raw = dir.join("keypoints.csv");
    let kp = if filtered.is_file() {
        filtered
    } else if raw.is_file() {
        warnings
            .push("no keypoints_filtered.csv: the overlay shows the raw keypoints.csv".to_string());
        raw
    } else {
        return Err(OverlayError::run_file(
            &filtered,
            "missing (and so is keypoints.csv): no poses to draw",
        ));
    };
    let file =
        std::fs::File::open(&kp).map_err(OverlayError::io(format!("opening {}", kp.display())))?;
    let seq = gait_core::dlc::read(std::io::BufReader::new(file), None, fps)
        .map_err(|e| OverlayError::run_file(&kp, e))?;

    let optional = |name: &str, lacks: &str, warnings: &mut Vec<String>| {
        let p = dir.join(name);
        if p.is_file() {
            Some(p)
        } else {
            warnings.push(format!("no {name}: {lacks}"));
            None
        }
    };
    let events = match optional("events.csv", "no gait events are shown", &mut warnings) {
        Some(p) => read_events(&p)?,
        None => Vec::new(),
    };
    let bouts = match optional(
        "bouts.csv",
        "no frame is dimmed as outside a walking bout",
        &mut warnings,
    ) {
        Some(p) => Some(read_bouts(&p)?),
        None => None,
    };
    let cycles = match optional(
        "cycle_quality.csv",
        "no frame is dimmed as a rejected cycle",
        &mut warnings,
    ) {
        Some(p) => read_cycles(&p)?,
        None => Vec::new(),
    };
    Ok(RunMarks {
        fps,
        marks: plan_marks(&seq, &events, bouts.as_deref(), &cycles),
        names: seq.names,
        warnings,
    })
}

/// The input's frame rate from run.json (`input.fps`, or a top-level `fps`).
fn read_fps(path: &Path) -> Result<f64, OverlayError> {
    let text = std::fs::read_to_string(path)
        .map_err(OverlayError::io(format!("reading {}", path.display())))?;
    let v: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| OverlayError::run_file(path, e))?;
    v.pointer("/input/fps")
        .or_else(|| v.get("fps"))
        .and_then(serde_json::Value::as_f64)
        .filter(|f| f.is_finite() && *f > 0.0)
        .ok_or_else(|| OverlayError::run_file(path, "no positive `input.fps`"))
}

/// The cells of columns `need` (by header name) of every row of a CSV.
fn rows(path: &Path, need: &[&str]) -> Result<Vec<Vec<String>>, OverlayError> {
    let bad = |e: String| OverlayError::run_file(path, e);
    let mut r = csv::ReaderBuilder::new()
        .flexible(true)
        .from_path(path)
        .map_err(|e| bad(e.to_string()))?;
    let header = r.headers().map_err(|e| bad(e.to_string()))?.clone();
    let cols: Vec<usize> = need
        .iter()
        .map(|n| {
            header
                .iter()
                .position(|h| h.trim() == *n)
                .ok_or_else(|| bad(format!("no `{n}` column")))
        })
        .collect::<Result<_, _>>()?;
    let mut out = Vec::new();
    for rec in r.records() {
        let rec = rec.map_err(|e| bad(e.to_string()))?;
        out.push(
            cols.iter()
                .map(|&c| rec.get(c).unwrap_or("").trim().to_string())
                .collect(),
        );
    }
    Ok(out)
}

fn cell_err(path: &Path, row: usize, what: &str, v: &str) -> OverlayError {
    OverlayError::run_file(path, format!("row {}: `{v}` is not {what}", row + 2))
}

fn frame_of(path: &Path, row: usize, v: &str) -> Result<usize, OverlayError> {
    v.parse()
        .map_err(|_| cell_err(path, row, "a frame number", v))
}

fn side_of(path: &Path, row: usize, v: &str) -> Result<Side, OverlayError> {
    match v {
        "left" => Ok(Side::Left),
        "right" => Ok(Side::Right),
        _ => Err(cell_err(path, row, "a side (left or right)", v)),
    }
}

/// `events.csv`: `side,event,frame,time_s`.
pub(crate) fn read_events(path: &Path) -> Result<Vec<EventAt>, OverlayError> {
    rows(path, &["side", "event", "frame"])?
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let kind = match r[1].as_str() {
                "heel_strike" => EventKind::HeelStrike,
                "toe_off" => EventKind::ToeOff,
                v => return Err(cell_err(path, i, "heel_strike or toe_off", v)),
            };
            Ok(EventAt {
                side: side_of(path, i, &r[0])?,
                kind,
                frame: frame_of(path, i, &r[2])?,
            })
        })
        .collect()
}

/// `bouts.csv`: inclusive `first`..`last` input frames.
pub(crate) fn read_bouts(path: &Path) -> Result<Vec<[usize; 2]>, OverlayError> {
    rows(path, &["first", "last"])?
        .iter()
        .enumerate()
        .map(|(i, r)| Ok([frame_of(path, i, &r[0])?, frame_of(path, i, &r[1])?]))
        .collect()
}

/// `cycle_quality.csv`: side, inclusive frames, verdict, `;`-separated reasons.
pub(crate) fn read_cycles(path: &Path) -> Result<Vec<CycleSpan>, OverlayError> {
    rows(
        path,
        &["side", "first_frame", "last_frame", "accepted", "reasons"],
    )?
    .iter()
    .enumerate()
    .map(|(i, r)| {
        let accepted = match r[3].as_str() {
            "true" => true,
            "false" => false,
            v => return Err(cell_err(path, i, "true or false", v)),
        };
        Ok(CycleSpan {
            side: side_of(path, i, &r[0])?,
            first: frame_of(path, i, &r[1])?,
            last: frame_of(path, i, &r[2])?,
            accepted,
            reasons: r[4]
                .split(';')
                .map(str::trim)
                .filter(|s| !s.is_empty())
                .map(str::to_string)
                .collect(),
        })
    })
    .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows of frames 58-60, 79-81 and 186-187 and the heel and toe columns
    /// of runs/sample/keypoints_filtered.csv (frame 58: nobody found).
    const KEYPOINTS: &str = "\
scorer,gait-kin,gait-kin,gait-kin,gait-kin,gait-kin,gait-kin,gait-kin,gait-kin,gait-kin,gait-kin,gait-kin,gait-kin
bodyparts,left_heel,left_heel,left_heel,right_heel,right_heel,right_heel,left_toe,left_toe,left_toe,right_toe,right_toe,right_toe
coords,x,y,likelihood,x,y,likelihood,x,y,likelihood,x,y,likelihood
58,,,,,,,,,,,,
59,1495.4185110679905,927.2781445910964,0.9359469413757324,1332.565112536572,917.706038645415,0.9521440267562866,1479.4951198318292,938.6228339077323,0.9919481873512268,1284.5702085329604,904.601449943816,0.9821071028709412
60,1495.2560974209805,927.8602075935032,0.9278525114059448,1327.5649217569999,920.1475823337394,0.9715979695320129,1471.2280015936303,936.9107022726167,0.995419979095459,1280.1560458541023,907.7511077534094,0.9931892156600952
79,1153.898405928291,919.0310811714853,0.9773393273353577,1306.5763242070068,919.9960503413712,0.8931311964988708,1111.3718329301237,908.0611476026394,0.9821345806121826,1278.314979051825,947.0696027356365,0.8688372373580933
80,1153.8742476975033,918.8556547328278,0.9245812296867371,1293.8793274422167,914.4705853547786,0.9679291248321533,1111.2869681973873,914.0153237238585,0.9439247250556946,1269.2274670251727,946.1099329682411,0.990709662437439
81,1155.2292264619846,919.0640632785327,0.9847602248191833,1290.5976559576648,909.6854451766352,0.9089692234992981,1111.8660412285979,919.9200805015876,0.9947485327720642,1269.5847771838842,940.5497953250336,0.9389868378639221
186,75.10058667420907,936.5149824144504,0.9912654757499695,207.18102980370261,938.1958730942579,0.9195175766944885,19.33450157357025,934.3546366789797,0.9868501424789429,174.044766276567,936.8700195253314,0.8907976746559143
187,42.71298497114759,938.418757126,0.9932430386543274,207.59705006193283,935.4402801996373,0.9485405683517456,-1.1830816395299806,934.7010174016522,0.9861149787902832,175.89941597254366,937.2209358838563,0.9115976095199585
";

    /// runs/sample/events.csv, first five rows.
    const EVENTS: &str = "side,event,frame,time_s
left,toe_off,65,2.166667
left,heel_strike,79,2.633333
right,toe_off,85,2.833333
right,heel_strike,99,3.300000
left,toe_off,102,3.400000
";

    /// runs/sample/bouts.csv.
    const BOUTS: &str = "bout,first,last,direction,mean_speed\n0,59,186,left,1.543504\n";

    /// runs/sample/cycle_quality.csv, its first and last rows, plus a made-up
    /// rejected left stride from 152 to 187 (the sample rejected none).
    const CYCLES: &str = "side,first_frame,last_frame,accepted,reasons,stride_s,stride_deviation,max_filled_s,mean_likelihood,thigh_ratio,shank_ratio,swapped_frames,bout
left,79,117,true,,1.266667,0.055556,0.033333,0.989234,0.976651,0.986033,2,0
right,134,171,true,,1.233333,0.027778,0.066667,0.925431,1.022356,1.022607,2,0
left,152,187,false,stride_time;bout,1.166667,0.3,0.033333,0.99,1.0,1.0,0,
";

    fn run_dir(files: &[(&str, &str)]) -> tempfile::TempDir {
        let d = tempfile::tempdir().unwrap();
        for (name, text) in files {
            std::fs::write(d.path().join(name), text).unwrap();
        }
        d
    }

    fn by_frame(m: &RunMarks, f: usize) -> &FrameMarks {
        m.marks.iter().find(|x| x.frame == f).unwrap()
    }

    #[test]
    fn sample_run_outputs_become_marks() {
        let d = run_dir(&[
            ("run.json", r#"{"input": {"fps": 30.0}}"#),
            ("keypoints_filtered.csv", KEYPOINTS),
            ("events.csv", EVENTS),
            ("bouts.csv", BOUTS),
            ("cycle_quality.csv", CYCLES),
        ]);
        let m = marks_from_run_dir(d.path()).unwrap();
        assert!(m.warnings.is_empty(), "{:?}", m.warnings);
        assert_eq!(m.names[0], "left_heel");
        assert_eq!(m.marks.len(), 8);
        let f58 = by_frame(&m, 58);
        assert!(f58.pose.is_none());
        assert_eq!(f58.dim.as_deref(), Some("outside walking bout"));
        let f59 = by_frame(&m, 59);
        assert!(f59.pose.is_some() && f59.dim.is_none() && f59.events.is_empty());
        assert!((by_frame(&m, 60).time_s - 2.0).abs() < 1e-12);
        let hs = EventMark {
            side: Side::Left,
            kind: EventKind::HeelStrike,
            age_frames: 0,
        };
        assert_eq!(by_frame(&m, 79).events, vec![hs]);
        assert_eq!(by_frame(&m, 81).events[0].age_frames, 2);
        assert_eq!(
            by_frame(&m, 186).dim.as_deref(),
            Some("rejected cycle (left: stride time, bout)")
        );
        assert_eq!(
            by_frame(&m, 187).dim.as_deref(),
            Some("outside walking bout")
        );
    }

    #[test]
    fn labels_last_a_third_of_a_second() {
        let seq = PoseSequence {
            fps: 30.0,
            names: vec![],
            frames: (0..20).collect(),
            poses: vec![gait_core::Pose::empty(0); 20],
        };
        let ev = [EventAt {
            side: Side::Right,
            kind: EventKind::ToeOff,
            frame: 5,
        }];
        let m = plan_marks(&seq, &ev, None, &[]);
        let shown: Vec<usize> = m
            .iter()
            .filter(|f| !f.events.is_empty())
            .map(|f| f.frame)
            .collect();
        assert_eq!(shown, (5..14).collect::<Vec<_>>());
        assert!(
            m.iter().all(|f| f.dim.is_none()),
            "no bouts known: nothing dimmed"
        );
        let m = plan_marks(&seq, &ev, Some(&[]), &[]);
        assert!(
            m.iter().all(|f| f.dim.is_some()),
            "no bout found: all dimmed"
        );
    }

    #[test]
    fn missing_outputs_are_warned_about() {
        let d = run_dir(&[("run.json", r#"{"fps": 25}"#), ("keypoints.csv", KEYPOINTS)]);
        let m = marks_from_run_dir(d.path()).unwrap();
        assert_eq!(m.fps, 25.0);
        assert_eq!(m.warnings.len(), 4, "{:?}", m.warnings);
        assert!(m.warnings[0].contains("raw keypoints.csv"));
        assert!(
            m.marks
                .iter()
                .all(|f| f.dim.is_none() && f.events.is_empty())
        );
    }

    #[test]
    fn bad_outputs_are_named() {
        let d = run_dir(&[("keypoints.csv", KEYPOINTS)]);
        let e = marks_from_run_dir(d.path()).unwrap_err().to_string();
        assert!(e.contains("run.json"), "{e}");
        let d = run_dir(&[
            ("run.json", r#"{"input": {"fps": 30}}"#),
            ("keypoints_filtered.csv", KEYPOINTS),
            ("events.csv", "side,event,frame\nmiddle,heel_strike,3\n"),
        ]);
        let e = marks_from_run_dir(d.path()).unwrap_err().to_string();
        assert!(
            e.contains("events.csv") && e.contains("row 2") && e.contains("middle"),
            "{e}"
        );
        let d = run_dir(&[
            ("run.json", r#"{"input": {"fps": 30}}"#),
            ("keypoints_filtered.csv", KEYPOINTS),
            ("bouts.csv", "bout,start\n0,1\n"),
        ]);
        let e = marks_from_run_dir(d.path()).unwrap_err().to_string();
        assert!(e.contains("no `first` column"), "{e}");
        let d = run_dir(&[("run.json", "{}")]);
        assert!(marks_from_run_dir(d.path()).is_err());
    }
}
