//! End-to-end tests of `gait kin`, `gait edges`, `gait eval`, `gait ablate`,
//! stage reuse through the cache, and a plugin stage chosen by config.

mod common;

use common::{fails_with, gait, models_dir, read_json, run_ok, sample_video};
use std::path::{Path, PathBuf};

fn data(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data")
        .join(rel)
}

fn csv_column(path: &Path, name: &str) -> Vec<Option<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = header
        .iter()
        .position(|h| *h == name)
        .unwrap_or_else(|| panic!("no {name} in {header:?}"));
    lines
        .map(|l| l.split(',').nth(col).and_then(|c| c.parse().ok()))
        .collect()
}

#[test]
fn kin_on_real_motion_capture() {
    // Fukuchi 2018 overground walking (150 Hz), projected on the sagittal plane.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("kin");
    run_ok(
        gait()
            .args(["kin", "--fps", "150", "--keypoints"])
            .arg(data("fukuchi2018/keypoints.csv"))
            .arg("--out")
            .arg(&out),
    );
    let header = std::fs::read_to_string(out.join("angles.csv")).unwrap();
    assert!(header.starts_with(
        "frame,time_s,left_hip,right_hip,left_knee,right_knee,left_ankle,right_ankle\n"
    ));
    for f in [
        "events.csv",
        "cycles.csv",
        "spatiotemporal.csv",
        "keypoints_filtered.csv",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    // Knee angle against the file's own reference knee angle.
    for side in ["left_knee", "right_knee"] {
        let ours = csv_column(&out.join("angles.csv"), side);
        let reference = csv_column(&data("fukuchi2018/reference.csv"), side);
        let errs: Vec<f64> = ours
            .iter()
            .zip(&reference)
            .filter_map(|(a, b)| Some((a.as_ref()? - b.as_ref()?).abs()))
            .collect();
        let mae = errs.iter().sum::<f64>() / errs.len() as f64;
        assert!(
            errs.len() > 300 && mae < 3.0,
            "{side}: MAE {mae:.2} deg over {} frames",
            errs.len()
        );
    }
    let events = std::fs::read_to_string(out.join("events.csv")).unwrap();
    assert!(
        events.starts_with("side,event,frame,time_s\n")
            && events.contains("heel_strike")
            && events.contains("toe_off")
    );

    fails_with(
        gait()
            .args(["kin", "--fps", "150", "--keypoints"])
            .arg(dir.path().join("none.csv"))
            .arg("--out")
            .arg(&out),
        &["none.csv"],
    );
    fails_with(
        gait()
            .args(["kin", "--fps=0", "--keypoints"])
            .arg(data("fukuchi2018/keypoints.csv"))
            .arg("--out")
            .arg(&out),
        &["--fps"],
    );
}

#[test]
fn eval_scores_a_prediction_against_truth() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("eval");
    let truth = data("fukuchi2018/keypoints.csv");
    run_ok(
        gait()
            .args([
                "eval",
                "--fps",
                "150",
                "--prosthetic-side",
                "right",
                "--truth",
            ])
            .arg(&truth)
            .arg("--pred")
            .arg(&truth)
            .arg("--out")
            .arg(&out),
    );
    let metrics = read_json(&out.join("metrics.json"));
    for leg in metrics["legs"].as_array().unwrap() {
        assert_eq!(leg["stat"]["mean"].as_f64(), Some(0.0), "{leg}");
    }
    assert!(
        std::fs::read_to_string(out.join("table.md"))
            .unwrap()
            .contains("|")
    );
    assert!(out.join("metrics.csv").is_file());
}

#[test]
fn edges_are_written_at_the_controlnet_size() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("edges");
    run_ok(
        gait()
            .args([
                "edges",
                "--no-progress",
                "--config",
                "configs/zero-shot-canny.toml",
            ])
            .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."))
            .arg("--input")
            .arg(sample_video())
            .args([
                "--set",
                "input.first_frame=120",
                "--set",
                "input.last_frame=122",
                "--out",
            ])
            .arg(&out),
    );
    for i in 120..=122 {
        let img = image::open(out.join(format!("{i:06}.png")))
            .unwrap()
            .to_luma8();
        assert_eq!(img.dimensions(), (896, 512));
        assert!(img.pixels().all(|p| p[0] == 0 || p[0] == 255));
        assert!(
            img.pixels().filter(|p| p[0] == 255).count() > 1000,
            "frame {i} has edges"
        );
    }
    assert!(!out.join("000119.png").exists() && !out.join("000123.png").exists());
    fails_with(
        gait()
            .args(["edges", "--no-progress", "--input"])
            .arg(sample_video())
            .arg("--out")
            .arg(&out),
        &["edge.kind", "none"],
    );
}

