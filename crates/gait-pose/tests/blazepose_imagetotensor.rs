//! The BlazePose crops against mediapipe 0.10.14's own ImageToTensorCalculator,
//! byte for byte (tests/fixtures/blazepose/imagetotensor.json, from
//! tools/blazepose/make_fixtures.py): the detector's zero-bordered letterbox,
//! the landmark crop of mediapipe's detection, and rotated rectangles running
//! past the image edges with replicated or zero border. Needs no model files.

use std::path::PathBuf;

use gait_pose::blazepose::{Border, image_to_tensor};
use sha2::{Digest, Sha256};

fn fixtures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/blazepose")
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[test]
fn crops_match_mediapipe_byte_for_byte() {
    let text = std::fs::read_to_string(fixtures().join("imagetotensor.json")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let crops = json["crops"].as_array().unwrap();
    let mut wrong = Vec::new();
    let mut images = std::collections::HashMap::new();
    for c in crops {
        let name = c["image"].as_str().unwrap();
        let img = images
            .entry(name.to_string())
            .or_insert_with(|| image::open(fixtures().join(name)).unwrap().to_rgb8());
        let r: Vec<f32> = c["roi"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap() as f32)
            .collect();
        let border = match c["border"].as_str().unwrap() {
            "zero" => Border::Zero,
            _ => Border::Replicate,
        };
        let size = c["size"].as_u64().unwrap() as usize;
        let crop = image_to_tensor(img, [r[0], r[1], r[2], r[3], r[4]], size, border).unwrap();
        assert_eq!(crop.len(), size * size * 3);
        if hex(&Sha256::digest(&crop)) != c["sha256"].as_str().unwrap() {
            wrong.push(format!("{name} {r:?} {size} {border:?}"));
        }
    }
    assert!(crops.len() >= 60, "only {} crops", crops.len());
    assert!(
        wrong.is_empty(),
        "crops differing from mediapipe's: {wrong:#?}"
    );
}

#[test]
fn degenerate_rectangles_give_no_crop() {
    let img = image::RgbImage::new(8, 8);
    assert!(image_to_tensor(&img, [0.5, 0.5, 0.0, 0.0, 0.0], 16, Border::Zero).is_none());
    assert!(image_to_tensor(&img, [f32::NAN, 0.5, 1.0, 1.0, 0.0], 16, Border::Zero).is_none());
    let empty = image::RgbImage::new(0, 0);
    assert!(image_to_tensor(&empty, [0.5, 0.5, 1.0, 1.0, 0.0], 16, Border::Replicate).is_none());
}
