//! Raw network outputs: candle vs ort on the same inputs, and the reader on
//! broken files. Needs GAIT_MODELS_DIR (after `gait models fetch blazepose`)
//! and ORT_DYLIB_PATH.

use std::path::PathBuf;

use gait_core::{Backend, Frame, StageContext};
use gait_pose::blazepose::{BlazeposeConfig, DETECTOR_FILE, LANDMARK_FILE, raw_outputs};
use gait_tflite::{Graph, TfliteError};

fn model(name: &str) -> PathBuf {
    let dir = std::env::var_os("GAIT_MODELS_DIR").expect(
        "GAIT_MODELS_DIR is not set: run `gait models fetch blazepose` and point GAIT_MODELS_DIR at the models folder",
    );
    PathBuf::from(dir).join("blazepose").join(name)
}

fn fixture(name: &str) -> image::RgbImage {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/blazepose")
        .join(name);
    image::open(p).unwrap().to_rgb8()
}

/// An NHWC input of `size` from a fixture image (nearest resize), in [lo, hi].
fn input(size: u32, lo: f32, hi: f32) -> Vec<f32> {
    let img = image::imageops::resize(
        &fixture("frame_150.png"),
        size,
        size,
        image::imageops::FilterType::Nearest,
    );
    img.as_raw()
        .iter()
        .map(|&v| lo + (hi - lo) * v as f32 / 255.0)
        .collect()
}

#[test]
fn candle_and_ort_agree() {
    assert!(
        std::env::var_os("ORT_DYLIB_PATH").is_some(),
        "ORT_DYLIB_PATH is not set: point it at libonnxruntime.so from the onnxruntime wheel"
    );
    for (file, x) in [
        (DETECTOR_FILE, input(224, -1.0, 1.0)),
        (LANDMARK_FILE, input(256, 0.0, 1.0)),
    ] {
        let a = raw_outputs(&model(file), Backend::Candle, &x).unwrap();
        let b = raw_outputs(&model(file), Backend::Ort, &x).unwrap();
        assert_eq!(a.len(), b.len());
        for (i, (a, b)) in a.iter().zip(&b).enumerate() {
            assert_eq!(a.len(), b.len(), "{file} output {i}");
            // Relative to the output's scale: near-zero elements carry no meaning alone.
            let scale = b.iter().fold(0f32, |m, v| m.max(v.abs())).max(1e-6);
            let diff = a.iter().zip(b).fold(0f32, |m, (x, y)| m.max((x - y).abs()));
            eprintln!(
                "{file} output {i}: max |candle - ort| / max |ort| = {:.2e}",
                diff / scale
            );
            assert!(
                diff / scale < 1e-3,
                "{file} output {i}: relative difference {}",
                diff / scale
            );
        }
    }
}

#[test]
fn broken_tflite_files_are_errors() {
    let bytes = std::fs::read(model(DETECTOR_FILE)).unwrap();
    for cut in [
        0,
        7,
        8,
        100,
        5000,
        bytes.len() / 3,
        bytes.len() / 2,
        bytes.len() * 9 / 10,
    ] {
        assert!(Graph::parse(&bytes[..cut]).is_err(), "cut at {cut}");
    }
    let mut foreign = bytes.clone();
    foreign[4..8].copy_from_slice(b"ABCD");
    assert!(matches!(
        Graph::parse(&foreign),
        Err(TfliteError::Foreign(_))
    ));
    // Flipped bytes in the header area must not panic either.
    for pos in (8..400).step_by(7) {
        let mut b = bytes.clone();
        b[pos] ^= 0xA5;
        let _ = Graph::parse(&b);
    }
    // Through the estimator: a clear error naming the file.
    let dir = std::env::temp_dir().join(format!("gait-bp-broken-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("blazepose")).unwrap();
    std::fs::write(dir.join("blazepose").join(DETECTOR_FILE), &bytes[..1000]).unwrap();
    std::fs::copy(
        model(LANDMARK_FILE),
        dir.join("blazepose").join(LANDMARK_FILE),
    )
    .unwrap();
    let err = BlazeposeConfig::default()
        .build(&StageContext::new(&dir))
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains(DETECTOR_FILE) && err.contains("TFLite"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn video_tracking_and_empty_frames() {
    let frames: Vec<Frame> = [
        "frame_100.png",
        "frame_150.png",
        "frame_200.png",
        "frame_229.png",
        "frame_200.png",
    ]
    .iter()
    .enumerate()
    .map(|(i, n)| Frame::new(i, fixture(n)))
    .collect();
    let ctx = StageContext::new(model(DETECTOR_FILE).parent().unwrap().parent().unwrap());
    let mut tracked = BlazeposeConfig::default().build(&ctx).unwrap();
    let statik = BlazeposeConfig {
        tracking: false,
        ..Default::default()
    };
    let mut statik = statik.build(&ctx).unwrap();
    let a = tracked.estimate(&frames).unwrap();
    let b = statik.estimate(&frames).unwrap();
    let names = tracked.keypoint_names();
    let ankle = names.iter().position(|n| n == "left_ankle").unwrap();
    for (i, (a, b)) in a.iter().zip(&b).enumerate() {
        if i == 3 {
            // Nobody in this frame: an empty pose, then re-detection on the next.
            assert!(
                a.keypoints
                    .iter()
                    .all(|k| !k.is_found() && k.likelihood == 0.0)
            );
            assert!(b.keypoints.iter().all(|k| !k.is_found()));
            continue;
        }
        // Frames are far apart in time, so the tracked crop is stale: the
        // estimator must re-detect when the person is lost and still land near
        // the per-frame detection.
        let (ka, kb) = (a.keypoints[ankle], b.keypoints[ankle]);
        assert!(ka.is_found() && kb.is_found(), "frame {i}");
        eprintln!(
            "frame {i}: tracked vs static left ankle {:.2} px apart",
            (ka.x - kb.x).hypot(ka.y - kb.y)
        );
        assert!(
            (ka.x - kb.x).hypot(ka.y - kb.y) < 15.0,
            "frame {i}: {ka:?} vs {kb:?}"
        );
    }
    // Same frame again right after itself: tracking from its own landmarks
    // gives (nearly) the same body position (the crop differs a little, so
    // occluded points such as this frame's left ankle may move more).
    let hip = names.iter().position(|n| n == "mid_hip").unwrap();
    let again = tracked.estimate(&frames[4..5]).unwrap().remove(0);
    let (k1, k2) = (a[4].keypoints[hip], again.keypoints[hip]);
    assert!((k1.x - k2.x).hypot(k1.y - k2.y) < 8.0, "{k1:?} vs {k2:?}");
}
