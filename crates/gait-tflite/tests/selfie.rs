//! MediaPipe's selfie segmentation model on the candle runner against the
//! masks MediaPipe 0.10.14 computes (fixtures: tools/edge/make_selfie_fixtures.py).

use std::path::PathBuf;

use gait_tflite::{CandleGraph, Graph};

fn model() -> PathBuf {
    let dir = std::env::var_os("GAIT_MODELS_DIR")
        .expect("set GAIT_MODELS_DIR to a models folder holding blazepose/selfie_segmentation.tflite (`gait models fetch blazepose`)");
    PathBuf::from(dir).join("blazepose/selfie_segmentation.tflite")
}

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

#[test]
fn selfie_mask_matches_mediapipe() {
    let graph = Graph::load(&model()).expect("selfie_segmentation.tflite");
    let net = CandleGraph::new(&graph).expect("compile");
    // The edge_* frames have the person touching one image border each.
    for name in [
        "frame_150",
        "astronaut",
        "edge_bottom_150",
        "edge_top_120",
        "edge_left_150",
        "edge_right_120",
    ] {
        let img = image::open(fixture(&format!("selfie_{name}.png")))
            .unwrap()
            .to_rgb8();
        assert_eq!(img.dimensions(), (256, 256));
        // MediaPipe feeds RGB scaled to [0, 1].
        let input: Vec<f32> = img.as_raw().iter().map(|&v| f32::from(v) / 255.0).collect();
        let out = net.run(&input).expect("run");
        let ours = &out[0];
        let bytes = std::fs::read(fixture(&format!("selfie_{name}.f32"))).unwrap();
        let theirs: Vec<f32> = bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        assert_eq!(ours.len(), theirs.len());
        let max = ours
            .iter()
            .zip(&theirs)
            .map(|(a, b)| (a - b).abs())
            .fold(0f32, f32::max);
        println!("{name}: max |ours - mediapipe| = {max:e}");
        assert!(max < 1e-3, "{name}: max abs difference {max}");
    }
}
