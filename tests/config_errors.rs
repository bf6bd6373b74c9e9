//! Bad configuration gives one clear line on stderr naming `table.key` and where the value came
//! from, exit code 2, no panic; a missing model names the command that fetches it; every shipped
//! config parses and every subcommand has help.

mod common;

use common::{assert_no_results, fails_with, gait};
use std::path::Path;

#[test]
fn toml_syntax_error() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("bad.toml");
    std::fs::write(&cfg, "[pose\nkind = \"blazepose\"\n").unwrap();
    fails_with(
        gait()
            .args(["run", "--no-progress", "--config"])
            .arg(&cfg)
            .arg("--input")
            .arg(common::sample_video())
            .arg("--out")
            .arg(dir.path().join("out")),
        &["bad.toml", "line 1"],
    );
}

#[test]
fn unknown_stage_kind_lists_the_choices() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, &[&str]); 2] = [
        (
            "edge.kind=sobelx",
            &["--set edge.kind=sobelx", "edge.kind", "sobelx", "none"],
        ),
        (
            "pose.backend=tensorrt",
            &[
                "--set pose.backend=tensorrt",
                "pose.backend",
                "tensorrt",
                "candle",
                "ort",
            ],
        ),
    ];
    for (set, words) in cases {
        fails_with(
            gait()
                .args(["run", "--no-progress", "--set", set, "--input"])
                .arg(common::sample_video())
                .arg("--out")
                .arg(dir.path().join("out")),
            words,
        );
    }
}

/// Every config error names `table.key` and the place the value came from: the `--set`
/// option, or the file and its line (never the built-in default the value did not come from).
#[test]
fn config_errors_name_the_key_and_its_origin() {
    let dir = tempfile::tempdir().unwrap();
    let run = |config: Option<&Path>, sets: &[&str], needles: &[&str]| {
        let mut cmd = gait();
        cmd.args(["run", "--no-progress"]);
        if let Some(c) = config {
            cmd.arg("--config").arg(c);
        }
        for s in sets {
            cmd.args(["--set", s]);
        }
        cmd.arg("--input")
            .arg(common::sample_video())
            .arg("--out")
            .arg(dir.path().join("out"));
        let err = fails_with(&mut cmd, needles);
        assert!(!err.contains("built in"), "{err}");
        assert!(
            !dir.path().join("out").exists(),
            "a failed run left its folder"
        );
    };
    run(
        None,
        &["pose.backnd=ort"],
        &["--set pose.backnd=ort", "pose.backnd", "unknown field"],
    );
    run(
        None,
        &["pose.backend=nonsense"],
        &[
            "--set pose.backend=nonsense",
            "pose.backend",
            "nonsense",
            "candle",
        ],
    );
    run(
        None,
        &["regenerator.kind=controlnet", "regenerator.crop_size=300"],
        &[
            "--set regenerator.crop_size=300",
            "regenerator.crop_size",
            "array of length 2",
        ],
    );
    let cfg = dir.path().join("study.toml");
    std::fs::write(
        &cfg,
        "# a study\n[pose]\nkind = \"blazepose\"\nbackend = 3\n",
    )
    .unwrap();
    run(
        Some(&cfg),
        &[],
        &[
            "study.toml line 4",
            "pose.backend",
            "invalid type: integer `3`",
        ],
    );
}

/// `gait run --config configs/<config> --set <set>` fails with every word of
/// its case in one line, and writes nothing.
fn each_set_fails(config: &str, cases: &[(&str, &[&str])]) {
    let dir = tempfile::tempdir().unwrap();
    let config = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../configs")
        .join(config);
    for (set, words) in cases {
        fails_with(
            gait()
                .args(["run", "--no-progress", "--config"])
                .arg(&config)
                .args(["--set", set, "--input"])
                .arg(common::sample_video())
                .arg("--out")
                .arg(dir.path().join("out")),
            words,
        );
        assert_no_results(&dir.path().join("out"));
    }
}

#[test]
fn speed_settings_out_of_range_name_the_key() {
    let cases: [(&str, &[&str]); 4] = [
        (
            "regenerator.guidance_end=1.5",
            &["regenerator.guidance_end = 1.5", "[0, 1]"],
        ),
        (
            "regenerator.control_guidance_start=0.9",
            &[
                "control_guidance_start = 0.9",
                "control_guidance_end = 0.75",
            ],
        ),
        ("regenerator.scheduler=\"euler\"", &["euler", "dpmpp2m"]),
        (
            "regenerator.control_guidance_end=-1",
            &["control_guidance_end = -1"],
        ),
    ];
    each_set_fails("zero-shot-fast.toml", &cases);
}

