//! `gait batch` end to end on three short clips cut from the sample video and one corrupt file:
//! the local executor and a real one-node Slurm (Debian's slurmctld/slurmd/munge, started by
//! tools/batch/slurm.sh) give the same keypoints and angles as a plain `gait run`; a corrupt
//! video fails alone; a cancelled batch reruns only its unfinished rows; a video's regeneration
//! spread over array tasks gives a byte-identical run; bad studies are refused before anything
//! is submitted.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use common::{fails_with, gait, models_dir, run_ok, sample_video};

/// tools/batch/slurm.sh up (idempotent): the path of the cluster's slurm.conf.
fn slurm_conf() -> &'static str {
    static CONF: OnceLock<String> = OnceLock::new();
    CONF.get_or_init(|| {
        let text = common::tool_output("tools/batch/slurm.sh", &["up"]);
        text.strip_prefix("SLURM_CONF=").unwrap().to_string()
    })
}

/// `frames` frames of the sample from `start` seconds, re-encoded (H.264) into `out`.
fn cut(start: &str, frames: &str, out: &Path) {
    let status = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-ss", start, "-i"])
        .arg(sample_video())
        .args([
            "-frames:v",
            frames,
            "-an",
            "-c:v",
            "libx264",
            "-preset",
            "veryfast",
        ])
        .args(["-pix_fmt", "yuv420p"])
        .arg(out)
        .status()
        .unwrap();
    assert!(status.success());
}

/// Three clips of the sample, each with the walker's whole walk (two cycles a side at least,
/// so the cohort has curves), and a truncated copy, with a study file.
fn clips() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap().keep();
        for (name, start, frames) in [
            ("a", "1.9", "140"),
            ("b", "2.0", "135"),
            ("c", "1.8", "145"),
        ] {
            let out = dir.join(format!("clip_{name}.mp4"));
            cut(start, frames, &out);
        }
        let bytes = std::fs::read(dir.join("clip_a.mp4")).unwrap();
        std::fs::write(dir.join("corrupt.mp4"), &bytes[..20_000]).unwrap();
        std::fs::write(
            dir.join("study.csv"),
            "video,subject,session,view,prosthetic_side,config,set\n\
             clip_a.mp4,S01,1,left,right,,report.pdf=false;report.overlay=false\n\
             clip_b.mp4,S01,2,left,right,,report.pdf=false;report.overlay=false\n\
             clip_c.mp4,S02,1,left,,,report.pdf=false;report.overlay=false\n\
             corrupt.mp4,S03,1,left,,,report.pdf=false\n",
        )
        .unwrap();
        dir
    })
}

const GOOD: [&str; 3] = [
    "S01_1_left_clip_a",
    "S01_2_left_clip_b",
    "S02_1_left_clip_c",
];

fn batch(study: &Path, out: &Path, extra: &[&str]) -> Command {
    let mut cmd = gait();
    cmd.arg("--models-dir")
        .arg(models_dir())
        .arg("batch")
        .arg(study)
        .arg("--out")
        .arg(out)
        .args(extra)
        .env("SLURM_CONF", slurm_conf());
    cmd
}

fn code(out: &Output) -> Option<i32> {
    out.status.code()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).to_string()
}

/// The local batch of the study, run once for the tests that compare with it.
fn local_batch() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let out = tempfile::tempdir().unwrap().keep().join("local");
        let done = batch(&clips().join("study.csv"), &out, &["--jobs", "2"])
            .output()
            .unwrap();
        assert_eq!(code(&done), Some(3), "{}", stderr(&done));
        out
    })
}

fn same_results(a: &Path, b: &Path) {
    for f in ["keypoints.csv", "angles.csv", "events.csv", "cycles.csv"] {
        let (x, y) = (
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
        );
        assert!(
            x == y,
            "{f} differs between {} and {}",
            a.display(),
            b.display()
        );
    }
}

fn cohort(out: &Path) -> Vec<Vec<String>> {
    let mut r = csv::Reader::from_path(out.join("cohort.csv")).unwrap();
    r.records()
        .map(|rec| rec.unwrap().iter().map(String::from).collect())
        .collect()
}

