//! The paper's two speed-ups end to end on the bundled real walking video
//! with the real BlazePose model and the passthrough regenerator:
//! selective regeneration of poor frames (`selection.mode = "poor"`) and
//! the frame stride with interpolation (`selection.stride`).

mod common;

use common::{fails_with, read_json, run_ok, sample_run};
use gait_core::keypoint::LOWER_LIMB as LOWER;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::process::Command;

fn run_args(out: &Path, first: usize, last: usize, sets: &[&str]) -> Command {
    let mut cmd = sample_run(out, first, last);
    for s in sets {
        cmd.args(["--set", s]);
    }
    cmd
}

/// A keypoints CSV: keypoint names and, per frame, the raw cells.
struct Csv {
    names: Vec<String>,
    rows: Vec<(usize, Vec<String>)>,
}

impl Csv {
    fn read(path: &Path) -> Self {
        let text = std::fs::read_to_string(path).unwrap();
        let mut lines = text.lines();
        lines.next();
        let names = lines
            .next()
            .unwrap()
            .split(',')
            .skip(1)
            .step_by(3)
            .map(str::to_string)
            .collect();
        lines.next();
        let rows = lines
            .map(|l| {
                let mut cells = l.split(',');
                let frame = cells.next().unwrap().parse().unwrap();
                (frame, cells.map(str::to_string).collect())
            })
            .collect();
        Csv { names, rows }
    }

    fn frames(&self) -> Vec<usize> {
        self.rows.iter().map(|r| r.0).collect()
    }

    fn row(&self, frame: usize) -> &[String] {
        &self.rows.iter().find(|r| r.0 == frame).unwrap().1
    }

    /// (x, y, likelihood) of `name` in `frame`; NaN coordinates when missing.
    fn point(&self, frame: usize, name: &str) -> [f64; 3] {
        let i = self.names.iter().position(|n| n == name).unwrap();
        let cells = self.row(frame);
        let v = |c: usize| cells[3 * i + c].parse::<f64>().unwrap_or(f64::NAN);
        [v(0), v(1), v(2)]
    }
}

/// The poor-frame rule written out again from its documentation
/// (configs/default.toml), with the default bands [0.6, 1.6]: the first
/// rule that fires names the reason.
fn judge(csv: &Csv, min_likelihood: f64) -> BTreeMap<usize, Option<&'static str>> {
    let mut verdict = BTreeMap::new();
    for &f in &csv.frames() {
        let points: Vec<[f64; 3]> = LOWER.iter().map(|n| csv.point(f, n)).collect();
        let reason = if points.iter().any(|p| p[0].is_nan() || p[1].is_nan()) {
            Some("missing")
        } else if points.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min) < min_likelihood {
            Some("low_likelihood")
        } else {
            None
        };
        verdict.insert(f, reason);
    }
    let len = |f: usize, a: &str, b: &str| {
        let (p, q) = (csv.point(f, a), csv.point(f, b));
        (p[0] - q[0]).hypot(p[1] - q[1])
    };
    let segments = [("hip", "knee"), ("knee", "ankle")];
    let mut medians = Vec::new();
    for (a, b) in segments {
        let mut all: Vec<f64> = verdict
            .iter()
            .filter(|(_, r)| r.is_none())
            .flat_map(|(&f, _)| {
                ["left", "right"].map(|s| len(f, &format!("{s}_{a}"), &format!("{s}_{b}")))
            })
            .collect();
        all.sort_by(f64::total_cmp);
        let n = all.len();
        medians.push(if n % 2 == 1 {
            all[n / 2]
        } else {
            (all[n / 2 - 1] + all[n / 2]) / 2.0
        });
    }
    let inside = |r: f64| (0.6..=1.6).contains(&r);
    for (&f, reason) in verdict.iter_mut() {
        if reason.is_some() {
            continue;
        }
        for ((a, b), m) in segments.iter().zip(&medians) {
            let l = len(f, &format!("left_{a}"), &format!("left_{b}"));
            let r = len(f, &format!("right_{a}"), &format!("right_{b}"));
            if !(inside(l / m) && inside(r / m)) {
                *reason = Some("segment_length");
                break;
            }
            if !inside(l / r) {
                *reason = Some("left_right");
                break;
            }
        }
    }
    verdict
}

