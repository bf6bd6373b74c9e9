//! `gait models`: Hub downloads fail cleanly without a reachable Hub, and the
//! list reports what is missing.

mod common;

use common::{fails_with, gait, run_ok};
use std::path::Path;
use std::process::Command;

/// An endpoint that refuses connections: a port that was just free on the
/// loopback (so the test never downloads, with or without network).
fn closed_endpoint() -> String {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    drop(listener);
    format!("http://127.0.0.1:{port}")
}

fn fetch(models: &Path, endpoint: &str, args: &[&str]) -> Command {
    let mut cmd = gait();
    cmd.args(["models", "fetch"])
        .args(args)
        .arg("--models-dir")
        .arg(models)
        .env("HF_ENDPOINT", endpoint)
        .env("HF_HOME", models.join("no-hf-home"))
        .env_remove("HF_TOKEN");
    cmd
}

fn assert_empty(dir: &Path) {
    let left: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");
}

#[test]
fn hed_without_hub_names_the_file_and_where_it_goes() {
    let dir = tempfile::tempdir().unwrap();
    let endpoint = closed_endpoint();
    let dest = dir.path().join("ControlNetHED.pth");
    let url = format!("{endpoint}/lllyasviel/Annotators/resolve/main/ControlNetHED.pth");
    let err = fails_with(
        &mut fetch(dir.path(), &endpoint, &["hed"]),
        &[
            "cannot reach the Hugging Face Hub",
            &endpoint,
            &format!("download ControlNetHED.pth from {url}"),
            &format!("put it at {}", dest.display()),
        ],
    );
    assert!(!err.contains("; download"), "one file only: {err}");
    assert_empty(dir.path());
}

#[test]
fn sd15_without_hub_lists_every_file() {
    let dir = tempfile::tempdir().unwrap();
    let endpoint = closed_endpoint();
    let sd = dir.path().join("stable-diffusion-v1-5");
    let cn = dir.path().join("sd-controlnet-canny");
    let unet = format!(
        "{endpoint}/stable-diffusion-v1-5/stable-diffusion-v1-5/resolve/main/unet/diffusion_pytorch_model.safetensors"
    );
    let controlnet = format!(
        "{endpoint}/lllyasviel/sd-controlnet-canny/resolve/main/diffusion_pytorch_model.safetensors"
    );
    let mut needles = vec![unet, controlnet];
    for f in [
        "unet/config.json",
        "unet/diffusion_pytorch_model.safetensors",
        "vae/config.json",
        "vae/diffusion_pytorch_model.safetensors",
        "text_encoder/config.json",
        "text_encoder/model.safetensors",
        "tokenizer/merges.txt",
    ] {
        needles.push(format!("put it at {}", sd.join(f).display()));
    }
    for f in ["config.json", "diffusion_pytorch_model.safetensors"] {
        needles.push(format!("put it at {}", cn.join(f).display()));
    }
    let needles: Vec<&str> = needles.iter().map(String::as_str).collect();
    fails_with(
        &mut fetch(dir.path(), &endpoint, &["sd15-controlnet-canny"]),
        &needles,
    );
    assert_empty(dir.path());
}

#[test]
fn repo_and_revision_flags_change_the_source() {
    let dir = tempfile::tempdir().unwrap();
    let endpoint = closed_endpoint();
    fails_with(
        &mut fetch(
            dir.path(),
            &endpoint,
            &[
                "sd15-controlnet-canny",
                "--repo",
                "runwayml/stable-diffusion-v1-5",
                "--revision",
                "fp16",
                "--controlnet-repo",
                "someone/my-canny",
                "--controlnet-revision",
                "v2",
            ],
        ),
        &[
            &format!("{endpoint}/runwayml/stable-diffusion-v1-5/resolve/fp16/vae/config.json"),
            &format!("{endpoint}/someone/my-canny/resolve/v2/config.json"),
        ],
    );
    fails_with(
        &mut fetch(dir.path(), &endpoint, &["hed", "--controlnet-repo", "a/b"]),
        &["--controlnet-repo", "sd15-controlnet-canny only", "hed"],
    );
    fails_with(
        &mut fetch(dir.path(), &endpoint, &["blazepose", "--repo", "a/b"]),
        &["blazepose", "does not come from the Hugging Face Hub"],
    );
    assert_empty(dir.path());
}

