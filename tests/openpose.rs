//! OpenPose as the pose stage of `gait run`, end to end on the sample video.
//! The real weights cannot be downloaded here, so the checkpoint is written in
//! the real layout (every tensor name and shape of body_pose_model.pth) with
//! made-up values: this checks the wiring, not the detections (the network
//! and the decoding are checked against controlnet_aux in gait-pose's tests).

mod common;

use common::{gait, read_json, run_ok, sample_video};
use std::path::Path;

/// A safetensors file with the COCO-18 checkpoint's names and shapes and
/// small deterministic values.
fn write_checkpoint(path: &Path) {
    let layout = gait_pose::openpose::net::coco18_layout();
    let mut header = serde_json::Map::new();
    let mut offset = 0usize;
    for (name, shape) in &layout {
        let len = shape.iter().product::<usize>() * 4;
        header.insert(
            name.clone(),
            serde_json::json!({"dtype": "F32", "shape": shape, "data_offsets": [offset, offset + len]}),
        );
        offset += len;
    }
    let header = serde_json::to_vec(&header).unwrap();
    let mut bytes = Vec::with_capacity(8 + header.len() + offset);
    bytes.extend_from_slice(&(header.len() as u64).to_le_bytes());
    bytes.extend_from_slice(&header);
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    while bytes.len() < 8 + header.len() + offset {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let v = ((state >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * 0.02;
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::write(path, bytes).unwrap();
}

#[test]
fn openpose_runs_as_the_pose_stage() {
    let dir = tempfile::tempdir().unwrap();
    let models = dir.path().join("models");
    std::fs::create_dir_all(models.join("openpose")).unwrap();
    write_checkpoint(&models.join("openpose/body_pose_model.pth.safetensors"));
    let out = dir.path().join("run");
    run_ok(
        gait()
            .args(["run", "--no-progress", "--models-dir"])
            .arg(&models)
            .arg("--input")
            .arg(sample_video())
            .args([
                "--set",
                "pose.kind=openpose",
                "--set",
                "pose.model_path=openpose/body_pose_model.pth.safetensors",
                "--set",
                "input.first_frame=150",
                "--set",
                "input.last_frame=151",
                // Random weights find nobody, which the subject pass rightly
                // refuses ("no person was found in any frame"); this test is
                // about the wiring, so the estimator runs frame by frame.
                "--set",
                "subject.enabled=false",
                "--out",
            ])
            .arg(&out),
    );
    let csv = std::fs::read_to_string(out.join("keypoints.csv")).unwrap();
    let parts: Vec<&str> = csv.lines().nth(1).unwrap().split(',').collect();
    for name in [
        "left_heel",
        "right_toe",
        "mid_hip",
        "op_neck",
        "op_left_ear",
    ] {
        assert!(parts.contains(&name), "no {name} column: {parts:?}");
    }
    assert_eq!(csv.lines().count(), 3 + 2, "two frames");
    let manifest = read_json(&out.join("run.json"));
    assert_eq!(manifest["config"]["pose"]["kind"], "openpose");
    let models_used = manifest["models"].as_array().unwrap();
    assert!(
        models_used.iter().any(|m| m["path"]
            .as_str()
            .is_some_and(|p| p.ends_with("body_pose_model.pth.safetensors"))),
        "{models_used:?}"
    );
    let warnings = manifest["warnings"].to_string();
    assert!(
        warnings.contains("ankle angle is unavailable"),
        "{warnings}"
    );
}
