//! `keypoints.c3d`: the filtered keypoints as 2-D markers and the gait events
//! as Vicon writes them, through gait-c3d.

use std::path::Path;

use gait_core::PoseSequence;

use super::RunFacts;
use crate::EvalError;

/// One row of events.csv.
#[derive(Debug, Clone, PartialEq)]
pub struct RunEvent {
    pub left: bool,
    pub heel_strike: bool,
    pub frame: usize,
}

/// Reads a run's events.csv (`side,event,frame,time_s`).
pub fn read_events(path: &Path) -> Result<Vec<RunEvent>, EvalError> {
    let mut r = csv::Reader::from_path(path).map_err(|e| EvalError::input(path, e))?;
    let mut out = Vec::new();
    for (i, rec) in r.records().enumerate() {
        let rec = rec.map_err(|e| EvalError::input(path, e))?;
        let bad = |what: &str| EvalError::input(path, format!("line {}: {what}", i + 2));
        let left = match rec.get(0) {
            Some("left") => true,
            Some("right") => false,
            _ => return Err(bad("side must be left or right")),
        };
        let heel_strike = match rec.get(1) {
            Some("heel_strike") => true,
            Some("toe_off") => false,
            _ => return Err(bad("event must be heel_strike or toe_off")),
        };
        let frame = rec
            .get(2)
            .and_then(|f| f.parse().ok())
            .ok_or_else(|| bad("frame is not a frame number"))?;
        out.push(RunEvent {
            left,
            heel_strike,
            frame,
        });
    }
    Ok(out)
}

/// Markers X = x, Y = y (image coordinates; POINT:Y_SCREEN says -Y so a
/// viewer shows the image upright), Z = 0, in mm when the run has a scale,
/// else in pixels; frames numbered from input frame + 1;
/// event times input frame / fps, as events.csv gives them.
pub fn write(
    seq: &PoseSequence,
    events: &[RunEvent],
    facts: &RunFacts,
    path: &Path,
) -> Result<(), EvalError> {
    let (Some(&first), Some(&last)) = (seq.frames.iter().min(), seq.frames.iter().max()) else {
        return Err(EvalError::input(path, "no frames to export"));
    };
    let (scale, units) = match facts.px_per_cm {
        Some(p) if p.is_finite() && p > 0.0 => (10.0 / p, "mm"),
        _ => (1.0, "px"),
    };
    let n = last - first + 1;
    let markers = seq
        .names
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let mut xy = vec![None; n];
            for (f, pose) in seq.frames.iter().zip(&seq.poses) {
                xy[f - first] = pose
                    .keypoints
                    .get(k)
                    .filter(|p| p.is_found())
                    .map(|p| [p.x * scale, p.y * scale]);
            }
            gait_c3d::Marker {
                label: name.clone(),
                xy,
            }
        })
        .collect();
    let events = events
        .iter()
        .map(|e| gait_c3d::Event {
            context: if e.left {
                gait_c3d::Context::Left
            } else {
                gait_c3d::Context::Right
            },
            kind: if e.heel_strike {
                gait_c3d::EventKind::FootStrike
            } else {
                gait_c3d::EventKind::FootOff
            },
            time_s: e.frame as f64 / facts.fps,
        })
        .collect();
    let data = gait_c3d::C3dData {
        rate_hz: facts.fps,
        first_frame: first + 1,
        units: units.into(),
        markers,
        events,
    };
    gait_c3d::write(path, &data).map_err(|e| EvalError::input(path, e))
}