/// A likelihood threshold between the `below`-th and the next frame's weakest
/// lower-limb likelihood, so that some frames are poor and some good.
fn splitting_threshold(csv: &Csv, below: usize) -> f64 {
    let mut weakest: Vec<f64> = csv
        .frames()
        .iter()
        .map(|&f| {
            LOWER
                .iter()
                .map(|n| csv.point(f, n)[2])
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    weakest.sort_by(f64::total_cmp);
    (weakest[below - 1] + weakest[below]) / 2.0
}

/// Inclusive ranges of run.json as a set of frames.
fn frames_of(ranges: &serde_json::Value) -> BTreeSet<usize> {
    ranges
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|r| r[0].as_u64().unwrap() as usize..=r[1].as_u64().unwrap() as usize)
        .collect()
}

fn cached_files(cache: &Path, prefix: &str) -> Vec<std::path::PathBuf> {
    let dir = std::fs::read_dir(cache)
        .unwrap()
        .flatten()
        .find(|e| {
            let name = e.file_name().to_string_lossy().to_string();
            name.starts_with(prefix) && name[prefix.len()..].chars().all(|c| c.is_ascii_hexdigit())
        })
        .unwrap_or_else(|| panic!("no {prefix}* folder in {}", cache.display()))
        .path();
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.file_name().is_some_and(|n| n != "config.json"))
        .collect();
    files.sort();
    files
}

#[test]
fn poor_frames_are_regenerated_and_good_frames_keep_their_pose() {
    let dir = tempfile::tempdir().unwrap();
    let (first, last) = (150, 159);
    // The original-frame run: every frame, the passthrough regenerator.
    let plain = dir.path().join("plain");
    run_ok(&mut run_args(&plain, first, last, &[]));
    let original = Csv::read(&plain.join("keypoints.csv"));

    let threshold = splitting_threshold(&original, 5);
    let threshold_set = format!("selection.min_likelihood={threshold}");
    let sets = ["selection.mode=poor", threshold_set.as_str()];

    let out = dir.path().join("poor");
    let done = run_ok(&mut run_args(&out, first, last, &sets));
    // The pass over the original frames equals the plain run.
    let judged = Csv::read(&out.join("keypoints_original.csv"));
    assert_eq!(judged.rows, original.rows);

    let verdict = judge(&judged, threshold);
    let poor: BTreeSet<usize> = verdict
        .iter()
        .filter(|(_, r)| r.is_some())
        .map(|(f, _)| *f)
        .collect();
    let good: BTreeSet<usize> = (first..=last).filter(|f| !poor.contains(f)).collect();
    assert!(
        !poor.is_empty() && !good.is_empty(),
        "the threshold {threshold} should split the frames: {verdict:?}"
    );

    let manifest = read_json(&out.join("run.json"));
    let sel = &manifest["selection"];
    assert_eq!(frames_of(&sel["regenerated"]), poor);
    assert_eq!(frames_of(&sel["original"]), good);
    assert_eq!(sel["regenerated_count"], poor.len());
    assert!(frames_of(&sel["interpolated"]).is_empty());
    let mut by_reason: BTreeMap<&str, BTreeSet<usize>> = BTreeMap::new();
    for (f, r) in &verdict {
        if let Some(r) = r {
            by_reason.entry(r).or_default().insert(*f);
        }
    }
    let recorded: BTreeMap<&str, BTreeSet<usize>> = sel["poor"]
        .as_object()
        .unwrap()
        .iter()
        .map(|(k, v)| (k.as_str(), frames_of(v)))
        .collect();
    assert_eq!(recorded, by_reason);
    for (reason, frames) in &by_reason {
        assert_eq!(sel["poor_counts"][reason], frames.len());
    }
    assert_eq!(manifest["stages"]["original-pose"]["computed"], 10);
    assert_eq!(manifest["stages"]["pose"]["computed"], poor.len());
    let stderr = String::from_utf8_lossy(&done.stderr);
    assert!(
        stderr.contains(&format!("regenerated {} of 10 frames", poor.len())),
        "{stderr}"
    );

    // Good frames keep the original-frame pose exactly.
    let result = Csv::read(&out.join("keypoints.csv"));
    assert_eq!(result.frames(), (first..=last).collect::<Vec<_>>());
    for f in &good {
        assert_eq!(result.row(*f), original.row(*f), "frame {f}");
    }

    // run.json repeats the run, all from the cache.
    let again = dir.path().join("again");
    let cache_dir = format!("run.cache_dir={}", out.join("cache").display());
    run_ok(common::rerun(&out, &again).args(["--set", &cache_dir]));
    let repeated = read_json(&again.join("run.json"));
    assert_eq!(repeated["frames_from_cache"], 10);
    assert_eq!(repeated["stages"]["pose"]["computed"], 0);
    assert_eq!(repeated["stages"]["original-pose"]["computed"], 0);
    assert_eq!(repeated["selection"], manifest["selection"]);
    assert_eq!(Csv::read(&again.join("keypoints.csv")).rows, result.rows);

    // Without a cache: the same result.
    let clean = dir.path().join("clean");
    let mut no_cache = sets.to_vec();
    no_cache.push("run.cache=false");
    run_ok(&mut run_args(&clean, first, last, &no_cache));
    assert_eq!(Csv::read(&clean.join("keypoints.csv")).rows, result.rows);

    // An interrupted run (the later half of each pass's cached poses and
    // tracker states gone) resumes to the same result: the tracker state is
    // restored from the frame before, in each pass's own order.
    // A pose is written after its state, so whole frames go (both files).
    for prefix in ["original-pose-", "pose-"] {
        let files = cached_files(&out.join("cache"), prefix);
        let frames: BTreeSet<String> = files
            .iter()
            .map(|f| f.file_stem().unwrap().to_string_lossy().to_string())
            .collect();
        let later: BTreeSet<String> = frames.into_iter().skip(1).step_by(2).collect();
        assert!(!later.is_empty() || prefix == "pose-");
        for f in &files {
            if later.contains(&*f.file_stem().unwrap().to_string_lossy()) {
                std::fs::remove_file(f).unwrap();
            }
        }
    }
    std::fs::remove_file(out.join("keypoints.csv")).unwrap();
    run_ok(&mut run_args(&out, first, last, &sets));
    let resumed = read_json(&out.join("run.json"));
    let redone = resumed["stages"]["original-pose"]["computed"]
        .as_u64()
        .unwrap();
    assert_eq!(redone, 5, "recomputed original poses");
    let resumed = Csv::read(&out.join("keypoints.csv"));
    for f in first..=last {
        assert_eq!(resumed.row(f), result.row(f), "frame {f} after resuming");
    }
}