#[test]
fn cpu_settings_out_of_range_name_the_key() {
    let cases: [(&str, &[&str]); 11] = [
        (
            "regenerator.cache_interval=0",
            &["regenerator.cache_interval = 0", "1..=8"],
        ),
        (
            "regenerator.cache_interval=9",
            &["regenerator.cache_interval = 9"],
        ),
        (
            "regenerator.cache_branch=12",
            &["regenerator.cache_branch = 12", "0..=11"],
        ),
        (
            "regenerator.token_merge_ratio=0.95",
            &["regenerator.token_merge_ratio = 0.95", "[0, 0.9]"],
        ),
        (
            "regenerator.crop_size=[250, 512]",
            &["regenerator.crop_size", "multiple of 64"],
        ),
        (
            "regenerator.crop_size=[256, 2048]",
            &["regenerator.crop_size", "1024"],
        ),
        (
            "subject.enabled=false",
            &["region = \"subject\"", "subject.enabled"],
        ),
        (
            "regenerator.strength=1.5",
            &["regenerator.strength = 1.5", "(0, 1]"],
        ),
        ("regenerator.strength=0", &["regenerator.strength = 0"]),
        (
            "regenerator.mode=\"inpaint\"",
            &["mode = \"inpaint\"", "region = \"frame\""],
        ),
        (
            "regenerator.backend=\"ort\"",
            &["cache_interval", "backend = \"candle\""],
        ),
    ];
    each_set_fails("zero-shot-cpu.toml", &cases);
}

#[test]
fn missing_model_file_names_the_fetch_command() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    fails_with(
        gait()
            .args(["run", "--no-progress", "--models-dir"])
            .arg(dir.path().join("no-models"))
            .arg("--input")
            .arg(common::sample_video())
            .arg("--out")
            .arg(&out),
        &["pose_detection.tflite", "gait models fetch blazepose"],
    );
    assert_no_results(&out);
    assert!(!out.exists(), "a failed run left an empty folder behind");
}

#[test]
fn zero_shot_without_weights_names_the_fetch_command_and_the_folders() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let models = dir.path().join("no-models");
    let config = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/zero-shot-canny.toml");
    let sd = models.join("stable-diffusion-v1-5");
    let cn = models.join("sd-controlnet-canny");
    fails_with(
        gait()
            .args(["run", "--no-progress", "--models-dir"])
            .arg(&models)
            .arg("--config")
            .arg(&config)
            .arg("--input")
            .arg(common::sample_video())
            .arg("--out")
            .arg(&out),
        &[
            "gait models fetch sd15-controlnet-canny",
            "fetched elsewhere",
            &sd.display().to_string(),
            &cn.display().to_string(),
        ],
    );
    assert!(!out.exists(), "a failed run left an empty folder behind");
}

#[test]
fn missing_openpose_weights_name_the_fetch_command() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    fails_with(
        gait()
            .args(["run", "--no-progress", "--models-dir"])
            .arg(dir.path().join("no-models"))
            .arg("--input")
            .arg(common::sample_video())
            .args(["--set", "pose.kind=openpose", "--out"])
            .arg(&out),
        &["body_pose_model.pth", "gait models fetch openpose"],
    );
    assert_no_results(&out);
}

#[test]
fn every_shipped_config_parses() {
    // Each config gets past parsing and validation: the run then stops at
    // the missing input, not at the config.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs");
    let dir = tempfile::tempdir().unwrap();
    let mut seen = 0;
    for entry in std::fs::read_dir(&root).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        seen += 1;
        fails_with(
            gait()
                .args(["run", "--no-progress", "--config"])
                .arg(&path)
                .arg("--input")
                .arg(dir.path().join("nope.mp4"))
                .arg("--out")
                .arg(dir.path().join("out")),
            &["nope.mp4"],
        );
    }
    assert!(seen >= 4, "configs found: {seen}");
}

#[test]
fn every_subcommand_has_help() {
    let out = gait().arg("--help").output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    let subcommands: Vec<String> = text
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .filter(|c| c != "help")
        .collect();
    assert!(subcommands.contains(&"run".to_string()), "{text}");
    for sub in subcommands {
        let out = gait().args([sub.as_str(), "--help"]).output().unwrap();
        assert!(out.status.success(), "gait {sub} --help failed");
        assert!(
            String::from_utf8_lossy(&out.stdout).contains("Usage: gait"),
            "gait {sub} --help"
        );
    }
}
