//! BlazePose against mediapipe 0.10.14 itself, on the committed fixtures
//! (tools/blazepose/make_fixtures.py). Needs the real model files: run
//! `gait models fetch blazepose` and set GAIT_MODELS_DIR to the models folder;
//! the ort test also needs ORT_DYLIB_PATH.

use std::path::PathBuf;

use gait_core::{Backend, Frame, PoseEstimator, StageContext};
use gait_pose::PersonRule;
use gait_pose::blazepose::{Blazepose, BlazeposeConfig, PersonChoice};

fn models_dir() -> PathBuf {
    let dir = std::env::var_os("GAIT_MODELS_DIR").expect(
        "GAIT_MODELS_DIR is not set: run `gait models fetch blazepose` and point GAIT_MODELS_DIR at the models folder",
    );
    PathBuf::from(dir)
}

fn fixtures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/blazepose")
}

fn load_frame(name: &str) -> Frame {
    let img = image::open(fixtures().join(name)).unwrap().to_rgb8();
    Frame::new(0, img)
}

/// Lower-limb landmarks: hips, knees, ankles, heels, toes.
const LOWER: std::ops::RangeInclusive<usize> = 23..=32;
/// mediapipe's landmarks for the whole-body frames and the astronaut, and for
/// the crops whose body touches an image edge (issue 22).
const REFERENCES: [&str; 2] = ["mediapipe.json", "mediapipe_edges.json"];

/// Lower-limb errors (px) and the largest error of any landmark, for one
/// image; `None` where mediapipe found nobody (and so must we).
fn image_errors(
    est: &mut Box<dyn PoseEstimator>,
    first_native: usize,
    name: &str,
    entry: &serde_json::Value,
) -> Option<(Vec<f64>, f64)> {
    let frame = load_frame(name);
    let (w, h) = (frame.width() as f64, frame.height() as f64);
    let pose = est.estimate(&[frame]).unwrap().remove(0);
    let Some(lms) = entry["landmarks"].as_array() else {
        assert!(
            pose.keypoints
                .iter()
                .all(|k| !k.is_found() && k.likelihood == 0.0),
            "{name}: mediapipe found nobody"
        );
        return None;
    };
    assert!(
        pose.keypoints[first_native].is_found(),
        "{name}: no person found"
    );
    let mut lower = Vec::new();
    let mut all_max = 0f64;
    for (i, lm) in lms.iter().enumerate() {
        let lm: Vec<f64> = lm
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let (ex, ey) = (lm[0] * w - 0.5, lm[1] * h - 0.5);
        let k = pose.keypoints[first_native + i];
        let err = (k.x - ex).hypot(k.y - ey);
        assert!(
            (k.likelihood - lm[3]).abs() < 0.02,
            "{name} landmark {i}: visibility {} vs {}",
            k.likelihood,
            lm[3]
        );
        if LOWER.contains(&i) {
            lower.push(err);
        }
        all_max = all_max.max(err);
    }
    lower.sort_by(f64::total_cmp);
    Some((lower, all_max))
}

/// Every fixture on its own: lower-limb max within 1 px and median within
/// 0.3 px of mediapipe, borders included.
fn check(backend: Backend) {
    let config = BlazeposeConfig {
        backend,
        person: PersonChoice::Rule(PersonRule::MostConfident),
        tracking: false,
        ..Default::default()
    };
    let mut est = config.build(&StageContext::new(models_dir())).unwrap();
    let names = est.keypoint_names();
    let first_native = names.iter().position(|n| n == "bp_nose").unwrap();
    let mut failures = Vec::new();
    let mut checked = 0;
    for file in REFERENCES {
        let text = std::fs::read_to_string(fixtures().join(file)).unwrap();
        let json: serde_json::Value = serde_json::from_str(&text).unwrap();
        for (name, entry) in json["images"].as_object().unwrap() {
            let Some((lower, all_max)) = image_errors(&mut est, first_native, name, entry) else {
                continue;
            };
            checked += 1;
            let (median, max) = (lower[lower.len() / 2], lower[lower.len() - 1]);
            eprintln!(
                "{backend} {name}: lower-limb median {median:.3} px, max {max:.3} px; all landmarks max {all_max:.3} px"
            );
            if max > 1.0 || median > 0.3 {
                failures.push(format!("{name}: median {median:.3}, max {max:.3}"));
            }
        }
    }
    assert!(checked >= 10, "only {checked} images with a person");
    assert!(
        failures.is_empty(),
        "lower-limb error vs mediapipe: {failures:?}"
    );
}

