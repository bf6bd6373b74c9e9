//! `gait run` end to end on the bundled real walking video, with the default
//! pipeline and the real BlazePose model.

mod common;

use common::{read_json, run_ok};
use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

const NAMES: [&str; 15] = [
    "nose",
    "neck",
    "left_shoulder",
    "right_shoulder",
    "mid_hip",
    "left_hip",
    "right_hip",
    "left_knee",
    "right_knee",
    "left_ankle",
    "right_ankle",
    "left_heel",
    "right_heel",
    "left_toe",
    "right_toe",
];

fn run_args(out: &Path, first: usize, last: usize) -> std::process::Command {
    common::sample_run(out, first, last)
}

/// Data rows of keypoints.csv: (frame, values).
fn rows(csv: &Path) -> Vec<(usize, Vec<String>)> {
    let text = std::fs::read_to_string(csv).unwrap();
    text.lines()
        .skip(3)
        .map(|l| {
            let mut cells = l.split(',');
            let frame = cells.next().unwrap().parse().unwrap();
            (frame, cells.map(str::to_string).collect())
        })
        .collect()
}

#[test]
fn default_pipeline_on_the_sample_video() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    run_ok(&mut run_args(&out, 150, 157));

    let text = std::fs::read_to_string(out.join("keypoints.csv")).unwrap();
    let header: Vec<Vec<&str>> = text
        .lines()
        .take(3)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(header[0][0], "scorer");
    assert_eq!(header[1][0], "bodyparts");
    assert_eq!(header[2][0], "coords");
    for (i, name) in NAMES.iter().enumerate() {
        assert_eq!(header[1][1 + 3 * i], *name);
        assert_eq!(&header[2][1 + 3 * i..4 + 3 * i], ["x", "y", "likelihood"]);
    }
    let data = rows(&out.join("keypoints.csv"));
    assert_eq!(
        data.iter().map(|r| r.0).collect::<Vec<_>>(),
        (150..=157).collect::<Vec<_>>()
    );
    // The walker is in view: her knees and ankles are found inside the frame.
    for (frame, cells) in &data {
        for name in ["left_knee", "right_knee", "left_ankle", "right_ankle"] {
            let i = NAMES.iter().position(|n| *n == name).unwrap();
            let x: f64 = cells[3 * i]
                .parse()
                .unwrap_or_else(|_| panic!("frame {frame}: no {name}"));
            let y: f64 = cells[3 * i + 1].parse().unwrap();
            assert!(
                (0.0..1768.0).contains(&x) && (0.0..994.0).contains(&y),
                "frame {frame} {name} at {x},{y}"
            );
        }
    }

    let manifest = read_json(&out.join("run.json"));
    assert_eq!(manifest["frames_processed"], 8);
    assert_eq!(manifest["input"]["fps"], 30.0);
    assert_eq!(manifest["config"]["pose"]["kind"], "blazepose");
    assert!(
        manifest["models"]
            .as_array()
            .unwrap()
            .iter()
            .all(|m| m["sha256"].as_str().is_some_and(|s| s.len() == 64))
    );
    assert!(manifest["stages"]["pose"]["seconds"].as_f64().unwrap() > 0.0);

    // run.json repeats the run: same keypoints, all from the cache.
    let again = dir.path().join("again");
    run_ok(common::rerun(&out, &again).args([
        "--set",
        &format!("run.cache_dir={}", out.join("cache").display()),
    ]));
    assert_eq!(read_json(&again.join("run.json"))["frames_from_cache"], 8);
    assert_eq!(rows(&again.join("keypoints.csv")), data);
}

