//! Corrections through the command: `gait kin --corrections FILE`, and
//! `gait run` picking up the run folder's corrections.toml on a rerun; both
//! record the file (sha256) in what they write, and a bad file is one line.

mod common;

use std::path::{Path, PathBuf};

use common::{fails_with, gait, read_json, run_ok};

fn sample_keypoints() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/sample-subject/keypoints.csv")
}

fn events(dir: &Path) -> Vec<String> {
    std::fs::read_to_string(dir.join("events.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').take(3).collect::<Vec<_>>().join(","))
        .collect()
}

fn kin(out: &Path, corrections: Option<&Path>) -> std::process::Command {
    let mut cmd = gait();
    cmd.args(["kin", "--fps", "30", "--keypoints"])
        .arg(sample_keypoints())
        .arg("--out")
        .arg(out)
        .args([
            "--set",
            "report.pdf=false",
            "--set",
            "kinematics.frame_size=[1768, 994]",
        ]);
    if let Some(c) = corrections {
        cmd.arg("--corrections").arg(c);
    }
    cmd
}

/// Adds the right heel strike at frame 60 that the manual annotation has and the detector misses.
const ADD_EVENT: &str =
    "[[event]]\nside = \"right\"\nkind = \"heel_strike\"\nframe = 60\naction = \"add\"\n";

#[test]
fn gait_kin_applies_a_corrections_file() {
    let work = tempfile::tempdir().unwrap();
    let (plain, fixed) = (work.path().join("plain"), work.path().join("fixed"));
    let file = work.path().join("corrections.toml");
    std::fs::write(&file, ADD_EVENT).unwrap();
    run_ok(&mut kin(&plain, None));
    let out = run_ok(&mut kin(&fixed, Some(&file)));
    let mut want = events(&plain);
    want.push("right,heel_strike,60".into());
    want.sort_by_key(|e| e.rsplit(',').next().unwrap().parse::<usize>().unwrap());
    assert_eq!(events(&fixed), want);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("corrections applied from") && err.contains("1 event added"),
        "{err}"
    );
}

#[test]
fn bad_corrections_are_one_line_errors_naming_the_entry() {
    let work = tempfile::tempdir().unwrap();
    let file = work.path().join("corrections.toml");
    std::fs::write(
        &file,
        "[[swap]]\nfirst = 120\nlast = 131\n[[swap]]\nfirst = 125\nlast = 140\n",
    )
    .unwrap();
    fails_with(
        &mut kin(&work.path().join("a"), Some(&file)),
        &["[[swap]] #2", "overlaps [[swap]] #1"],
    );
    std::fs::write(
        &file,
        "[[keypoint]]\nframe = 140\nname = \"right_elbow\"\nx = 1.0\ny = 2.0\n",
    )
    .unwrap();
    fails_with(
        &mut kin(&work.path().join("b"), Some(&file)),
        &["[[keypoint]] #1", "right_elbow"],
    );
    std::fs::write(&file, "[[swop]]\nfirst = 1\nlast = 2\n").unwrap();
    fails_with(
        &mut kin(&work.path().join("c"), Some(&file)),
        &["corrections.toml", "swop"],
    );
    std::fs::write(&file, "[[exclude]]\nfirst = 100\nlast = 900\n").unwrap();
    fails_with(
        &mut kin(&work.path().join("d"), Some(&file)),
        &["[[exclude]] #1", "outside the run"],
    );
}

/// Moves the right toe-off the detector places at 121 to 123, where the manual annotation has it.
const MOVE_TOE_OFF: &str = "[[event]]\nside = \"right\"\nkind = \"toe_off\"\nframe = 121\naction = \"remove\"\n\
     [[event]]\nside = \"right\"\nkind = \"toe_off\"\nframe = 123\naction = \"add\"\n";

#[test]
fn gait_run_applies_the_run_folders_corrections_on_a_rerun() {
    let work = tempfile::tempdir().unwrap();
    let out = work.path().join("run");
    run_ok(&mut common::sample_run(&out, 40, 200));
    let before = events(&out);
    let (found, annotated) = (
        "right,toe_off,121".to_string(),
        "right,toe_off,123".to_string(),
    );
    assert!(
        before.contains(&found) && !before.contains(&annotated),
        "{before:?}"
    );
    std::fs::write(out.join("corrections.toml"), MOVE_TOE_OFF).unwrap();
    // The poses come from the run's cache; only the kinematics change.
    run_ok(&mut common::sample_run(&out, 40, 200));
    let after = events(&out);
    assert!(
        after.contains(&annotated) && !after.contains(&found),
        "{after:?}"
    );
    let m = read_json(&out.join("run.json"));
    let c = &m["extra"]["kinematics"]["corrections"];
    assert_eq!(
        (&c["events_added"], &c["events_removed"]),
        (&1.into(), &1.into())
    );
    assert_eq!(c["sha256"].as_str().unwrap().len(), 64);
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(
        html.contains("Corrections applied ("),
        "the report lists them"
    );
}