#[test]
fn changing_only_the_pose_stage_reuses_the_edge_maps() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let run = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        run_ok(
            gait()
                .args(["run", "--no-progress", "--models-dir"])
                .arg(models_dir())
                .arg("--input")
                .arg(sample_video())
                .args([
                    "--set",
                    "input.first_frame=150",
                    "--set",
                    "input.last_frame=153",
                    "--set",
                    "edge.kind=canny",
                ])
                .args(["--set", &format!("run.cache_dir=\"{}\"", cache.display())])
                .args(extra.iter().flat_map(|s| ["--set", s]))
                .arg("--out")
                .arg(&out),
        );
        read_json(&out.join("run.json"))
    };
    let first = run("a", &[]);
    assert_eq!(first["stages"]["edge"]["computed"], 4);
    let second = run("b", &["pose.tracking=false"]);
    assert_eq!(second["stages"]["edge"]["cached"], 4);
    assert_eq!(second["stages"]["edge"]["computed"], 0);
    assert_eq!(second["stages"]["pose"]["computed"], 4);
}

#[test]
fn ablate_compares_configurations() {
    let dir = tempfile::tempdir().unwrap();
    // Ground truth for the scoring columns: a plain run's own keypoints, so
    // the configuration equal to it must score zero error.
    let truth_run = dir.path().join("truth");
    run_ok(
        gait()
            .args(["run", "--no-progress", "--models-dir"])
            .arg(models_dir())
            .arg("--input")
            .arg(sample_video())
            .args([
                "--set",
                "input.first_frame=150",
                "--set",
                "input.last_frame=152",
                "--out",
            ])
            .arg(&truth_run),
    );
    let matrix = dir.path().join("matrix.toml");
    std::fs::write(
        &matrix,
        format!(
            "set = [\"input.first_frame=150\", \"input.last_frame=152\"]\n[[video]]\npath = \"{}\"\ntruth = \"{}\"\n[axes]\n\"edge.kind\" = [\"none\", \"canny\"]\n\"pose.tracking\" = [true, false]\n",
            sample_video().display(),
            truth_run.join("keypoints.csv").display()
        ),
    )
    .unwrap();
    let out = dir.path().join("ablate");
    run_ok(
        gait()
            .args(["ablate", "--no-progress", "--models-dir"])
            .arg(models_dir())
            .arg("--matrix")
            .arg(&matrix)
            .arg("--out")
            .arg(&out),
    );
    let table = std::fs::read_to_string(out.join("comparison.csv")).unwrap();
    let rows: Vec<&str> = table.lines().skip(1).collect();
    assert_eq!(rows.len(), 4, "{table}");
    for r in &rows {
        assert!(
            r.contains(",3,") && r.ends_with(",\"\""),
            "row without 3 frames or with an error: {r}"
        );
    }
    // Combinations in file order, labels quoted as CSV.
    assert!(
        rows[0].starts_with("sports2d-demo,\"edge.kind=\"\"none\"\",pose.tracking=true\","),
        "{table}"
    );
    assert!(
        rows[3].starts_with("sports2d-demo,\"edge.kind=\"\"canny\"\",pose.tracking=false\","),
        "{table}"
    );
    // px_err_prosthetic and px_err_intact of the configuration that made the truth.
    let cells: Vec<&str> = rows[0].rsplitn(8, ',').collect();
    assert_eq!((cells[5], cells[4]), ("0.000", "0.000"), "{table}");
    assert!(out.join("comparison.md").is_file());
}

