//! The whole sample video with the default pipeline: the walker is found
//! with no frame range, the man who jumps off the box after she has left
//! never enters an accepted cycle, and the automatic events agree with the
//! manual annotation in tests/data/sample-events.

mod common;

use std::path::Path;

use common::{read_json, run_ok, run_on, sample_video};

/// Rows of a CSV file as maps from the header's names to the cells.
fn csv_rows(path: &Path) -> Vec<std::collections::HashMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    lines
        .map(|l| {
            header
                .iter()
                .cloned()
                .zip(l.split(',').map(str::to_string))
                .collect()
        })
        .collect()
}

fn events(path: &Path) -> Vec<(String, String, i64)> {
    csv_rows(path)
        .into_iter()
        .map(|r| {
            (
                r["side"].clone(),
                r["event"].clone(),
                r["frame"].parse().unwrap(),
            )
        })
        .collect()
}

#[test]
fn whole_sample_video_follows_the_walker_only_while_she_walks() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    run_ok(&mut run_on(&sample_video(), &out));
    let run = read_json(&out.join("run.json"));

    // The subject is the woman: a track that starts after the man's (he is
    // in view from frame 0) and walks across the view to the left.
    let subject = &run["subject"];
    let chosen = subject["chosen"].as_u64().unwrap();
    let track = subject["tracks"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["id"].as_u64() == Some(chosen))
        .unwrap();
    assert!(subject["walking"].as_bool().unwrap(), "{subject}");
    assert!(track["first_frame"].as_u64().unwrap() >= 20, "{track}");
    assert!(track["last_frame"].as_u64().unwrap() <= 205, "{track}");
    assert_eq!(track["walk"]["direction"].as_i64(), Some(-1), "{track}");
    assert!(
        subject["tracks"].as_array().unwrap().len() >= 2,
        "the man is tracked too"
    );

    // keypoints.csv has only her: from frame 205 on (she is gone) every
    // frame is empty.
    let text = std::fs::read_to_string(out.join("keypoints.csv")).unwrap();
    for line in text.lines().skip(3) {
        let mut cells = line.split(',');
        let frame: usize = cells.next().unwrap().parse().unwrap();
        if frame >= 205 {
            assert!(
                cells.all(|c| c.is_empty() || c == "NaN"),
                "frame {frame}: {line}"
            );
        }
    }

    // Accepted cycles lie inside her bouts, before she leaves, with stride
    // times within 20 % of their median.
    let quality = csv_rows(&out.join("cycle_quality.csv"));
    let accepted: Vec<_> = quality.iter().filter(|q| q["accepted"] == "true").collect();
    assert!(accepted.len() >= 2, "{quality:?}");
    let mut strides: Vec<f64> = accepted
        .iter()
        .map(|q| q["stride_s"].parse().unwrap())
        .collect();
    strides.sort_by(f64::total_cmp);
    let median = strides[strides.len() / 2];
    for q in &accepted {
        assert!(q["last_frame"].parse::<usize>().unwrap() < 200, "{q:?}");
        let s: f64 = q["stride_s"].parse().unwrap();
        assert!((s - median).abs() <= 0.2 * median, "{q:?} median {median}");
    }
    for side in ["left", "right"] {
        assert!(
            accepted.iter().any(|q| q["side"] == side),
            "no accepted {side} cycle: {quality:?}"
        );
    }

    // Events against the manual annotation, where she is fully in view
    // (frames 54-186; before, a tree trunk hides her, after, the image edge
    // cuts her, and no bout covers those frames): every heel strike is
    // found, and at least 90 % of the annotated events are within 2 frames.
    let found = events(&out.join("events.csv"));
    let annotation =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/sample-events/events.csv");
    let truth: Vec<_> = events(&annotation)
        .into_iter()
        .filter(|t| (54..=186).contains(&t.2))
        .collect();
    let near = |t: &(String, String, i64)| {
        found
            .iter()
            .any(|f| f.0 == t.0 && f.1 == t.1 && (f.2 - t.2).abs() <= 2)
    };
    // An event needs frames on both sides of it: heel strikes within a
    // frame of the first one with her pose cannot be found.
    let first_pose = text
        .lines()
        .skip(3)
        .find(|l| l.split(',').skip(1).any(|c| !c.is_empty() && c != "NaN"))
        .and_then(|l| l.split(',').next()?.parse::<i64>().ok())
        .unwrap();
    for t in truth
        .iter()
        .filter(|t| t.1 == "heel_strike" && t.2 > first_pose + 1)
    {
        assert!(near(t), "annotated {t:?} not found: {found:?}");
    }
    let hits = truth.iter().filter(|t| near(t)).count();
    assert!(
        hits as f64 >= 0.9 * truth.len() as f64,
        "{hits} of {} annotated events within 2 frames; found {found:?}",
        truth.len()
    );

    // The report names no prosthetic side that nobody set, and lists the bouts.
    let report = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(
        !report.contains("Prosthetic side"),
        "the report invents a prosthetic side"
    );
    assert!(report.contains("Walking bouts") && report.contains("Cycle quality"));
}