#[test]
fn local_and_slurm_give_what_gait_run_gives_and_a_corrupt_video_fails_alone() {
    let local = local_batch();
    // A plain `gait run` of the first clip with the row's settings.
    let plain = tempfile::tempdir().unwrap();
    run_ok(
        gait()
            .arg("--models-dir")
            .arg(models_dir())
            .args(["run", "--no-progress", "--input"])
            .arg(clips().join("clip_a.mp4"))
            .arg("--out")
            .arg(plain.path())
            .args(["--set", "report.pdf=false", "--set", "report.overlay=false"])
            .args(["--set", "kinematics.prosthetic_side=\"right\""]),
    );
    same_results(&local.join("runs").join(GOOD[0]), plain.path());

    let slurm = tempfile::tempdir().unwrap();
    let done = batch(
        &clips().join("study.csv"),
        slurm.path(),
        &["--executor", "slurm", "--wait"],
    )
    .output()
    .unwrap();
    assert_eq!(code(&done), Some(3), "{}", stderr(&done));
    for run in GOOD {
        same_results(
            &local.join("runs").join(run),
            &slurm.path().join("runs").join(run),
        );
    }
    assert!(slurm.path().join("logs").read_dir().unwrap().count() >= 4);
    let jobs: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(slurm.path().join("batch/jobs.json")).unwrap(),
    )
    .unwrap();
    assert!(jobs["aggregate"].as_str().is_some(), "{jobs}");

    for out in [local, slurm.path()] {
        let rows = cohort(out);
        // Two sides for each video that ran, one row with the error for the corrupt one.
        assert_eq!(rows.len(), 7, "{rows:?}");
        let failed: Vec<&Vec<String>> = rows.iter().filter(|r| r[7] == "failed").collect();
        assert_eq!(failed.len(), 1);
        assert_eq!(failed[0][4], "S03_1_left_corrupt");
        assert!(
            failed[0][8].contains("not a readable video"),
            "{:?}",
            failed[0]
        );
        assert_eq!(rows.iter().filter(|r| r[7] == "done").count(), 6);
        // The prosthetic side is marked where the row set it.
        assert!(
            rows.iter()
                .any(|r| r[4] == GOOD[0] && r[5] == "right" && r[6] == "yes")
        );
        let html = std::fs::read_to_string(out.join("cohort.html")).unwrap();
        assert!(
            html.contains("Group: mean ± SD across") && html.contains("<svg"),
            "cohort.html"
        );
        assert!(html.contains("S03_1_left_corrupt"));
        // Each subject's session is a visit (issue 39): its report and checklist beside the
        // rows; the failed row's visit is not written.
        for visit in ["S01_1", "S01_2", "S02_1"] {
            let dir = out.join("visits").join(visit);
            let page = std::fs::read_to_string(dir.join("report.html")).unwrap();
            assert!(page.contains("Amputee gait-deviation checklist"), "{visit}");
            // The pass is named with where each side's curves came from (these clips' left
            // limbs have one accepted cycle, under min_cycles, so the left curves say none).
            assert!(
                page.contains("left view (clip_") && page.contains("sagittal curves:"),
                "{visit}"
            );
            assert!(dir.join("visit_checklist.csv").is_file(), "{visit}");
        }
        assert!(!out.join("visits/S03_1").exists());
        // S01's two sessions: its progress, linked from the cohort page with the visits.
        assert!(out.join("progress/S01/progress.html").is_file());
        assert!(
            html.contains("Visits and progress") && html.contains("progress/S01/progress.html")
        );
        let status = gait()
            .args(["batch", "status"])
            .arg(out)
            .env("SLURM_CONF", slurm_conf())
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&status.stdout);
        assert_eq!(text.matches(" done ").count(), 3, "{text}");
        assert!(
            text.contains("failed") && text.contains("moov atom"),
            "{text}"
        );
    }
}