/// `[edge] kind = "plugin"`: the example Sobel plugin, built like a user would.
#[test]
fn plugin_edge_stage_from_config() {
    let exe = std::env::current_exe().unwrap();
    let profile_dir = exe.parent().unwrap().parent().unwrap().to_path_buf();
    let profile = match profile_dir.file_name().and_then(|n| n.to_str()) {
        Some("debug") => "dev".to_string(),
        Some(p) => p.to_string(),
        None => panic!("profile folder"),
    };
    let status = std::process::Command::new(env!("CARGO"))
        .args([
            "build",
            "-p",
            "gait-sobel-edge",
            "--profile",
            &profile,
            "--target-dir",
        ])
        .arg(profile_dir.parent().unwrap())
        .arg("--manifest-path")
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../Cargo.toml"))
        .status()
        .unwrap();
    assert!(status.success());
    let lib = profile_dir.join(format!(
        "{}gait_sobel_edge{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    ));
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("edges");
    run_ok(
        gait()
            .args(["edges", "--no-progress", "--set", "edge.kind=plugin"])
            .args([
                "--set",
                &format!("edge.path=\"{}\"", lib.display()),
                "--set",
                "edge.options.threshold=120",
            ])
            .args([
                "--set",
                "input.first_frame=120",
                "--set",
                "input.last_frame=120",
                "--input",
            ])
            .arg(sample_video())
            .arg("--out")
            .arg(&out),
    );
    let img = image::open(out.join("000120.png")).unwrap().to_luma8();
    assert_eq!(img.dimensions(), (1768, 994));
    assert!(img.pixels().any(|p| p[0] == 255));
    fails_with(
        gait()
            .args([
                "edges",
                "--no-progress",
                "--set",
                "edge.kind=plugin",
                "--set",
                "edge.path=\"/nonexistent/libx.so\"",
                "--input",
            ])
            .arg(sample_video())
            .arg("--out")
            .arg(&out),
        &["libx.so"],
    );
}

#[test]
fn inpainting_runs_on_a_pose_of_the_original_frames() {
    // The tiny random SD 1.5 + ControlNet of gait-diffuse's fixtures: the
    // images are noise, but the wiring is real: a pose pass on the original
    // frames, leg masks from it, and a cache that knows the mask depends on it.
    let dir = tempfile::tempdir().unwrap();
    let cache = format!("run.cache_dir={}", dir.path().join("cache").display());
    let run = |out: &Path, extra: &[&str]| {
        let mut cmd = common::sample_run(out, 150, 151);
        for s in common::tiny_controlnet_sets()
            .iter()
            .map(String::as_str)
            .chain([
                "regenerator.mode=\"inpaint\"",
                "regenerator.mask.paste_back=true",
                &cache,
            ])
            .chain(extra.iter().copied())
        {
            cmd.args(["--set", s]);
        }
        run_ok(&mut cmd);
        common::read_json(&out.join("run.json"))
    };
    let first = run(&dir.path().join("a"), &[]);
    let stage = |m: &serde_json::Value, s: &str, k: &str| m["stages"][s][k].as_u64().unwrap();
    assert_eq!(stage(&first, "original-pose", "computed"), 2);
    assert_eq!(stage(&first, "regenerator", "computed"), 2);
    assert!(dir.path().join("a/keypoints_original.csv").is_file());
    // Same settings: the poses come from the cache, nothing is redrawn.
    let again = run(&dir.path().join("b"), &[]);
    assert_eq!(stage(&again, "pose", "cached"), 2);
    assert_eq!(stage(&again, "regenerator", "computed"), 0);
    // Another pose setting changes the masks, so the images are redrawn
    // rather than taken from the cache.
    let other = run(&dir.path().join("c"), &["pose.person=\"leftmost\""]);
    assert_eq!(stage(&other, "regenerator", "computed"), 2);
}

/// The matrix file of docs/ablate.md runs as documented: four runs scored against the truth,
/// and the page shows the file as it is.
#[test]
fn the_documented_ablate_example_runs() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let matrix = root.join("examples/ablate/matrix.toml");
    let text = std::fs::read_to_string(&matrix).unwrap();
    let doc = std::fs::read_to_string(root.join("docs/ablate.md")).unwrap();
    for line in text
        .lines()
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
    {
        assert!(
            doc.contains(line),
            "docs/ablate.md lacks `{line}` of the example"
        );
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ablation");
    run_ok(
        gait()
            .args(["ablate", "--no-progress", "--models-dir"])
            .arg(models_dir())
            .arg("--matrix")
            .arg(&matrix)
            .arg("--out")
            .arg(&out),
    );
    let table = std::fs::read_to_string(out.join("comparison.csv")).unwrap();
    let rows: Vec<Vec<&str>> = table
        .lines()
        .skip(1)
        .map(|r| r.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 4, "{table}");
    for r in &rows {
        // video, config (two quoted parts), frames, ..., px_err_prosthetic, ..., error.
        assert_eq!(r[3], "10", "{table}");
        assert!(
            r[7].parse::<f64>().is_ok(),
            "scored against the truth: {table}"
        );
        assert_eq!(*r.last().unwrap(), "\"\"", "no error: {table}");
    }
}