#[test]
fn interrupted_run_resumes_where_it_stopped() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let mut child = run_args(&out, 100, 139)
        .args(["--set", "run.batch_size=1"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Kill the run hard once a few frames are done.
    wait_for_poses(&out, &mut child, 5);
    child.kill().unwrap();
    child.wait().unwrap();
    let finished_before = cached_poses(&out);
    assert!(
        finished_before < 40,
        "the run finished before it was killed"
    );
    assert!(
        !out.join("keypoints.csv").exists(),
        "an interrupted run must not leave results"
    );

    run_ok(&mut run_args(&out, 100, 139));
    let manifest = read_json(&out.join("run.json"));
    assert_eq!(manifest["frames_processed"], 40);
    let from_cache = manifest["frames_from_cache"].as_u64().unwrap() as usize;
    assert!(
        from_cache >= 5 && from_cache >= finished_before - 1,
        "resumed with {from_cache} cached frames"
    );
    assert_eq!(
        manifest["stages"]["pose"]["computed"].as_u64().unwrap() as usize,
        40 - from_cache
    );

    // Same keypoints as an uninterrupted run without a cache.
    let clean = dir.path().join("clean");
    run_ok(run_args(&clean, 100, 139).args(["--set", "run.cache=false"]));
    let (a, b) = (
        rows(&out.join("keypoints.csv")),
        rows(&clean.join("keypoints.csv")),
    );
    // The tracker state is saved with every cached pose, so the resumed run
    // is identical to one that was never interrupted.
    assert_eq!(a, b);
}

/// Poses in the run's pose cache.
fn cached_poses(out: &Path) -> usize {
    std::fs::read_dir(out.join("cache"))
        .into_iter()
        .flatten()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with("pose-"))
        .flat_map(|e| std::fs::read_dir(e.path()).into_iter().flatten().flatten())
        .filter(|e| {
            e.file_name().to_string_lossy().ends_with(".json") && e.file_name() != "config.json"
        })
        .count()
}

