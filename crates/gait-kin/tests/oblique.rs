//! A walk filmed obliquely (tests/data/oblique, real motion capture projected through a camera
//! turned from the walking line by tools/frontal/oblique.py): its angle to the camera's axis is
//! estimated within a few degrees and a run beyond the tolerance is warned; walks straight
//! toward or away from the camera (tests/data/frontal) are not.

use std::path::{Path, PathBuf};

use gait_kin::{KinematicsConfig, PostprocessConfig, analyse};

fn data(dir: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data")
        .join(dir)
}

/// The estimated angle and the warnings of the keypoints in `dir`, seen in a 1920 x 1080 frame.
fn run(dir: &Path) -> (f64, Vec<String>) {
    let f = std::fs::File::open(dir.join("keypoints.csv")).expect("keypoints.csv");
    let seq = gait_core::dlc::read(f, None, 150.0).expect("DeepLabCut CSV");
    let kin = KinematicsConfig {
        frame_size: Some([1920, 1080]),
        ..KinematicsConfig::default()
    };
    let r = analyse(&seq, &PostprocessConfig::default(), &kin).expect("analysis");
    (r.view.walk_angle_deg, r.warnings)
}

#[test]
fn oblique_walks_are_measured_and_warned() {
    for case in ["gaitkit_pd_030", "gaitkit_pd_060", "fukuchi2018_160"] {
        let dir = data("oblique").join(case);
        let truth: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap())
                .unwrap();
        let want = truth["walk_angle_deg"].as_f64().unwrap();
        let (angle, warnings) = run(&dir);
        println!("{case}: walk angle {angle:.1} deg (true {want}); {warnings:?}");
        assert!(
            (angle - want).abs() <= 3.0,
            "{case}: {angle} against {want}"
        );
        assert!(
            warnings.iter().any(|w| w.contains("off the camera's axis")),
            "{case}: not warned: {warnings:?}"
        );
    }
}

#[test]
fn straight_walks_toward_or_away_are_not_warned() {
    for case in [
        "fukuchi2018_anterior",
        "fukuchi2018_posterior",
        "gaitkit_pd_anterior",
        "gaitkit_pd_posterior",
    ] {
        let (angle, warnings) = run(&data("frontal").join(case));
        println!("{case}: walk angle {angle:.1} deg");
        assert!(angle < 3.0, "{case}: {angle}");
        assert!(
            !warnings.iter().any(|w| w.contains("off the camera's axis")),
            "{case}: {warnings:?}"
        );
    }
}