#[test]
fn stride_interpolates_between_processed_frames() {
    let dir = tempfile::tempdir().unwrap();
    let (first, last) = (150, 160);
    // Detection in every frame (no tracking), so a frame's pose does not
    // depend on which frames came before and the two runs can be compared.
    let every = dir.path().join("every");
    run_ok(&mut run_args(&every, first, last, &["pose.tracking=false"]));
    let out = dir.path().join("stride");
    let done = run_ok(&mut run_args(
        &out,
        first,
        last,
        &["pose.tracking=false", "selection.stride=3"],
    ));
    let (full, strided) = (
        Csv::read(&every.join("keypoints.csv")),
        Csv::read(&out.join("keypoints.csv")),
    );
    assert_eq!(strided.frames(), (first..=last).collect::<Vec<_>>());

    let manifest = read_json(&out.join("run.json"));
    let sel = &manifest["selection"];
    let processed = [150, 153, 156, 159, 160];
    assert_eq!(
        frames_of(&sel["processed"]),
        processed.into_iter().collect::<BTreeSet<_>>()
    );
    assert_eq!(frames_of(&sel["regenerated"]), frames_of(&sel["processed"]));
    let between: BTreeSet<usize> = (first..=last).filter(|f| !processed.contains(f)).collect();
    assert_eq!(frames_of(&sel["interpolated"]), between);
    assert_eq!(sel["interpolated_count"], 6);
    assert_eq!(manifest["frames_processed"], 11);
    assert_eq!(manifest["stages"]["pose"]["computed"], 5);
    assert!(String::from_utf8_lossy(&done.stderr).contains("; 6 interpolated"));

    for f in processed {
        assert_eq!(strided.row(f), full.row(f), "processed frame {f}");
    }
    for pair in processed.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        for f in a + 1..b {
            let t = (f - a) as f64 / (b - a) as f64;
            for name in &full.names {
                let (pa, pb, got) = (
                    full.point(a, name),
                    full.point(b, name),
                    strided.point(f, name),
                );
                if pa[0].is_nan() || pb[0].is_nan() {
                    assert!(got[0].is_nan() && got[1].is_nan(), "{name} at {f}");
                    continue;
                }
                for c in 0..2 {
                    let want = pa[c] + t * (pb[c] - pa[c]);
                    assert!(
                        (got[c] - want).abs() <= 1e-9 * want.abs().max(1.0),
                        "{name} at {f}: {} vs {want}",
                        got[c]
                    );
                }
                assert_eq!(got[2], pa[2].min(pb[2]), "{name} likelihood at {f}");
            }
        }
    }

    // Repeating from run.json gives the same keypoints.
    let again = dir.path().join("again");
    run_ok(&mut common::rerun(&out, &again));
    assert_eq!(Csv::read(&again.join("keypoints.csv")).rows, strided.rows);
    assert_eq!(read_json(&again.join("run.json"))["selection"], *sel);
}