#[test]
fn openpose_without_hub_says_where_the_checkpoint_goes() {
    let dir = tempfile::tempdir().unwrap();
    let endpoint = closed_endpoint();
    let dest = dir.path().join("openpose").join("body_pose_model.pth");
    fails_with(
        &mut fetch(dir.path(), &endpoint, &["openpose"]),
        &[
            "cannot reach the Hugging Face Hub",
            &format!(
                "download body_pose_model.pth from {endpoint}/lllyasviel/Annotators/resolve/main/body_pose_model.pth"
            ),
            &format!("put it at {}", dest.display()),
        ],
    );
    // Another repository and file: still saved where the estimator looks.
    fails_with(
        &mut fetch(
            dir.path(),
            &endpoint,
            &["openpose", "--repo", "me/poses", "--file", "body/coco.pth"],
        ),
        &[
            &format!("download coco.pth from {endpoint}/me/poses/resolve/main/body/coco.pth"),
            &format!("put it at {}", dest.display()),
        ],
    );
    fails_with(
        &mut fetch(
            dir.path(),
            &endpoint,
            &["sd15-controlnet-canny", "--file", "x.safetensors"],
        ),
        &["--file", "single-file models", "sd15-controlnet-canny"],
    );
    assert_empty(dir.path());
}

#[test]
fn missing_models_folder_is_not_created() {
    let dir = tempfile::tempdir().unwrap();
    let models = dir.path().join("models");
    fails_with(
        &mut fetch(&models, &closed_endpoint(), &["hed"]),
        &["cannot reach the Hugging Face Hub", "ControlNetHED.pth"],
    );
    assert!(!models.exists());
}

#[test]
fn list_shows_hub_models_missing_then_present() {
    let dir = tempfile::tempdir().unwrap();
    let list = |dir: &Path| {
        let out = run_ok(gait().args(["models", "list", "--models-dir"]).arg(dir));
        String::from_utf8_lossy(&out.stdout).to_string()
    };
    let line = |text: &str, name: &str| -> String {
        text.lines()
            .find(|l| l.split_whitespace().next() == Some(name))
            .unwrap_or_else(|| panic!("no `{name}` line in:\n{text}"))
            .to_string()
    };
    let before = list(dir.path());
    for name in ["hed", "openpose", "sd15-controlnet-canny"] {
        assert!(line(&before, name).contains(" missing "), "{before}");
    }
    // A file put by hand (the manual route of the error above) counts.
    std::fs::write(dir.path().join("ControlNetHED.pth"), b"weights").unwrap();
    let after = list(dir.path());
    assert!(line(&after, "hed").contains(" present "), "{after}");
    assert!(
        line(&after, "sd15-controlnet-canny").contains(" missing "),
        "{after}"
    );
}

/// Present and valid BlazePose files are checked and left alone; `--force` is what fetches
/// them again (here from the wheel in the folder, so no network is needed).
#[test]
fn blazepose_present_is_checked_not_rewritten() {
    let dir = tempfile::tempdir().unwrap();
    let src = common::models_dir().join("blazepose");
    let dst = dir.path().join("blazepose");
    std::fs::create_dir_all(&dst).unwrap();
    let files = [
        "pose_detection.tflite",
        "pose_landmark_full.tflite",
        "selfie_segmentation.tflite",
        "pose_detection.onnx",
        "pose_landmark_full.onnx",
    ];
    for f in files {
        std::fs::copy(src.join(f), dst.join(f)).unwrap();
    }
    let stamp = |f: &str| std::fs::metadata(dst.join(f)).unwrap().modified().unwrap();
    let before: Vec<_> = files.iter().map(|f| stamp(f)).collect();
    let out = run_ok(&mut fetch(dir.path(), &closed_endpoint(), &["blazepose"]));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("present and checked") && err.contains("--force"),
        "{err}"
    );
    let after: Vec<_> = files.iter().map(|f| stamp(f)).collect();
    assert_eq!(before, after, "present files were rewritten");
    assert!(!dst.join("wheel").exists(), "nothing was downloaded");

    // A damaged file is named and fetched again; with the wheel at hand no network is needed.
    let wheel = dst.join("wheel");
    std::fs::create_dir_all(&wheel).unwrap();
    let name = gait_pose::blazepose::fetch::WHEEL_NAME;
    std::fs::copy(src.join("wheel").join(name), wheel.join(name)).unwrap();
    std::fs::write(dst.join("pose_landmark_full.onnx"), b"broken").unwrap();
    let out = run_ok(&mut fetch(dir.path(), &closed_endpoint(), &["blazepose"]));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("pose_landmark_full.onnx") && err.contains("fetching again"),
        "{err}"
    );
    let out = run_ok(&mut fetch(dir.path(), &closed_endpoint(), &["blazepose"]));
    assert!(String::from_utf8_lossy(&out.stderr).contains("present and checked"));
    let out = run_ok(&mut fetch(
        dir.path(),
        &closed_endpoint(),
        &["blazepose", "--force"],
    ));
    assert!(!String::from_utf8_lossy(&out.stderr).contains("present and checked"));
}
