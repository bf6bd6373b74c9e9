//! Bad input gives one clear line on stderr, exit code 2, no panic, and no
//! output file that looks complete.

mod common;

use common::{assert_no_results, fails_with, gait};
use std::path::Path;

#[test]
fn missing_video() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    fails_with(
        gait()
            .args(["run", "--no-progress", "--input"])
            .arg(dir.path().join("nope.mp4"))
            .arg("--out")
            .arg(&out),
        &["nope.mp4", "no such file"],
    );
    assert_no_results(&out);
}

#[test]
fn corrupt_video() {
    let dir = tempfile::tempdir().unwrap();
    let video = dir.path().join("broken.mp4");
    std::fs::write(&video, b"this is not a video at all, just text pretending").unwrap();
    let out = dir.path().join("out");
    fails_with(
        gait()
            .args(["run", "--no-progress", "--input"])
            .arg(&video)
            .arg("--out")
            .arg(&out),
        &["broken.mp4", "not a readable video"],
    );
    assert_no_results(&out);
}

#[test]
fn truncated_video() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = std::fs::read(common::sample_video()).unwrap();
    let video = dir.path().join("cut.mp4");
    std::fs::write(&video, &bytes[..bytes.len() / 50]).unwrap();
    let out = dir.path().join("out");
    let out_status = gait()
        .args(["run", "--no-progress", "--input"])
        .arg(&video)
        .arg("--out")
        .arg(&out)
        .env("GAIT_MODELS_DIR", dir.path())
        .output()
        .unwrap();
    // Either the container is unreadable or the model is missing; both are
    // one-line errors with exit code 2 and no results.
    assert_eq!(out_status.status.code(), Some(2));
    assert!(!String::from_utf8_lossy(&out_status.stderr).contains("panicked"));
    assert_no_results(&out);
}

#[test]
fn empty_folder() {
    let dir = tempfile::tempdir().unwrap();
    let frames = dir.path().join("frames");
    std::fs::create_dir(&frames).unwrap();
    fails_with(
        gait()
            .args(["run", "--no-progress", "--input"])
            .arg(&frames)
            .arg("--out")
            .arg(dir.path().join("out")),
        &["frames", "no images"],
    );
}

#[test]
fn unreadable_image() {
    let dir = tempfile::tempdir().unwrap();
    let img = dir.path().join("frame.png");
    std::fs::write(&img, b"\x89PNG but not really").unwrap();
    fails_with(
        gait()
            .args(["run", "--no-progress", "--input"])
            .arg(&img)
            .arg("--out")
            .arg(dir.path().join("out")),
        &["frame.png", "unreadable image"],
    );
}

/// A real JPEG (tests/data/jpeg) cut short or corrupt, alone or as one frame of a folder: one
/// line naming the file, before anything runs.
#[test]
fn broken_jpegs_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let whole = std::fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/jpeg/hopper.jpg"),
    )
    .unwrap();
    let cut = dir.path().join("cut.jpg");
    std::fs::write(&cut, &whole[..whole.len() / 2]).unwrap();
    let frames = dir.path().join("frames");
    std::fs::create_dir(&frames).unwrap();
    for (name, bytes) in [
        ("f1.jpg", whole.clone()),
        ("f2.jpg", [&whole[..4], &[0x55u8; 64][..]].concat()),
        ("f3.jpg", whole.clone()),
    ] {
        std::fs::write(frames.join(name), bytes).unwrap();
    }
    for (input, needles) in [
        (&cut, &["cut.jpg", "cut short"][..]),
        (&frames, &["f2.jpg", "not a readable JPEG"][..]),
    ] {
        let out = dir.path().join("out");
        fails_with(
            gait()
                .args(["run", "--no-progress", "--input"])
                .arg(input)
                .arg("--out")
                .arg(&out),
            needles,
        );
        assert_no_results(&out);
    }
}

/// `[run] device = "cuda"` in a build without the `cuda` feature: one line
/// saying how to get a GPU build, before any model is loaded.
#[cfg(not(feature = "cuda"))]
#[test]
fn cuda_device_without_a_cuda_build() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    // candle on a GPU needs the `cuda` feature; fails before any model loads.
    let mut cmd = common::sample_run(&out, 150, 151);
    for s in common::tiny_controlnet_sets() {
        cmd.args(["--set", &s]);
    }
    let err = fails_with(
        cmd.args(["--set", "run.device=cuda"]),
        &["this build has no CUDA support: rebuild with `--features cuda` (README, GPU section)"],
    );
    assert!(!err.contains("model"), "{err}");
    assert_no_results(&out);

    // The default pipeline has no stage that runs on a GPU.
    fails_with(
        common::sample_run(&out, 150, 151).args(["--set", "run.device=cuda:1"]),
        &["[run]", "cuda:1", "no stage", "run.device = \"cpu\""],
    );
    assert_no_results(&out);

    // ONNX Runtime stages ask the runtime for CUDA, which the CPU wheel lacks.
    fails_with(
        common::sample_run(&out, 150, 151).args([
            "--set",
            "run.device=cuda",
            "--set",
            "pose.backend=ort",
        ]),
        &["CUDA", "onnxruntime-gpu"],
    );
    assert_no_results(&out);
}

