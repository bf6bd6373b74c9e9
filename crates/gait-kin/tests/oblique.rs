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

/// Rows of a fixture CSV as (side, frame, value in cm) from columns `frame` and `value`.
fn reference(file: &Path, frame: usize, value: usize) -> Vec<(String, usize, f64)> {
    let text = std::fs::read_to_string(file).expect("reference csv");
    text.lines()
        .skip(1)
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            (
                c[0].to_string(),
                c[frame].parse().unwrap(),
                c[value].parse().unwrap(),
            )
        })
        .collect()
}

/// A camera looking along the walk from 1 m beside its line (the Parkinson's walk toward it):
/// step widths within 2 cm and circumduction within 2.5 cm of the 3-D truth (tests/data/frontal,
/// the same trial). Measured at the pelvis' depth, as before, its circumduction read 5.2 and
/// 6.8 cm against 1.0 and 1.2.
#[test]
fn a_camera_beside_the_walking_line_keeps_the_feet_measures() {
    let dir = data("oblique").join("gaitkit_pd_000_beside1000");
    let f = std::fs::File::open(dir.join("keypoints.csv")).expect("keypoints.csv");
    let seq = gait_core::dlc::read(f, None, 150.0).expect("DeepLabCut CSV");
    let leg_cm = 89.95;
    let kin = KinematicsConfig {
        frame_size: Some([1920, 1080]),
        subject_height_m: Some(leg_cm / 100.0 / gait_kin::spatiotemporal::LEG_PER_HEIGHT),
        ..KinematicsConfig::default()
    };
    let r = analyse(&seq, &PostprocessConfig::default(), &kin).expect("analysis");
    let feet = &r.frontal.as_ref().expect("a front view").feet;
    let truth = data("frontal").join("gaitkit_pd_anterior");
    // Step widths at heel strikes within 5 frames of the annotated ones (the Parkinson's walker's
    // left annotations lie 7-11 frames before the heel's contact: tests/data/frontal).
    for (measure, file, frame, value, window, limit) in [
        ("step_width", "steps.csv", 1, 2, 5, 2.0),
        ("circumduction", "circumduction.csv", 1, 3, 15, 2.5),
    ] {
        let want = reference(&truth.join(file), frame, value);
        let mut compared = 0;
        for got in feet.iter().filter(|l| l.measure == measure) {
            let Some(w) = want
                .iter()
                .find(|w| w.0 == got.side.name() && w.1.abs_diff(got.first_frame) <= window)
            else {
                continue;
            };
            println!(
                "{measure} {} {}: {:.2} cm against {:.2}",
                w.0, w.1, got.value, w.2
            );
            assert!(
                (got.value - w.2).abs() <= limit,
                "{measure}: {got:?} against {w:?}"
            );
            compared += 1;
        }
        assert!(compared >= 3, "{measure}: {compared} compared");
    }
}
