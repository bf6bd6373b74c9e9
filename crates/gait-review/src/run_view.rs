//! What the page gets once: the keypoints as the pose stage gave them, the skeleton, and what
//! there is to show of the frames.

use gait_core::keypoint::{LEG_SEGMENTS, UPPER_SEGMENTS};
use serde::Serialize;
use serde_json::Value;

use crate::source::ReviewSource;

#[derive(Serialize)]
struct RunView<'a> {
    title: &'a str,
    fps: f64,
    names: &'a [String],
    /// Input frame number of each pose.
    frames: &'a [usize],
    /// Per keypoint: x, y and likelihood series (null where missing).
    keypoints: Vec<[Vec<f64>; 3]>,
    skeleton: Vec<[&'static str; 2]>,
    frame_size: Option<[u32; 2]>,
    /// Why the frames cannot be shown (null when they can).
    no_video: Option<&'a str>,
    /// Frames with a regenerated image.
    regenerated: Vec<usize>,
    subject: Option<&'a Value>,
    prosthetic_side: Option<gait_kin::Side>,
    corrections_path: String,
    rerun: &'a str,
}

/// The JSON of `GET /api/run`.
pub(crate) fn json(src: &ReviewSource, regenerated: Vec<usize>) -> String {
    let seq = &src.seq;
    let keypoints = (0..seq.names.len())
        .map(|j| {
            let series = |f: fn(&gait_core::Keypoint) -> f64| {
                seq.poses.iter().map(|p| f(&p.keypoints[j])).collect()
            };
            [series(|k| k.x), series(|k| k.y), series(|k| k.likelihood)]
        })
        .collect();
    let view = RunView {
        title: &src.title,
        fps: seq.fps,
        names: &seq.names,
        frames: &seq.frames,
        keypoints,
        skeleton: LEG_SEGMENTS
            .iter()
            .chain(UPPER_SEGMENTS.iter())
            .map(|&(a, b)| [a, b])
            .collect(),
        frame_size: src.frame_size,
        no_video: src.video.as_ref().err().map(String::as_str),
        regenerated,
        subject: src.subject.as_ref(),
        prosthetic_side: src.kin.prosthetic_side,
        corrections_path: src.corrections_path.display().to_string(),
        rerun: &src.rerun,
    };
    serde_json::to_string(&view).expect("plain data serialises")
}
