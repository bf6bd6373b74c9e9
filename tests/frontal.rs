//! Front and back views from the command (issue 38): `gait kin` on a walk toward or away from
//! the camera (real motion capture projected through a pinhole camera, tests/data/frontal)
//! writes the frontal tables and the report's frontal section; a declared view the keypoints
//! disagree with is analysed as declared, with a warning that says why.

mod common;

use std::path::{Path, PathBuf};

use common::{gait, run_ok};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data")
        .join(name)
        .join("keypoints.csv")
}

fn kin(keypoints: &Path, fps: &str, out: &Path, sets: &[&str]) -> String {
    let mut cmd = gait();
    cmd.args(["kin", "--keypoints"])
        .arg(keypoints)
        .args(["--fps", fps, "--out"])
        .arg(out);
    for s in sets {
        cmd.args(["--set", s]);
    }
    let o = run_ok(&mut cmd);
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn a_walk_away_from_the_camera_gets_the_frontal_report() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("pd-posterior");
    kin(
        &fixture("frontal/gaitkit_pd_posterior"),
        "150",
        &out,
        &["kinematics.subject_height_m=1.83"],
    );
    for f in [
        "frontal_angles.csv",
        "frontal_cycles.csv",
        "frontal_scalars.csv",
        "frontal_feet.csv",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    let cycles = std::fs::read_to_string(out.join("frontal_cycles.csv")).unwrap();
    for m in [
        "trunk_lean",
        "pelvic_obliquity",
        "hip_adduction",
        "knee_varus",
    ] {
        assert!(cycles.contains(&format!("left,{m},")), "{m}");
        assert!(cycles.contains(&format!("right,{m},")), "{m}");
    }
    let feet = std::fs::read_to_string(out.join("frontal_feet.csv")).unwrap();
    assert!(
        feet.contains(",step_width,") && feet.contains(",cm"),
        "{feet}"
    );
    let quality = std::fs::read_to_string(out.join("cycle_quality.csv")).unwrap();
    assert!(
        quality
            .lines()
            .next()
            .unwrap()
            .ends_with(",frontal_missing")
    );
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    for needle in [
        "Frontal plane (posterior view)",
        "fig-frontal_graphs",
        "Pelvic obliquity",
        "Sign conventions of the frontal measures",
        "Step width and circumduction",
        "No sagittal angles: this is a posterior view",
    ] {
        assert!(html.contains(needle), "report lacks `{needle}`");
    }
}

#[test]
fn a_declared_view_the_keypoints_contradict_is_named() {
    let dir = tempfile::tempdir().unwrap();
    // A walk toward the camera declared as a side view ...
    let err = kin(
        &fixture("frontal/fukuchi2018_anterior"),
        "150",
        &dir.path().join("a"),
        &["kinematics.view=\"left\""],
    );
    assert!(
        err.contains("disagree with kinematics.view = \"left\"")
            && err.contains("front or back view"),
        "{err}"
    );
    // ... and the sample's side view declared as a walk toward the camera.
    let err = kin(
        &fixture("sample-blazepose"),
        "30",
        &dir.path().join("b"),
        &["kinematics.view=\"anterior\""],
    );
    assert!(
        err.contains("disagree with kinematics.view = \"anterior\"") && err.contains("side view"),
        "{err}"
    );
    assert!(dir.path().join("b/frontal_angles.csv").is_file());
}