#[test]
fn invalid_selection_settings_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    fails_with(
        &mut run_args(&out, 150, 152, &["selection.stride=0"]),
        &["selection.", "stride"],
    );
    fails_with(
        &mut run_args(&out, 150, 152, &["selection.segment_ratio=[1.6, 0.6]"]),
        &["selection.", "segment_ratio"],
    );
    fails_with(
        &mut run_args(&out, 150, 152, &["selection.side_ratio=[0.5]"]),
        &["selection.", "side_ratio"],
    );
    fails_with(
        &mut run_args(&out, 150, 152, &["selection.mode=some"]),
        &["selection.", "some", "poor"],
    );
    fails_with(
        &mut run_args(&out, 150, 152, &["selection.stide=2"]),
        &["stide", "stride"],
    );
    fails_with(
        &mut run_args(
            &out,
            150,
            152,
            &["selection.mode=poor", "selection.keypoints=[\"left_paw\"]"],
        ),
        &["selection.", "left_paw", "left_knee"],
    );
}

#[test]
fn only_poor_frames_go_through_the_controlnet() {
    // The tiny random SD 1.5 + ControlNet (noise images, real wiring): the
    // edge detector and the diffusion model run on the poor frames alone, and
    // their poses come from the redrawn images.
    let dir = tempfile::tempdir().unwrap();
    let (first, last) = (150, 155);
    let plain = dir.path().join("plain");
    run_ok(&mut run_args(&plain, first, last, &[]));
    let original = Csv::read(&plain.join("keypoints.csv"));
    let threshold = splitting_threshold(&original, 3);

    let cache = dir.path().join("cache");
    let mut sets = common::tiny_controlnet_sets();
    sets.extend([
        "selection.mode=poor".to_string(),
        format!("selection.min_likelihood={threshold}"),
        format!("run.cache_dir={}", cache.display()),
    ]);
    let sets: Vec<&str> = sets.iter().map(String::as_str).collect();
    let out = dir.path().join("poor");
    run_ok(&mut run_args(&out, first, last, &sets));

    let poor: BTreeSet<usize> = judge(&Csv::read(&out.join("keypoints_original.csv")), threshold)
        .into_iter()
        .filter_map(|(f, r)| r.map(|_| f))
        .collect();
    assert!(!poor.is_empty() && poor.len() < 6, "{poor:?}");
    let manifest = read_json(&out.join("run.json"));
    assert_eq!(frames_of(&manifest["selection"]["regenerated"]), poor);
    for stage in ["edge", "regenerator", "pose"] {
        assert_eq!(
            manifest["stages"][stage]["computed"],
            poor.len(),
            "{stage} ran on other frames than the poor ones"
        );
    }
    // The redrawn images are the poor frames, by frame number.
    let redrawn: BTreeSet<usize> = cached_files(&cache, "regenerator-")
        .iter()
        .map(|p| p.file_stem().unwrap().to_string_lossy().parse().unwrap())
        .collect();
    assert_eq!(redrawn, poor);

    let result = Csv::read(&out.join("keypoints.csv"));
    for f in first..=last {
        if poor.contains(&f) {
            // Poses of noise images, not of the original frames.
            assert_ne!(result.row(f), original.row(f), "frame {f}");
        } else {
            assert_eq!(result.row(f), original.row(f), "frame {f}");
        }
    }
}