#[test]
fn a_cancelled_batch_reruns_only_its_unfinished_rows() {
    let out = tempfile::tempdir().unwrap();
    let study = out.path().join("study.csv");
    let text = std::fs::read_to_string(clips().join("study.csv")).unwrap();
    // The good rows only, one task at a time, so that the cancel finds some done and some not.
    let rows: Vec<&str> = text.lines().take(4).collect();
    std::fs::write(&study, rows.join("\n") + "\n").unwrap();
    for clip in ["clip_a.mp4", "clip_b.mp4", "clip_c.mp4"] {
        std::fs::copy(clips().join(clip), out.path().join(clip)).unwrap();
    }
    let dir = out.path().join("batch");
    let submitted = batch(&study, &dir, &["--executor", "slurm", "--jobs", "1"])
        .output()
        .unwrap();
    assert_eq!(code(&submitted), Some(0), "{}", stderr(&submitted));
    let ids: Vec<String> = String::from_utf8_lossy(&submitted.stdout)
        .split_whitespace()
        .map(String::from)
        .collect();
    assert_eq!(ids.len(), 2, "{ids:?}");
    let first_done = dir.join("runs").join(GOOD[0]).join("report.html");
    let t = Instant::now();
    while !first_done.exists() {
        assert!(
            t.elapsed() < Duration::from_secs(300),
            "the first row never finished"
        );
        std::thread::sleep(Duration::from_millis(200));
    }
    let cancelled = Command::new("scancel")
        .args(&ids)
        .env("SLURM_CONF", slurm_conf())
        .status()
        .unwrap();
    assert!(cancelled.success());
    let t = Instant::now();
    loop {
        let q = Command::new("squeue")
            .args(["-h", "-j", &ids.join(",")])
            .env("SLURM_CONF", slurm_conf())
            .output()
            .unwrap();
        if String::from_utf8_lossy(&q.stdout).trim().is_empty() {
            break;
        }
        assert!(
            t.elapsed() < Duration::from_secs(60),
            "scancel left jobs in the queue"
        );
        std::thread::sleep(Duration::from_millis(300));
    }
    let again = batch(&study, &dir, &["--executor", "slurm", "--wait"])
        .output()
        .unwrap();
    let err = stderr(&again);
    assert_eq!(code(&again), Some(0), "{err}");
    // Only what had not finished ran again (the first row at least was complete).
    let complete: usize = err
        .split(" complete already")
        .next()
        .and_then(|s| s.rsplit(", ").next())
        .and_then(|s| s.trim().parse().ok())
        .unwrap_or_else(|| panic!("{err}"));
    assert!((1..3).contains(&complete), "{err}");
    for run in GOOD {
        same_results(
            &local_batch().join("runs").join(run),
            &dir.join("runs").join(run),
        );
    }
}

/// `--split-frames 3` with the tiny random SD 1.5 + ControlNet of gait-diffuse's fixtures: the
/// regeneration spread over three array tasks, then the poses from the shared cache.
#[test]
fn a_video_split_over_array_tasks_gives_the_unsplit_run() {
    let work = tempfile::tempdir().unwrap();
    let clip = work.path().join("clip.mp4");
    cut("4.0", "9", &clip);
    let mut sets: Vec<String> = common::tiny_controlnet_sets();
    sets.extend(["report.pdf=false".into(), "report.overlay=false".into()]);
    let study = work.path().join("study.toml");
    std::fs::write(
        &study,
        format!(
            "[[row]]\nvideo = \"clip.mp4\"\nsubject = \"S01\"\nview = \"left\"\nset = '{}'\n",
            sets.join(";")
        ),
    )
    .unwrap();
    let split = work.path().join("split");
    let done = batch(
        &study,
        &split,
        &["--executor", "slurm", "--split-frames", "3", "--wait"],
    )
    .output()
    .unwrap();
    assert_eq!(code(&done), Some(0), "{}", stderr(&done));
    let jobs: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(split.join("batch/jobs.json")).unwrap())
            .unwrap();
    assert_eq!(
        jobs["parts"][0]["indices"],
        serde_json::json!([0, 1, 2]),
        "{jobs}"
    );
    let run = split.join("runs/S01_left_clip");
    let manifest = common::read_json(&run.join("run.json"));
    // Every image came from the parts: the last task only estimated poses.
    assert_eq!(
        manifest["stages"]["regenerator"]["computed"], 0,
        "{manifest}"
    );
    assert!(
        manifest["stages"]["regenerator"]["cached"]
            .as_u64()
            .unwrap()
            > 0
    );

    let plain = work.path().join("plain");
    let mut cmd = gait();
    cmd.arg("--models-dir")
        .arg(models_dir())
        .args(["run", "--no-progress", "--input"])
        .arg(&clip)
        .arg("--out")
        .arg(&plain);
    for s in &sets {
        cmd.args(["--set", s]);
    }
    run_ok(&mut cmd);
    let unsplit = common::read_json(&plain.join("run.json"));
    assert_eq!(
        unsplit["stages"]["regenerator"]["computed"],
        manifest["stages"]["regenerator"]["cached"]
    );
    same_results(&run, &plain);
}