/// mediapipe's landmarks for every image, by name, from both reference files.
fn reference_landmarks() -> serde_json::Map<String, serde_json::Value> {
    let mut all = serde_json::Map::new();
    for file in REFERENCES {
        let text = std::fs::read_to_string(fixtures().join(file)).unwrap();
        let json: serde_json::Value = serde_json::from_str(&text).unwrap();
        all.extend(json["images"].as_object().unwrap().clone());
    }
    all
}

/// The landmark stage alone on mediapipe's own detection rectangle
/// (imagetotensor.json, kind "detection"): same crop, so every landmark
/// within 0.02 px and visibility within 0.005 — what is left is the landmark
/// network's float noise. (From our own detection the rectangle differs in
/// its last bits, through the detector network's float noise; on a few
/// images that alone flips a landmark across the 0.5 refinement threshold,
/// in mediapipe too.)
fn check_landmark_stage(backend: Backend) {
    let config = BlazeposeConfig {
        backend,
        ..Default::default()
    };
    let mut est = Blazepose::new(&config, &StageContext::new(models_dir())).unwrap();
    let first_native = est
        .keypoint_names()
        .iter()
        .position(|n| n == "bp_nose")
        .unwrap();
    let text = std::fs::read_to_string(fixtures().join("imagetotensor.json")).unwrap();
    let crops: serde_json::Value = serde_json::from_str(&text).unwrap();
    let references = reference_landmarks();
    let mut checked = 0;
    for c in crops["crops"].as_array().unwrap() {
        if c["kind"] != "detection" {
            continue;
        }
        let name = c["image"].as_str().unwrap();
        let r: Vec<f32> = c["roi"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap() as f32)
            .collect();
        let frame = load_frame(name);
        let (w, h) = (frame.width() as f64, frame.height() as f64);
        let pose = est
            .pose_in(&frame, [r[0], r[1], r[2], r[3], r[4]])
            .unwrap()
            .unwrap_or_else(|| panic!("{name}: nobody in mediapipe's crop"));
        let lms = references[name]["landmarks"].as_array().unwrap();
        let mut max = 0f64;
        for (i, lm) in lms.iter().enumerate() {
            let lm: Vec<f64> = lm
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect();
            let k = pose.keypoints[first_native + i];
            max = max.max((k.x - (lm[0] * w - 0.5)).hypot(k.y - (lm[1] * h - 0.5)));
            assert!(
                (k.likelihood - lm[3]).abs() < 0.005,
                "{name} landmark {i}: visibility {} vs {}",
                k.likelihood,
                lm[3]
            );
        }
        eprintln!("{backend} {name} on mediapipe's crop: all landmarks max {max:.4} px");
        assert!(
            max <= 0.02,
            "{name}: landmark {max} px from mediapipe on its own crop"
        );
        checked += 1;
    }
    assert!(checked >= 10, "only {checked} detection crops");
}

#[test]
fn candle_landmark_stage_matches_mediapipe() {
    check_landmark_stage(Backend::Candle);
}

#[test]
fn ort_landmark_stage_matches_mediapipe() {
    check_landmark_stage(Backend::Ort);
}

#[test]
fn candle_matches_mediapipe() {
    check(Backend::Candle);
}

#[test]
fn ort_matches_mediapipe() {
    assert!(
        std::env::var_os("ORT_DYLIB_PATH").is_some(),
        "ORT_DYLIB_PATH is not set: point it at libonnxruntime.so from the onnxruntime wheel"
    );
    check(Backend::Ort);
}
