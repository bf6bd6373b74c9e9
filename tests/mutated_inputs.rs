//! The command level of the fuzzing promise: `gait kin`, `gait eval`, `gait run` and the
//! corrections of `gait review` on mutated real files (byte flips, truncation, splices, extreme
//! numbers, NaN/inf text; gait-fuzz's mutator, fixed seeds). Each must exit 0 or 2; on 2 with
//! exactly one line on stderr and no panic; and no temporary or partial file may be left.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{gait, models_dir, sample_video};
use gait_fuzz::mutate::{Rng, numbers_only, variant};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Exit 0, or 2 with one `error:` line; never a panic; no leftover temporary files in `out`.
/// Returns the exit code.
fn check(cmd: &mut Command, what: &str, out: &Path) -> i32 {
    let o = cmd.output().expect("gait runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "{what}: {err}");
    match o.status.code() {
        Some(0) => {}
        Some(2) => {
            let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
            let errors: Vec<&&str> = lines.iter().filter(|l| l.starts_with("error: ")).collect();
            assert_eq!(errors.len(), 1, "{what}: {err}");
            assert!(
                lines
                    .iter()
                    .all(|l| l.starts_with("error: ") || l.starts_with("warning: ")),
                "{what}: {err}"
            );
        }
        other => panic!("{what}: exit {other:?}: {err}"),
    }
    let code = o.status.code().unwrap_or(-1);
    if out.is_dir() {
        for e in walk(out) {
            let name = e.file_name().unwrap().to_string_lossy().to_string();
            assert!(
                !(name.starts_with('.') && (name.contains(".tmp") || name.ends_with(".partial"))),
                "{what}: left {}",
                e.display()
            );
        }
    }
    code
}

/// Both outcomes must occur: mutants that still parse and mutants that are refused; otherwise
/// the test would not be testing what it says.
fn both_outcomes(codes: &[i32], what: &str) {
    eprintln!(
        "{what}: {} accepted, {} refused",
        codes.iter().filter(|&&c| c == 0).count(),
        codes.iter().filter(|&&c| c == 2).count()
    );
    assert!(
        codes.contains(&0) && codes.contains(&2),
        "{what}: exit codes {codes:?}"
    );
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut v = Vec::new();
    for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let p = e.path();
        if p.is_dir() {
            v.extend(walk(&p));
        } else {
            v.push(p);
        }
    }
    v
}

/// `n` mutated copies of `seed` written into `dir` as `mutant-K.ext`: every third one with only
/// numbers replaced (extreme, NaN, inf), the others with any mutation.
fn mutants(dir: &Path, seed: &Path, n: usize, rng: u64) -> Vec<PathBuf> {
    let bytes = std::fs::read(seed).unwrap();
    let ext = seed.extension().unwrap().to_string_lossy().to_string();
    let mut r = Rng::new(rng);
    (0..n)
        .map(|k| {
            let p = dir.join(format!("mutant-{k}.{ext}"));
            let m = if k % 3 == 0 {
                numbers_only(&mut r, &bytes)
            } else {
                variant(&mut r, &bytes, &bytes)
            };
            std::fs::write(&p, m).unwrap();
            p
        })
        .collect()
}

#[test]
fn gait_kin_on_mutated_keypoints_and_corrections() {
    let work = tempfile::tempdir().unwrap();
    let seed = repo().join("fuzz/seeds/dlc_csv/walk_frames_100_129.csv");
    let mut codes = Vec::new();
    for (k, file) in mutants(work.path(), &seed, 25, 1).iter().enumerate() {
        let out = work.path().join(format!("kin-{k}"));
        codes.push(check(
            gait()
                .args(["kin", "--fps", "30", "--keypoints"])
                .arg(file)
                .arg("--out")
                .arg(&out)
                .args(["--set", "report.pdf=false"]),
            &format!("gait kin --keypoints {}", file.display()),
            &out,
        ));
    }
    both_outcomes(&codes, "gait kin --keypoints");
    let keypoints = repo().join("tests/data/sample-subject/keypoints.csv");
    let seed = repo().join("fuzz/seeds/corrections/readme_example.toml");
    let mut codes = Vec::new();
    for (k, file) in mutants(work.path(), &seed, 25, 2).iter().enumerate() {
        let out = work.path().join(format!("corr-{k}"));
        codes.push(check(
            gait()
                .args(["kin", "--fps", "30", "--keypoints"])
                .arg(&keypoints)
                .arg("--corrections")
                .arg(file)
                .arg("--out")
                .arg(&out)
                .args(["--set", "report.pdf=false", "--set", "export.formats=[]"]),
            &format!("gait kin --corrections {}", file.display()),
            &out,
        ));
    }
    both_outcomes(&codes, "gait kin --corrections");
}