#[test]
fn bad_studies_are_refused_before_anything_runs() {
    let work = tempfile::tempdir().unwrap();
    std::fs::copy(clips().join("clip_a.mp4"), work.path().join("clip_a.mp4")).unwrap();
    let study = work.path().join("study.csv");
    std::fs::write(
        &study,
        "video,subject,session,view,prosthetic_side,config,set\n\
         clip_a.mp4,S01,1,left,,,\n\
         missing.mp4,S02,1,left,,,\n\
         clip_a.mp4,S03,1,left,,,pose.colour=1\n\
         clip_a.mp4,S01,1,left,,,report.pdf=false\n\
         clip_a.mp4,S04,1,sideways,,,\n\
         clip_a.mp4,S05,1,left,left,,\n\
         clip_a.mp4,S05,1,right,right,,\n",
    )
    .unwrap();
    let out = work.path().join("out");
    let err = fails_with(
        &mut batch(&study, &out, &[]),
        &[
            "5 bad row(s), nothing submitted",
            "row 2 (missing.mp4)",
            "not found",
            "row 3",
            "colour",
            "row 4",
            "same run folder `S01_1_left_clip_a` as row 1",
            "row 5",
            "sideways",
            "the visit of subject S05 session 1 (row 6, row 7): its rows differ in prosthetic side",
        ],
    );
    assert!(!err.contains("row 1 "), "{err}");
    assert!(!out.exists(), "a refused study wrote {}", out.display());

    // Slurm asked for, but no sbatch on the PATH.
    let good = work.path().join("good.csv");
    std::fs::write(
        &good,
        "video,subject,session,view,prosthetic_side,config,set\nclip_a.mp4,S01,1,left,,,\n",
    )
    .unwrap();
    let empty = work.path().join("empty-bin");
    std::fs::create_dir_all(&empty).unwrap();
    fails_with(
        batch(&good, &out, &["--executor", "slurm"]).env("PATH", &empty),
        &["sbatch", "--executor local"],
    );
    fails_with(
        &mut batch(&work.path().join("none.csv"), &out, &[]),
        &["none.csv", "cannot read the study file"],
    );
    fails_with(
        gait().args(["batch", "status"]).arg(work.path()),
        &["not a batch folder"],
    );
}

/// A row whose run completes without a walking bout is "no result: REASON" in `gait batch
/// status` and the cohort table, not "done"; the batch still exits 0 (nothing failed) and says
/// how many rows are empty. Local executor only: no Slurm needed.
#[test]
fn a_run_without_walking_is_no_result_not_done() {
    let dir = tempfile::tempdir().unwrap();
    // The first 12 frames: only the man on the box is in view, standing.
    cut("0", "12", &dir.path().join("standing.mp4"));
    let study = dir.path().join("study.csv");
    std::fs::write(
        &study,
        "video,subject,session,view,prosthetic_side,config,set\n\
         standing.mp4,S09,1,left,,,report.pdf=false;report.overlay=false\n",
    )
    .unwrap();
    let out = dir.path().join("study");
    let mut cmd = gait();
    cmd.arg("--models-dir")
        .arg(models_dir())
        .arg("batch")
        .arg(&study)
        .arg("--out")
        .arg(&out);
    let done = run_ok(&mut cmd);
    assert!(
        stderr(&done).contains("1 with no result"),
        "{}",
        stderr(&done)
    );
    let status = run_ok(gait().args(["batch", "status"]).arg(&out));
    let text = String::from_utf8_lossy(&status.stdout);
    assert!(
        text.contains("no result") && text.contains("no result: no walking bout found"),
        "{text}"
    );
    assert!(!text.contains(" done "), "{text}");
    let cohort = std::fs::read_to_string(out.join("cohort.csv")).unwrap();
    assert!(
        cohort.contains("no result") && cohort.contains("no walking bout found"),
        "{cohort}"
    );
    let html = std::fs::read_to_string(out.join("cohort.html")).unwrap();
    assert!(html.contains("1 without results"), "{html}");
}
