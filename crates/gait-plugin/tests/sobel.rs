//! The example plugin, built by cargo and loaded like a user would, against
//! OpenCV's Sobel on a real frame (fixtures: tools/plugin/make_sobel_fixtures.py).

mod common;

use std::path::Path;

use gait_core::{Frame, Resize};
use gait_plugin::load_edge_detector;

fn expected(threshold: &str) -> image::GrayImage {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(format!("tests/fixtures/sobel/edges_t{threshold}.png"));
    image::open(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_luma8()
}

#[test]
fn sobel_plugin_matches_opencv_on_a_video_frame() {
    for threshold in ["61.5", "200.05"] {
        let cfg = common::config("gait-sobel-edge", &format!("threshold = {threshold}"));
        let mut edge = load_edge_detector(&cfg, &common::ctx()).unwrap();
        let frames = [common::sample_frame(7), common::sample_frame(8)];
        let maps = edge.detect(&frames).unwrap();
        assert_eq!(maps.len(), 2);
        let want = expected(threshold);
        for (map, frame) in maps.iter().zip(&frames) {
            assert_eq!(map.index, frame.index);
            assert_eq!(map.resize, Resize::identity(320, 180));
            let differing = map
                .image
                .pixels()
                .zip(want.pixels())
                .filter(|(a, b)| a != b)
                .count();
            assert_eq!(
                differing, 0,
                "threshold {threshold}: pixels differing from OpenCV"
            );
        }
    }
}

#[test]
fn empty_batch_and_tiny_frames() {
    let cfg = common::config("gait-sobel-edge", "");
    let mut edge = load_edge_detector(&cfg, &common::ctx()).unwrap();
    assert!(edge.detect(&[]).unwrap().is_empty());
    let one = Frame::new(0, image::RgbImage::from_pixel(1, 1, [200, 10, 10].into()));
    let maps = edge.detect(&[one]).unwrap();
    assert_eq!(maps[0].image.as_raw(), &[0]);
}

#[test]
fn unknown_option_is_named() {
    let cfg = common::config("gait-sobel-edge", "thresh = 3");
    let err = load_edge_detector(&cfg, &common::ctx())
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("thresh") && err.contains("threshold") && err.contains("gait-sobel-edge"),
        "{err}"
    );
}

#[test]
fn invalid_option_value_is_refused() {
    let cfg = common::config("gait-sobel-edge", "threshold = -1.0");
    let err = load_edge_detector(&cfg, &common::ctx())
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("threshold must be a finite number"), "{err}");
    let cfg = common::config("gait-sobel-edge", "threshold = \"high\"");
    let err = load_edge_detector(&cfg, &common::ctx())
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("invalid type"), "{err}");
}
