//! A camera that follows the walker (a phone in the hand) or a treadmill: the ground moves in
//! the image. The sample's real keypoints (tests/data/sample-subject) are shifted frame by frame
//! as a camera panning after her would shift them, and the stride lengths, which a heel's
//! image travel between its strikes gave as 14 and 79 px (symmetry index -138 %), come from
//! the steps instead (ground.rs).

use std::path::PathBuf;

use gait_core::PoseSequence;
use gait_kin::{KinResult, KinematicsConfig, PostprocessConfig, analyse};

fn sequence() -> PoseSequence {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data/sample-subject/keypoints.csv");
    let f = std::fs::File::open(path).expect("keypoints.csv");
    gait_core::dlc::read(f, None, 30.0).expect("DeepLabCut CSV")
}

/// The camera's pan at input frame `n`: it follows her hips (about 10 px a frame, right to left)
/// between frames 70 and 157 and stands before and after, as a 900 px wide crop of the video
/// that keeps her centred would (the robustness session's `pan.mp4`).
fn pan(n: usize) -> f64 {
    (2025.7 - 10.047 * n as f64 - 450.0).clamp(0.0, 868.0)
}

fn panned(mut seq: PoseSequence) -> PoseSequence {
    for (pose, &n) in seq.poses.iter_mut().zip(&seq.frames) {
        for k in &mut pose.keypoints {
            k.x -= pan(n);
        }
    }
    seq
}

fn analysed(seq: &PoseSequence) -> KinResult {
    let kin = KinematicsConfig {
        frame_size: Some([1768, 994]),
        ..Default::default()
    };
    analyse(seq, &PostprocessConfig::default(), &kin).expect("analysis")
}

fn param(r: &KinResult, name: &str, side: &str) -> f64 {
    r.spatiotemporal
        .iter()
        .find(|p| p.parameter == name && p.side == side)
        .map_or(f64::NAN, |p| p.mean)
}

#[test]
fn a_camera_following_the_walker_keeps_the_stride_lengths() {
    let (fixed, moving) = (analysed(&sequence()), analysed(&panned(sequence())));
    let share = |r: &KinResult| r.ground.map_or(f64::NAN, |g| g.share());
    // On a tripod the planted ankle drifts by a few percent of the walking speed (it rolls).
    assert!(share(&fixed) < 0.15, "{:?}", fixed.ground);
    assert!(share(&moving) > 0.5, "{:?}", moving.ground);
    let warned = |r: &KinResult| r.warnings.iter().any(|w| w.contains("ground moves"));
    assert!(!warned(&fixed) && warned(&moving));
    // The events are taken against the pelvis and the walking speed, so the pan moves none by
    // more than a frame.
    assert_eq!(fixed.events.len(), moving.events.len());
    for (a, b) in fixed.events.iter().zip(&moving.events) {
        assert!(
            a.key().0 == b.key().0 && a.event == b.event && a.frame.abs_diff(b.frame) <= 1,
            "{a:?} {b:?}"
        );
    }
    for side in ["left", "right"] {
        for name in ["stride_length", "speed"] {
            let (a, b) = (param(&fixed, name, side), param(&moving, name, side));
            assert!(
                (b / a - 1.0).abs() < 0.05,
                "{side} {name}: {a:.1} on a tripod, {b:.1} panned"
            );
        }
    }
    let si = param(&moving, "symmetry_index_stride_length", "left_vs_right");
    assert!(si.abs() < 5.0, "{si}");
}
