//! Inputs with no usable gait: clear empty results plus warnings, never a panic.

use gait_core::{CANONICAL, Keypoint, Pose, PoseSequence};
use gait_kin::{KinError, KinematicsConfig, PostprocessConfig, analyse, write_outputs};

fn names() -> Vec<String> {
    CANONICAL.iter().map(|s| s.to_string()).collect()
}

/// A sequence from a per-frame function giving (x, y) per canonical name (None = missing).
fn make(n: usize, fps: f64, f: impl Fn(usize, &str) -> Option<(f64, f64)>) -> PoseSequence {
    let names = names();
    PoseSequence {
        fps,
        frames: (0..n).collect(),
        poses: (0..n)
            .map(|i| Pose {
                keypoints: names
                    .iter()
                    .map(|k| match f(i, k) {
                        Some((x, y)) => Keypoint::new(x, y, 0.9),
                        None => Keypoint::missing(),
                    })
                    .collect(),
            })
            .collect(),
        names,
    }
}

/// A side-view standing pose (walking direction: right), offset by `dx`.
fn side_pose(name: &str, dx: f64) -> Option<(f64, f64)> {
    let p = match name {
        "neck" => (300.0, 100.0),
        "mid_hip" | "left_hip" | "right_hip" => (300.0, 300.0),
        "left_knee" | "right_knee" => (305.0, 450.0),
        "left_ankle" | "right_ankle" => (300.0, 600.0),
        "left_heel" | "right_heel" => (290.0, 615.0),
        "left_toe" | "right_toe" => (350.0, 620.0),
        _ => return None,
    };
    Some((p.0 + dx, p.1))
}

fn check_no_cycles(seq: &PoseSequence, must_warn: &str) -> gait_kin::KinResult {
    let r = analyse(
        seq,
        &PostprocessConfig::default(),
        &KinematicsConfig::default(),
    )
    .expect("analyse");
    assert!(r.cycles.is_empty(), "{:?}", r.cycles);
    assert!(
        r.warnings.iter().any(|w| w.contains(must_warn)),
        "no `{must_warn}` in {:?}",
        r.warnings
    );
    let dir = tempfile::tempdir().unwrap();
    write_outputs(&r, dir.path()).expect("write");
    let cycles = std::fs::read_to_string(dir.path().join("cycles.csv")).unwrap();
    assert_eq!(cycles, "side,joint,percent,mean,sd,n_cycles\n");
    r
}

#[test]
fn real_trial_has_fewer_than_two_cycles_per_side() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../tests/data/fukuchi2018/keypoints.csv"
    );
    let seq = gait_core::dlc::read(std::fs::File::open(path).unwrap(), None, 150.0).unwrap();
    let r = check_no_cycles(
        &seq,
        "fewer than 2 complete cycles for the left hip, knee, ankle (1 found); right hip, knee, ankle (1 found): no mean curve",
    );
    let short = r.warnings.iter().filter(|w| w.contains("complete cycles"));
    assert_eq!(
        short.count(),
        1,
        "one line for all joints: {:?}",
        r.warnings
    );
    assert_eq!(r.strides.len(), 2);
}

#[test]
fn standing_still() {
    let seq = make(90, 30.0, |i, k| side_pose(k, 0.3 * (i as f64 * 0.7).sin()));
    let r = check_no_cycles(&seq, "no heel strike found for the left leg");
    assert!(r.events.is_empty());
    assert!(r.bouts.is_empty() && r.cycle_quality.is_empty());
    assert!(
        r.warnings
            .iter()
            .any(|w| w == "no walking bout found: no events or cycles")
    );
    // Standing straight: the direction comes from the feet, the angles are defined and small.
    assert_eq!(r.direction_counts[2], 0);
    assert!(
        r.angles.left.knee.iter().all(|k| k.abs() < 10.0),
        "{:?}",
        &r.angles.left.knee[..3]
    );
}

#[test]
fn all_keypoints_missing() {
    let seq = make(60, 30.0, |_, _| None);
    let r = check_no_cycles(&seq, "walking direction unknown in every frame");
    assert!(r.angles.left.hip.iter().all(|v| v.is_nan()));
    let low = make(60, 30.0, |_, k| side_pose(k, 0.0));
    let mut low = low;
    for p in &mut low.poses {
        for k in &mut p.keypoints {
            k.likelihood = 0.2;
        }
    }
    check_no_cycles(&low, "walking direction unknown in every frame");
}