/// `[subject] detect_every = 2` against the default on the sample, sharing
/// the cache (it holds detections only, so the sparse run detects what it
/// would detect afresh): the same walker over the same frames, a good share
/// of the detector's frames spared, every event within a frame.
#[test]
fn the_detector_on_every_second_frame_follows_the_same_walker() {
    let dir = tempfile::tempdir().unwrap();
    let cache = format!("run.cache_dir={:?}", dir.path().join("cache"));
    let run = |name: &str, every: &str| {
        let out = dir.path().join(name);
        let set = format!("subject.detect_every={every}");
        run_ok(run_on(&sample_video(), &out).args(["--set", &cache, "--set", &set]));
        (
            read_json(&out.join("run.json")),
            events(&out.join("events.csv")),
        )
    };
    let (dense, dense_events) = run("dense", "1");
    let (sparse, sparse_events) = run("sparse", "2");
    let (d, s) = (&dense["subject"], &sparse["subject"]);
    assert_eq!(d["interpolated_frames"], 0);
    let spared = s["interpolated_frames"].as_u64().unwrap();
    assert!(spared >= 30, "only {spared} frames interpolated");
    assert_eq!(s["in_view"], d["in_view"]);
    assert_eq!(s["chosen"], d["chosen"]);
    assert_eq!(
        sparse_events.len(),
        dense_events.len(),
        "{sparse_events:?} vs {dense_events:?}"
    );
    for (a, b) in sparse_events.iter().zip(&dense_events) {
        assert!(
            a.0 == b.0 && a.1 == b.1 && (a.2 - b.2).abs() <= 1,
            "{a:?} vs {b:?}"
        );
    }
}

/// A patient asked to walk to the end of the room and back: the sample, then its mirror (she
/// leaves at the image's left, is out of view for 3 s, and walks back to the right with her
/// right side to the camera). Both walks are followed and analysed, each side's events from
/// both and its cycles from the walk where it is near the camera, and run.json says which track
/// was taken as her walk back; the man on the box, there all along, is not.
#[test]
fn a_walk_there_and_back_is_followed_both_ways() {
    let dir = tempfile::tempdir().unwrap();
    let mirror = dir.path().join("mirror.mp4");
    let both = dir.path().join("there_and_back.mp4");
    let ffmpeg = |args: &[&std::ffi::OsStr]| {
        let st = std::process::Command::new("ffmpeg")
            .args(["-loglevel", "error", "-y"])
            .args(args)
            .status()
            .expect("ffmpeg runs");
        assert!(st.success());
    };
    let sample = sample_video();
    ffmpeg(&[
        "-i".as_ref(),
        sample.as_os_str(),
        "-vf".as_ref(),
        "hflip".as_ref(),
        "-c:v".as_ref(),
        "libx264".as_ref(),
        "-crf".as_ref(),
        "16".as_ref(),
        mirror.as_os_str(),
    ]);
    ffmpeg(&[
        "-i".as_ref(),
        sample.as_os_str(),
        "-i".as_ref(),
        mirror.as_os_str(),
        "-filter_complex".as_ref(),
        "[0:v][1:v]concat=n=2:v=1[v]".as_ref(),
        "-map".as_ref(),
        "[v]".as_ref(),
        "-c:v".as_ref(),
        "libx264".as_ref(),
        "-crf".as_ref(),
        "16".as_ref(),
        both.as_os_str(),
    ]);
    let out = dir.path().join("run");
    run_ok(run_on(&both, &out).args([
        "--set",
        "report.overlay=false",
        "--set",
        "report.pdf=false",
    ]));
    let bouts = csv_rows(&out.join("bouts.csv"));
    let directions: Vec<&str> = bouts.iter().map(|b| b["direction"].as_str()).collect();
    assert_eq!(directions, ["left", "right"], "{bouts:?}");
    let ev = events(&out.join("events.csv"));
    for (side, first_half) in [
        ("left", true),
        ("left", false),
        ("right", true),
        ("right", false),
    ] {
        let n = ev
            .iter()
            .filter(|e| e.0 == side && e.1 == "heel_strike" && (e.2 < 230) == first_half)
            .count();
        assert!(
            n >= 2,
            "{side} heel strikes in the {} walk: {ev:?}",
            if first_half { "first" } else { "second" }
        );
    }
    let manifest = read_json(&out.join("run.json"));
    let back = manifest["subject"]["returns"].as_array().unwrap();
    assert_eq!(back.len(), 1, "{back:?}");
    let (first, last) = (
        back[0]["first_frame"].as_u64().unwrap(),
        back[0]["last_frame"].as_u64().unwrap(),
    );
    assert!(
        first < 100 && last < 230,
        "the other walk is the first one: {first}-{last}"
    );
    // Each leg's curves come from the walk where it is near the camera: the left's from the
    // first walk (toward the image's left), the right's from the walk back; the far leg's
    // strides are rejected as such.
    let cycles = csv_rows(&out.join("cycle_quality.csv"));
    for c in &cycles {
        let first: usize = c["first_frame"].parse().unwrap();
        let near = (c["side"] == "left") == (first < 230);
        let verdict = (c["accepted"].as_str(), c["reasons"].as_str());
        let want = if near {
            ("true", "")
        } else {
            ("false", "far_side")
        };
        assert_eq!(verdict, want, "{c:?}");
    }
    let accepted = cycles.iter().filter(|c| c["accepted"] == "true").count();
    assert!(accepted >= 4, "{accepted} cycles accepted over both walks");
}
