//! Scores and report of `gait kin` on committed motion-capture trials: the
//! healthy trial scores like a healthy walker against the normative set and
//! the Parkinson's trial higher; bad normative files; a run without cycles.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{fails_with, gait, run_ok};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// `gait kin` at 150 Hz on `keypoints`, with the report but no PDF.
fn kin_cmd(keypoints: &Path, out: &Path, sets: &[&str]) -> Command {
    let mut cmd = gait();
    cmd.args(["kin", "--fps", "150", "--keypoints"])
        .arg(keypoints)
        .arg("--out")
        .arg(out)
        .args(["--set", "report.pdf=false"]);
    for s in sets {
        cmd.args(["--set", s]);
    }
    cmd
}

fn trial(name: &str) -> PathBuf {
    repo().join(format!("tests/data/{name}/keypoints.csv"))
}

fn overall_gps(dir: &Path) -> f64 {
    let scores = std::fs::read_to_string(dir.join("scores.csv")).unwrap();
    let line = scores
        .lines()
        .find(|l| l.starts_with("gps_sagittal,both,"))
        .expect("an overall GPS");
    line.split(',').nth(3).unwrap().parse().unwrap()
}

#[test]
fn healthy_trial_scores_like_a_healthy_walker_and_parkinsons_higher() {
    let work = tempfile::tempdir().unwrap();
    let (healthy, pd) = (work.path().join("healthy"), work.path().join("pd"));
    // One stride a side is enough for a curve here.
    let one = ["kinematics.min_cycles=1"];
    run_ok(&mut kin_cmd(&trial("fukuchi2018"), &healthy, &one));
    run_ok(&mut kin_cmd(&trial("gaitkit_pd"), &pd, &one));
    let (h, p) = (overall_gps(&healthy), overall_gps(&pd));
    // A healthy walker one between-subject SD off the Schwartz 2008 free-speed
    // mean everywhere scores the RMS of the norm's SDs: 6.0 degrees
    // (gait_eval::Normative::expected_gps; README of data/normative).
    let expected = gait_eval::Normative::load("schwartz2008_free")
        .unwrap()
        .expected_gps()
        .unwrap();
    assert!((5.5..6.5).contains(&expected), "{expected}");
    assert!(
        h < expected,
        "healthy sagittal GPS {h:.2} within the healthy expectation {expected:.2}"
    );
    assert!(p > h, "Parkinson's {p:.2} above healthy {h:.2}");
}

#[test]
fn bad_normative_files_are_one_line_errors_naming_the_file_and_header() {
    let work = tempfile::tempdir().unwrap();
    let out = work.path().join("out");
    let missing = work.path().join("lab-missing.csv");
    let set = format!("report.normative={:?}", missing.display().to_string());
    fails_with(
        &mut kin_cmd(&trial("fukuchi2018"), &out, &[&set]),
        &["lab-missing.csv", "joint,percent,mean,sd"],
    );
    let wrong = work.path().join("lab-wrong.csv");
    std::fs::write(&wrong, "joint,pct,mean,sd\nhip,0,1,1\n").unwrap();
    let set = format!("report.normative={:?}", wrong.display().to_string());
    let mut cmd = gait();
    cmd.args(["kin", "--fps", "150", "--keypoints"])
        .arg(repo().join("tests/data/fukuchi2018/keypoints.csv"))
        .arg("--out")
        .arg(&out)
        .args(["--set", &set]);
    fails_with(
        &mut cmd,
        &["lab-wrong.csv", "expected `joint,percent,mean,sd`"],
    );
    assert!(
        !out.join("report.html").exists(),
        "nothing written before the config is checked"
    );
}

#[test]
fn a_run_without_an_accepted_cycle_still_gets_a_report_that_says_why() {
    let work = tempfile::tempdir().unwrap();
    // The first 60 frames (0.4 s) of the healthy trial: no complete stride.
    let text = std::fs::read_to_string(trial("fukuchi2018")).unwrap();
    let short: Vec<&str> = text.lines().take(3 + 60).collect();
    let csv = work.path().join("short.csv");
    std::fs::write(&csv, short.join("\n") + "\n").unwrap();
    let out = work.path().join("out");
    run_ok(&mut kin_cmd(&csv, &out, &[]));
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(
        html.contains("class=\"no-cycles\">No accepted gait cycle to show:"),
        "says why"
    );
    assert!(!html.contains("id=\"fig-gait_graphs\""));
}