/// A folder of `n` images: blank grey, or frames of the sample video.
fn image_folder(dir: &Path, n: usize, sample: bool) -> std::path::PathBuf {
    let folder = dir.join("frames");
    std::fs::create_dir_all(&folder).unwrap();
    let frames: Vec<image::RgbImage> = if sample {
        let info = gait_pipeline::input::InputInfo::open(&common::sample_video()).unwrap();
        let mut reader = info.frames().unwrap();
        (0..n)
            .map(|_| reader.next_frame().unwrap().unwrap().image)
            .collect()
    } else {
        vec![image::RgbImage::from_pixel(320, 240, image::Rgb([128, 128, 128])); n]
    };
    for (i, f) in frames.iter().enumerate() {
        f.save(folder.join(format!("{i:03}.png"))).unwrap();
    }
    folder
}

fn run_on(folder: &Path, out: &Path, sets: &[&str]) -> std::process::Command {
    let mut cmd = common::run_on(folder, out);
    for s in sets {
        cmd.args(["--set", s]);
    }
    cmd
}

#[test]
fn nobody_in_any_frame() {
    let dir = tempfile::tempdir().unwrap();
    let folder = image_folder(dir.path(), 3, false);
    let out = dir.path().join("out");
    fails_with(
        &mut run_on(&folder, &out, &[]),
        &["no person was found in any frame"],
    );
    assert_no_results(&out);
}

#[test]
fn a_subject_point_outside_the_frame_or_the_input() {
    let dir = tempfile::tempdir().unwrap();
    let folder = image_folder(dir.path(), 3, true);
    let out = dir.path().join("out");
    fails_with(
        &mut run_on(
            &folder,
            &out,
            &["pose.person={ frame = 1, x = 5000, y = 10 }"],
        ),
        &["pose.person", "(5000, 10)", "outside the 1768x994 frame"],
    );
    fails_with(
        &mut run_on(
            &folder,
            &out,
            &["pose.person={ frame = 40, x = 500, y = 500 }"],
        ),
        &["pose.person", "frame 40", "not in the analysed frames 0-2"],
    );
    assert_no_results(&out);
}

#[test]
fn nobody_walking_still_completes_and_says_so() {
    // The first 12 frames: only the man on the box is in view, standing.
    let dir = tempfile::tempdir().unwrap();
    let folder = image_folder(dir.path(), 12, true);
    let out = dir.path().join("out");
    let done = common::run_ok(&mut run_on(&folder, &out, &[]));
    let err = String::from_utf8_lossy(&done.stderr);
    assert!(err.contains("no result: no walking bout found"), "{err}");
    assert!(
        err.lines()
            .filter(|l| l.contains("complete cycles"))
            .count()
            <= 1,
        "one line for the missing cycles: {err}"
    );
    let run = common::read_json(&out.join("run.json"));
    assert_eq!(run["status"], "no_result", "{}", run["status"]);
    assert_eq!(run["reason"], "no walking bout found");
    assert_eq!(
        run["subject"]["walking"],
        serde_json::json!(false),
        "{}",
        run["subject"]
    );
    assert!(
        run["extra"]["kinematics"]["bouts"]
            .as_array()
            .unwrap()
            .is_empty()
    );
    let report = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(
        report.contains("No walking bout found"),
        "the report says so"
    );
}

#[test]
fn a_range_past_the_end_of_the_video() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    fails_with(
        &mut run_on(&common::sample_video(), &out, &["input.first_frame=5000"]),
        &[
            "no frames in the selected range",
            "first_frame = 5000",
            "the input has 230 frames (0 to 229)",
        ],
    );
    assert_no_results(&out);
    assert!(!out.exists(), "a failed run left an empty folder behind");
}

/// The walker seen for 1.2 s only (frames 150-192 of the sample): a walking bout, but no foot
/// strikes twice in it. Before, the run said "no complete gait cycle accepted (0 rejected)",
/// which named nothing to change.
#[test]
fn a_walk_too_short_for_a_stride_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let done =
        common::run_ok(common::sample_run(&out, 150, 192).args(["--set", "report.overlay=false"]));
    let err = String::from_utf8_lossy(&done.stderr);
    assert!(
        err.contains("no result: no complete gait cycle: no foot has two heel strikes within a walking bout (frames 150-")
            && err.contains("seen for a whole stride"),
        "{err}"
    );
    let run = common::read_json(&out.join("run.json"));
    assert_eq!(run["status"], "no_result", "{}", run["status"]);
}