#[test]
fn nan_and_garbage_values() {
    let mut seq = make(120, 30.0, |i, k| side_pose(k, 4.0 * i as f64));
    for (i, p) in seq.poses.iter_mut().enumerate() {
        for (j, k) in p.keypoints.iter_mut().enumerate() {
            match (i + j) % 7 {
                0 => k.x = f64::NAN,
                1 => k.likelihood = f64::NAN,
                2 => k.y = f64::INFINITY,
                _ => {}
            }
        }
    }
    check_no_cycles(&seq, "no heel strike");
    let text = "scorer,s,s,s\nbodyparts,left_knee,left_knee,left_knee\ncoords,x,y,likelihood\n0,NaN,NaN,NaN\n1,,,\n2,3,4,nan\n";
    let seq = gait_core::dlc::read(text.as_bytes(), None, 30.0).unwrap();
    check_no_cycles(&seq, "no heel strike");
    let empty = make(0, 30.0, |_, _| None);
    check_no_cycles(&empty, "no frames");
}

#[test]
fn walking_toward_the_camera() {
    // Front view: hips a pelvis-width apart, the figure growing as the person approaches, feet
    // pointing at the camera; steps alternate in depth only.
    let seq = make(150, 30.0, |i, k| {
        let s = 1.0 + i as f64 / 150.0;
        let phase = (i as f64 * 2.0 * std::f64::consts::PI / 30.0).sin();
        let (side, lift) = if k.starts_with("left") {
            (-1.0, phase)
        } else {
            (1.0, -phase)
        };
        let lift = 15.0 * lift.max(0.0);
        let (x, y) = match k.split_once('_').map_or(k, |(_, part)| part) {
            "hip" => (60.0, 300.0),
            "knee" => (55.0, 450.0 - lift),
            "ankle" => (50.0, 600.0 - lift),
            "heel" => (50.0, 612.0 - lift),
            "toe" => (50.0, 625.0 - lift),
            "neck" | "hip_mid" => (0.0, 100.0),
            _ => return None,
        };
        let x = if k == "neck" || k == "mid_hip" {
            0.0
        } else {
            side * x
        };
        Some((400.0 + s * x, 100.0 + s * y))
    });
    // A front view is analysed as one (issue 38): decided from the keypoints (hips apart,
    // growing), its labels put on the sides a walker facing the camera has (its left on the
    // image right: this figure's are the other way round in every frame), no sagittal curves.
    let r = analyse(
        &seq,
        &PostprocessConfig::default(),
        &KinematicsConfig::default(),
    )
    .expect("analyse");
    assert_eq!(r.view.view, gait_kin::View::Anterior, "{}", r.view.how);
    assert!(r.frontal.is_some() && r.cycles.is_empty());
    assert_eq!(r.swapped_frames, 150, "{:?}", r.warnings);
    let dir = tempfile::tempdir().unwrap();
    write_outputs(&r, dir.path()).expect("write");
    assert!(dir.path().join("frontal_angles.csv").is_file());
}

#[test]
fn bad_settings_are_errors_not_panics() {
    let seq = make(10, 0.0, |_, k| side_pose(k, 0.0));
    assert!(matches!(
        analyse(
            &seq,
            &PostprocessConfig::default(),
            &KinematicsConfig::default()
        ),
        Err(KinError::BadInput(_))
    ));
    let seq = make(10, 10.0, |_, k| side_pose(k, 0.0));
    let e = analyse(
        &seq,
        &PostprocessConfig::default(),
        &KinematicsConfig::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("cutoff_hz"), "{e}");
    let kin = KinematicsConfig {
        events_csv: Some("/nonexistent/events.csv".into()),
        ..Default::default()
    };
    let seq = make(10, 30.0, |_, k| side_pose(k, 0.0));
    let e = analyse(&seq, &PostprocessConfig::default(), &kin).unwrap_err();
    assert!(e.to_string().contains("/nonexistent/events.csv"), "{e}");
}

#[test]
fn a_model_without_feet_has_no_ankle_angle_and_says_so() {
    // A walker seen from the side whose pose model has no heels or toes
    // (OpenPose COCO-18): hips and knees swing, the ankle cannot be measured.
    let seq = make(120, 30.0, |i, name| {
        if name.ends_with("_heel") || name.ends_with("_toe") {
            return None;
        }
        let phase = i as f64 / 30.0 * std::f64::consts::TAU;
        let swing = if name.starts_with("left") { 1.0 } else { -1.0 } * 40.0 * phase.sin();
        let (x, y) = side_pose(name, 3.0 * i as f64)?;
        Some(match name {
            n if n.ends_with("_knee") || n.ends_with("_ankle") => (x + swing, y),
            _ => (x, y),
        })
    });
    let r = analyse(
        &seq,
        &PostprocessConfig::default(),
        &KinematicsConfig::default(),
    )
    .expect("analyse");
    for side in ["left", "right"] {
        assert!(
            r.warnings
                .iter()
                .any(|w| w.contains(&format!("{side} ankle angle is unavailable"))),
            "{:?}",
            r.warnings
        );
    }
    assert!(r.angles.left.ankle.iter().all(|a| a.is_nan()));
    assert!(r.angles.right.ankle.iter().all(|a| a.is_nan()));
    assert!(r.angles.left.hip.iter().filter(|a| a.is_finite()).count() > 100);
}