#[test]
fn gait_eval_on_mutated_truth() {
    let work = tempfile::tempdir().unwrap();
    let pred = repo().join("tests/data/sample-subject/keypoints.csv");
    let seed = repo().join("fuzz/seeds/dlc_csv/walk_frames_100_129.csv");
    let mut codes = Vec::new();
    for (k, file) in mutants(work.path(), &seed, 20, 3).iter().enumerate() {
        let out = work.path().join(format!("eval-{k}"));
        codes.push(check(
            gait()
                .args(["eval", "--truth"])
                .arg(file)
                .arg("--pred")
                .arg(&pred)
                .arg("--out")
                .arg(&out),
            &format!("gait eval --truth {}", file.display()),
            &out,
        ));
    }
    both_outcomes(&codes, "gait eval --truth");
}

#[test]
fn gait_run_on_mutated_configs() {
    let work = tempfile::tempdir().unwrap();
    let seed = repo().join("configs/default.toml");
    let mut codes = Vec::new();
    for (k, file) in mutants(work.path(), &seed, 20, 4).iter().enumerate() {
        let out = work.path().join(format!("run-{k}"));
        codes.push(check(
            gait()
                .arg("--models-dir")
                .arg(models_dir())
                .args(["run", "--no-progress", "--config"])
                .arg(file)
                .arg("--input")
                .arg(sample_video())
                .arg("--out")
                .arg(&out)
                .args([
                    "--set",
                    "input.first_frame=150",
                    "--set",
                    "input.last_frame=151",
                ])
                .args(["--set", "report.pdf=false", "--set", "report.overlay=false"]),
            &format!("gait run --config {}", file.display()),
            &out,
        ));
    }
    both_outcomes(&codes, "gait run --config");
}

/// `gait review` refuses a mutated corrections.toml with one line, or starts (and is stopped).
#[test]
fn gait_review_on_mutated_corrections() {
    let work = tempfile::tempdir().unwrap();
    let keypoints = repo().join("tests/data/sample-subject/keypoints.csv");
    let seed = repo().join("fuzz/seeds/corrections/remove_and_swaps.toml");
    let (mut started, mut refused) = (0, 0);
    // The seed itself first: a review that starts is one of the outcomes checked.
    let files = std::iter::once(seed.clone()).chain(mutants(work.path(), &seed, 15, 5));
    for file in files {
        let mut child = gait()
            .args(["review", "--fps", "30", "--keypoints"])
            .arg(&keypoints)
            .arg("--corrections")
            .arg(&file)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let mut line = String::new();
        use std::io::BufRead;
        let got = std::io::BufReader::new(child.stdout.take().unwrap()).read_line(&mut line);
        if got.is_ok_and(|n| n > 0) {
            assert!(line.starts_with("http://127.0.0.1:"), "{line}");
            let _ = child.kill();
            let _ = child.wait();
            started += 1;
            continue;
        }
        refused += 1;
        let o = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{}: {err}", file.display());
        let errors = err.lines().filter(|l| l.starts_with("error: ")).count();
        assert_eq!(errors, 1, "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    eprintln!("gait review --corrections: {started} started, {refused} refused");
    assert!(
        started > 0 && refused > 0,
        "{started} started, {refused} refused"
    );
}