/// Waits until `n` poses are cached, the run still going.
fn wait_for_poses(out: &Path, child: &mut std::process::Child, n: usize) {
    let deadline = Instant::now() + Duration::from_secs(600);
    while cached_poses(out) < n {
        assert!(Instant::now() < deadline, "no progress");
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before it could be interrupted"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn sigterm_stops_after_the_frame_in_flight_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let mut child = run_args(&out, 100, 139)
        .args(["--set", "run.batch_size=1"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_for_poses(&out, &mut child, 5);
    let pid = child.id().to_string();
    let sent = std::process::Command::new("kill")
        .args(["-TERM", &pid])
        .status();
    assert!(sent.unwrap().success());
    let ended = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&ended.stderr);
    // 128 + SIGTERM, as shells and Slurm report a task ended by it.
    assert_eq!(ended.status.code(), Some(143), "{stderr}");
    let error: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(error.len(), 1, "{stderr}");
    assert!(error[0].contains("interrupted during poses"), "{stderr}");
    let manifest = read_json(&out.join("run.json"));
    assert_eq!(manifest["status"], "interrupted");
    assert_eq!(manifest["interrupted_during"], "poses");
    assert!(!out.join("keypoints.csv").exists());

    // The rerun resumes and equals a run that was never stopped.
    run_ok(&mut run_args(&out, 100, 139));
    let manifest = read_json(&out.join("run.json"));
    assert!(manifest["frames_from_cache"].as_u64().unwrap() >= 5);
    // Completed: "done", or "no_result" where these frames hold no walking bout.
    assert!(
        ["done", "no_result"].contains(&manifest["status"].as_str().unwrap()),
        "{}",
        manifest["status"]
    );
    let clean = dir.path().join("clean");
    run_ok(run_args(&clean, 100, 139).args(["--set", "run.cache=false"]));
    assert_eq!(
        rows(&out.join("keypoints.csv")),
        rows(&clean.join("keypoints.csv"))
    );
}

#[test]
fn a_later_first_frame_does_not_reuse_tracked_poses() {
    // BlazePose tracks from frame to frame, so a run starting at 152 must not
    // take the poses that a run starting at 150 tracked into 152 and 153.
    let dir = tempfile::tempdir().unwrap();
    let cache = format!("run.cache_dir={}", dir.path().join("shared").display());
    let (long, short, alone) = (
        dir.path().join("long"),
        dir.path().join("short"),
        dir.path().join("alone"),
    );
    run_ok(run_args(&long, 150, 153).args(["--set", &cache]));
    run_ok(run_args(&short, 152, 153).args(["--set", &cache]));
    run_ok(run_args(&alone, 152, 153).args(["--set", "run.cache=false"]));
    let manifest = read_json(&short.join("run.json"));
    assert_eq!(manifest["stages"]["pose"]["computed"].as_u64(), Some(2));
    assert_eq!(
        rows(&short.join("keypoints.csv")),
        rows(&alone.join("keypoints.csv"))
    );
}

#[test]
fn a_second_run_into_a_busy_folder_is_refused_and_a_killed_one_leaves_no_lock() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let mut first = run_args(&out, 100, 139)
        .args(["--set", "run.batch_size=1"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    wait_for_poses(&out, &mut first, 2);
    let second = run_args(&out, 100, 139).output().unwrap();
    let stderr = String::from_utf8_lossy(&second.stderr);
    assert_eq!(second.status.code(), Some(2), "{stderr}");
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(
        lines[0].contains(&format!("pid {}", first.id())) && lines[0].contains("gait run"),
        "{stderr}"
    );
    // Killed hard, the holder cannot clean up; the kernel drops its lock.
    first.kill().unwrap();
    first.wait().unwrap();
    run_ok(&mut run_args(&out, 100, 139));
    assert!(out.join("keypoints.csv").exists());
    assert!(!out.join(".gait.lock").exists());
}

#[test]
fn corrupt_cache_entries_are_recomputed_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    run_ok(&mut run_args(&out, 100, 119));
    let before = std::fs::read(out.join("keypoints.csv")).unwrap();
    // Flip a byte in some entries and cut others short: poses, tracker states and the people
    // of a frame.
    let entries: Vec<std::path::PathBuf> = ["pose-", "subject-"]
        .iter()
        .flat_map(|prefix| {
            std::fs::read_dir(out.join("cache"))
                .unwrap()
                .flatten()
                .filter(move |e| e.file_name().to_string_lossy().starts_with(prefix))
                .flat_map(|e| std::fs::read_dir(e.path()).unwrap().flatten())
                .map(|e| e.path())
                .filter(|p| p.file_name().is_some_and(|n| n != "config.json"))
        })
        .collect();
    let pick = |stage: &str, name: &str| {
        entries
            .iter()
            .find(|p| {
                p.ends_with(name)
                    && p.parent()
                        .and_then(|d| d.file_name())
                        .is_some_and(|d| d.to_string_lossy().starts_with(stage))
            })
            .unwrap_or_else(|| panic!("no cache entry {stage}*/{name} in {entries:?}"))
            .clone()
    };
    // The tracker's state after frame 108 too: recomputing 109 needs it, so it is rebuilt
    // by estimating 108 again (not by starting the tracker afresh, which would change 109).
    let corrupted = [
        pick("pose-", "000105.json"),
        pick("pose-", "000112.json"),
        pick("subject-", "000110.json"),
        pick("pose-", "000108.state"),
        pick("pose-", "000109.json"),
    ];
    for (k, path) in corrupted.iter().enumerate() {
        let mut bytes = std::fs::read(path).unwrap();
        if k % 2 == 0 {
            bytes[1] ^= 0x20;
        } else {
            bytes.truncate(bytes.len() / 2);
        }
        std::fs::write(path, bytes).unwrap();
    }
    run_ok(&mut run_args(&out, 100, 119));
    let manifest = read_json(&out.join("run.json"));
    let warnings: Vec<&str> = manifest["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|w| w.as_str())
        .filter(|w| w.contains("failed its checksum"))
        .collect();
    assert!(warnings.len() >= corrupted.len(), "{warnings:?}");
    // Recomputed, not used: the results are those of the first run.
    assert_eq!(std::fs::read(out.join("keypoints.csv")).unwrap(), before);
}

/// A photograph with EXIF orientation 6 (taken with the camera turned) is analysed as displayed,
/// as `cv2.imread` reads it, and run.json records the orientation found. (That the pixels and the
/// sizes are OpenCV's is tested in gait-pipeline's tests/still_images.rs.)
#[test]
fn an_exif_orientation_is_applied_and_recorded() {
    let dir = tempfile::tempdir().unwrap();
    let photo = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data/jpeg/hopper_orientation_6.jpg");
    let out = dir.path().join("run");
    run_ok(&mut common::run_on(&photo, &out));
    let manifest = read_json(&out.join("run.json"));
    assert_eq!(
        manifest["input"]["exif_orientation"],
        serde_json::json!({"6": 1}),
        "{}",
        manifest["input"]
    );
}
