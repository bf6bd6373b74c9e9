//! BlazePose against mediapipe 0.10.14 itself, on the committed fixtures
//! (tools/blazepose/make_fixtures.py). Needs the real model files: run
//! `gait models fetch blazepose` and set GAIT_MODELS_DIR to the models folder;
//! the ort test also needs ORT_DYLIB_PATH.

use std::path::PathBuf;

use gait_core::{Backend, Frame, StageContext};
use gait_pose::PersonRule;
use gait_pose::blazepose::{BlazeposeConfig, PersonChoice};

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

fn check(backend: Backend) {
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fixtures().join("mediapipe.json")).unwrap())
            .unwrap();
    let config = BlazeposeConfig {
        backend,
        person: PersonChoice::Rule(PersonRule::MostConfident),
        tracking: false,
        ..Default::default()
    };
    let mut est = config.build(&StageContext::new(models_dir())).unwrap();
    let names = est.keypoint_names();
    let first_native = names.iter().position(|n| n == "bp_nose").unwrap();
    let mut lower = Vec::new();
    let mut all_max = 0f64;
    for (name, entry) in json["images"].as_object().unwrap() {
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
            continue;
        };
        assert!(
            pose.keypoints[first_native].is_found(),
            "{name}: no person found"
        );
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
    }
    lower.sort_by(f64::total_cmp);
    let median = lower[lower.len() / 2];
    let max = lower[lower.len() - 1];
    eprintln!(
        "{backend}: lower-limb error vs mediapipe: median {median:.3} px, max {max:.3} px; all landmarks max {all_max:.3} px"
    );
    assert!(max <= 1.0, "lower-limb max error {max} px");
    assert!(median <= 0.3, "lower-limb median error {median} px");
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
