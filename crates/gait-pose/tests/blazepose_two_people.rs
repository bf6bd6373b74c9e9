//! Several people in view: the configured person is chosen, and kept. The
//! sample video never shows both of its people to the detector at once, so
//! the scenes are built from a real frame: two copies of the walker, one
//! scaled down, side by side. Needs GAIT_MODELS_DIR (after `gait models fetch
//! blazepose`).

use std::path::PathBuf;

use gait_core::{Frame, StageContext};
use gait_pose::PersonRule;
use gait_pose::blazepose::{BlazeposeConfig, PersonChoice};
use image::{RgbImage, imageops};

/// The detector scores the left copy of these scenes at about 0.5 (the right
/// one 0.8-0.9); below mediapipe's 0.5 default so that both always count.
const THRESHOLD: f32 = 0.3;

fn ctx() -> StageContext {
    let dir = std::env::var_os("GAIT_MODELS_DIR").expect(
        "GAIT_MODELS_DIR is not set: run `gait models fetch blazepose` and point GAIT_MODELS_DIR at the models folder",
    );
    StageContext::new(PathBuf::from(dir))
}

/// The walker of frame_150 (a 140x210 crop) twice on a 400x260 canvas: the
/// left copy at `left` scale, the right one at `right` scale, each centred in
/// its half.
fn scene(left: f32, right: f32) -> Frame {
    let p =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/blazepose/frame_150.png");
    let src = image::open(p).unwrap().to_rgb8();
    let walker = imageops::crop_imm(&src, 120, 150, 140, 210).to_image();
    let mut canvas = RgbImage::from_pixel(400, 260, image::Rgb([128, 128, 128]));
    for (half, s) in [(0i64, left), (1, right)] {
        let (w, h) = ((140.0 * s) as u32, (210.0 * s) as u32);
        let copy = imageops::resize(&walker, w, h, imageops::FilterType::Triangle);
        let x = half * 200 + (200 - w as i64) / 2;
        imageops::overlay(&mut canvas, &copy, x, 250 - h as i64);
    }
    Frame::new(0, canvas)
}

/// x of the mid-hip of the estimated pose, or None when nobody was found.
fn hip_x(config: &BlazeposeConfig, frames: &[Frame]) -> Vec<Option<f64>> {
    let mut est = config.build(&ctx()).unwrap();
    let hip = est
        .keypoint_names()
        .iter()
        .position(|n| n == "mid_hip")
        .unwrap();
    est.estimate(frames)
        .unwrap()
        .iter()
        .map(|p| p.keypoints[hip].is_found().then_some(p.keypoints[hip].x))
        .collect()
}

#[test]
fn the_configured_person_is_chosen() {
    let frame = scene(1.0, 0.8);
    let side = |choice| {
        let c = BlazeposeConfig {
            person: choice,
            tracking: false,
            detection_threshold: THRESHOLD,
            ..Default::default()
        };
        let x = hip_x(&c, std::slice::from_ref(&frame))[0].expect("somebody found");
        if x < 200.0 { "left" } else { "right" }
    };
    assert_eq!(side(PersonChoice::Rule(PersonRule::Leftmost)), "left");
    assert_eq!(side(PersonChoice::Rule(PersonRule::Rightmost)), "right");
    assert_eq!(side(PersonChoice::Rule(PersonRule::Largest)), "left");
}

#[test]
fn the_chosen_person_is_kept_when_another_becomes_larger() {
    // The left walker is the larger at first, then the right one grows past it.
    let frames: Vec<Frame> = [(1.0, 0.8), (0.95, 0.9), (0.9, 1.0), (0.85, 1.0)]
        .iter()
        .map(|&(l, r)| scene(l, r))
        .collect();
    // Video mode (tracking) keeps to the person; static mode treats every
    // frame on its own by design.
    let c = BlazeposeConfig {
        person: PersonChoice::Rule(PersonRule::Largest),
        tracking: true,
        detection_threshold: THRESHOLD,
        ..Default::default()
    };
    let xs = hip_x(&c, &frames);
    assert!(xs.iter().all(|x| x.is_some_and(|x| x < 200.0)), "{xs:?}");
    // A fresh estimator on the last scene alone picks the now larger right one.
    let c = BlazeposeConfig {
        person: PersonChoice::Rule(PersonRule::Largest),
        tracking: false,
        detection_threshold: THRESHOLD,
        ..Default::default()
    };
    let last = hip_x(&c, &frames[3..])[0].expect("somebody found");
    assert!(last > 200.0, "{last}");
}
