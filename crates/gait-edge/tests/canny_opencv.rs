//! Canny against OpenCV's own output on real photographs (fixtures from
//! `tools/edge/make_canny_fixtures.py`).

use std::path::{Path, PathBuf};

use gait_core::{EdgeDetector, Frame};
use gait_edge::{Canny, CannyConfig, CannyDetector, CannyParams, edge_f1, resize_for_annotator};
use image::{GrayImage, RgbImage};

const NAMES: [&str; 5] = ["video40", "video170", "astronaut", "chelsea", "coffee"];

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/canny")
        .join(name)
}

fn rgb(name: &str) -> RgbImage {
    image::open(fixture(name)).expect(name).to_rgb8()
}

fn gray(name: &str) -> GrayImage {
    image::open(fixture(name)).expect(name).to_luma8()
}

/// Asserts agreement and returns the F1 so failures print every fixture's value.
fn check(label: &str, ours: &GrayImage, reference: &GrayImage, min_f1: f64) -> f64 {
    assert_eq!(ours.dimensions(), reference.dimensions(), "{label}");
    let f1 = edge_f1(ours, reference);
    let differing = ours
        .as_raw()
        .iter()
        .zip(reference.as_raw())
        .filter(|(a, b)| a != b)
        .count();
    println!("{label}: F1 {f1:.6}, {differing} differing pixels");
    assert!(f1 >= min_f1, "{label}: F1 {f1} < {min_f1}");
    f1
}

fn params(low: f64, high: f64, l2: bool) -> CannyParams {
    CannyParams {
        low,
        high,
        l2_gradient: l2,
    }
}

#[test]
fn rgb_matches_opencv_exactly() {
    let mut canny = Canny::new(CannyParams::default());
    for name in NAMES {
        let ours = canny.rgb(&rgb(&format!("{name}.rgb.png")));
        let reference = gray(&format!("{name}.rgb.canny.png"));
        check(&format!("{name} rgb"), &ours, &reference, 1.0);
    }
}

#[test]
fn gray_matches_opencv_exactly() {
    let mut canny = Canny::new(CannyParams::default());
    for name in NAMES {
        let ours = canny.gray(&gray(&format!("{name}.gray.png")));
        let reference = gray(&format!("{name}.gray.canny.png"));
        check(&format!("{name} gray"), &ours, &reference, 1.0);
    }
}

#[test]
fn l2_and_other_thresholds_match_opencv_exactly() {
    let mut l2 = Canny::new(params(100.0, 200.0, true));
    let mut low = Canny::new(params(50.0, 120.0, false));
    for name in NAMES {
        let input = rgb(&format!("{name}.rgb.png"));
        let reference = gray(&format!("{name}.rgb.canny_l2.png"));
        check(&format!("{name} rgb L2"), &l2.rgb(&input), &reference, 1.0);
        let reference = gray(&format!("{name}.rgb.canny_50_120.png"));
        check(
            &format!("{name} rgb 50/120"),
            &low.rgb(&input),
            &reference,
            1.0,
        );
    }
}

#[test]
fn annotator_resize_is_close_to_opencv_inter_area() {
    let input = rgb("annotator.rgb.png");
    let reference = rgb("annotator.resized.png");
    let ours = resize_for_annotator(&input, reference.width(), reference.height());
    let max_diff = ours
        .as_raw()
        .iter()
        .zip(reference.as_raw())
        .map(|(&a, &b)| a.abs_diff(b))
        .max()
        .unwrap_or(0);
    println!("INTER_AREA resize: max abs difference {max_diff}");
    assert!(max_diff <= 1, "max abs difference {max_diff}");
}

#[test]
fn canny_detector_reproduces_the_controlnet_annotator() {
    let frame = Frame::new(7, rgb("annotator.rgb.png"));
    let reference = gray("annotator.canny.png");
    let mut detector = CannyDetector::new(&CannyConfig::default());
    let maps = detector.detect(std::slice::from_ref(&frame)).unwrap();
    assert_eq!(maps.len(), 1);
    let map = &maps[0];
    assert_eq!(map.index, 7);
    assert_eq!(
        (map.resize.dst_width, map.resize.dst_height),
        reference.dimensions()
    );
    assert_eq!(
        (map.resize.src_width, map.resize.src_height),
        frame.image.dimensions()
    );
    check("annotator (resize + canny)", &map.image, &reference, 0.995);
}
