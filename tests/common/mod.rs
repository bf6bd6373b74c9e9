//! Helpers shared by the end-to-end tests of the `gait` command.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The bundled sample video (real walking footage).
pub fn sample_video() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/sample/sports2d-demo.mp4")
}

/// The models folder prepared by tools/test.sh (`gait models fetch ...`).
pub fn models_dir() -> PathBuf {
    match std::env::var_os("GAIT_MODELS_DIR") {
        Some(d) if Path::new(&d).is_dir() => PathBuf::from(d),
        _ => panic!(
            "GAIT_MODELS_DIR is not set to a folder with the models: run the tests through tools/test.sh"
        ),
    }
}

pub fn gait() -> Command {
    Command::new(env!("CARGO_BIN_EXE_gait"))
}

/// `gait run` on `input` with the test models and the default pipeline,
/// writing to `out`. The overlay video and the PDF are off (tests/report.rs
/// turns them on): the other tests look at keypoints, angles and cycles.
pub fn run_on(input: &Path, out: &Path) -> Command {
    let mut cmd = gait();
    cmd.args(["run", "--no-progress", "--models-dir"])
        .arg(models_dir())
        .arg("--input")
        .arg(input)
        .arg("--out")
        .arg(out)
        .args(["--set", "report.overlay=false", "--set", "report.pdf=false"]);
    cmd
}

/// `gait run` on frames `first..=last` of the sample video with the test
/// models, writing to `out`.
pub fn sample_run(out: &Path, first: usize, last: usize) -> Command {
    let mut cmd = run_on(&sample_video(), out);
    cmd.args([
        "--set",
        &format!("input.first_frame={first}"),
        "--set",
        &format!("input.last_frame={last}"),
    ]);
    cmd
}

/// `gait run --config <run>/run.json` on the sample video, writing to `out`:
/// a run repeated from its manifest.
pub fn rerun(run: &Path, out: &Path) -> Command {
    let mut cmd = gait();
    cmd.args(["run", "--no-progress", "--models-dir"])
        .arg(models_dir())
        .arg("--config")
        .arg(run.join("run.json"))
        .arg("--input")
        .arg(sample_video())
        .arg("--out")
        .arg(out);
    cmd
}

/// `--set` values that swap in the ControlNet regenerator with the tiny
/// random SD 1.5 + ControlNet of gait-diffuse's fixtures (64x64, 2 steps): the
/// images are noise, but every piece of the wiring is the real one.
pub fn tiny_controlnet_sets() -> Vec<String> {
    let tiny = Path::new(env!("CARGO_MANIFEST_DIR")).join("../gait-diffuse/tests/fixtures/tiny");
    vec![
        "edge.kind=\"canny\"".into(),
        "regenerator.kind=\"controlnet\"".into(),
        "regenerator.resolution=64".into(),
        "regenerator.steps=2".into(),
        format!("regenerator.sd_path={:?}", tiny.display().to_string()),
        format!(
            "regenerator.controlnet_path={:?}",
            tiny.join("controlnet").display().to_string()
        ),
    ]
}

pub fn run_ok(cmd: &mut Command) -> Output {
    let out = cmd.output().expect("gait runs");
    assert!(
        out.status.success(),
        "gait failed: {}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Runs a command that must fail with exit code 2 and one line on stderr
/// containing every one of `needles`.
pub fn fails_with(cmd: &mut Command, needles: &[&str]) -> String {
    let out = cmd.output().expect("gait runs");
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(
        out.status.code(),
        Some(2),
        "expected exit code 2, stderr: {err}"
    );
    let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "expected one line on stderr, got: {err}");
    assert!(lines[0].starts_with("error: "), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "stderr lacks `{n}`: {err}");
    }
    err
}

pub fn read_json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).expect("valid JSON")
}

/// Runs a set-up script of the repository (`tools/...`) with bash; its stdout, trimmed.
pub fn tool_output(script: &str, args: &[&str]) -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let out = Command::new("bash")
        .arg(root.join(script))
        .args(args)
        .output()
        .expect("bash runs");
    assert!(
        out.status.success(),
        "{script}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap().trim().to_string()
}

/// No output file that looks complete in `out` (bad input stopped the run before any).
pub fn assert_no_results(out: &Path) {
    for f in ["keypoints.csv", "run.json"] {
        assert!(
            !out.join(f).exists(),
            "{f} must not exist after a failed run"
        );
    }
}
