//! JPEG stills decoded byte for byte as `cv2.imread(path, IMREAD_COLOR)` decodes them
//! (opencv-python 4.10, libjpeg-turbo), EXIF orientation included, on the real files of
//! tests/data/jpeg (4:4:4, 4:2:2, 4:2:0, 4:4:0, progressive, restart markers, grayscale,
//! CMYK/YCCK, 16-bit tables, the eight orientations, photographs; a file cut short refused). The
//! expected RGB digests were written by tools/jpeg/make_fixtures.py running OpenCV.

use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

fn data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/jpeg")
}

fn manifest() -> serde_json::Map<String, serde_json::Value> {
    let text = std::fs::read_to_string(data().join("expected/manifest.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["files"].as_object().unwrap().clone()
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[test]
fn every_jpeg_decodes_as_opencv_decodes_it() {
    let files = manifest();
    assert!(files.len() >= 20, "{} files", files.len());
    let mut wrong = Vec::new();
    for (name, want) in files.iter().filter(|(n, _)| *n != CUT_SHORT) {
        let still = gait_pipeline::still::read(&data().join(name))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let (w, h) = still.image.dimensions();
        let got = (
            u64::from(w),
            u64::from(h),
            u64::from(still.orientation),
            hex(&Sha256::digest(still.image.as_raw())),
        );
        let expected = (
            want["width"].as_u64().unwrap(),
            want["height"].as_u64().unwrap(),
            want["orientation"].as_u64().unwrap(),
            want["sha256_of_rgb"].as_str().unwrap().to_string(),
        );
        if got != expected {
            wrong.push(format!("{name}: got {got:?}, OpenCV {expected:?}"));
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

#[test]
fn header_sizes_are_the_decoded_sizes() {
    for (name, want) in manifest().into_iter().filter(|(n, _)| n != CUT_SHORT) {
        let ((w, h), o) = gait_pipeline::still::dimensions(&data().join(&name)).unwrap();
        assert_eq!(
            (u64::from(w), u64::from(h), u64::from(o)),
            (
                want["width"].as_u64().unwrap(),
                want["height"].as_u64().unwrap(),
                want["orientation"].as_u64().unwrap()
            ),
            "{name}"
        );
    }
}

/// A real file cut short. OpenCV decodes it, grey where the data is missing (its digest is in
/// the manifest); gait refuses it, so a half-grey frame is never analysed unnoticed.
const CUT_SHORT: &str = "truncated_jpeg.jpg";

#[test]
fn a_file_cut_short_is_refused() {
    let Err(e) = gait_pipeline::still::read(&data().join(CUT_SHORT)) else {
        panic!("{CUT_SHORT} decoded");
    };
    assert!(e.contains("cut short") && !e.contains('\n'), "{e}");
}

/// 12-bit samples: `cv2.imread` returns None; gait says what the file is, in one line.
#[test]
fn a_12_bit_jpeg_is_refused() {
    let Err(e) = gait_pipeline::still::read(&data().join("refused/testorig12.jpg")) else {
        panic!("a 12-bit JPEG decoded");
    };
    assert!(
        e.contains("not a readable JPEG") && !e.contains('\n'),
        "{e}"
    );
}

#[test]
fn broken_jpegs_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let whole = std::fs::read(data().join("hopper.jpg")).unwrap();
    let cases: [(&str, Vec<u8>); 3] = [
        ("header_only.jpg", whole[..200].to_vec()),
        ("garbage.jpg", [&whole[..4], &[0x55u8; 64][..]].concat()),
        ("empty.jpg", Vec::new()),
    ];
    for (name, bytes) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        let e = match gait_pipeline::still::read(&path) {
            Ok(_) => panic!("{name} decoded"),
            Err(e) => e,
        };
        assert!(!e.contains('\n') && !e.is_empty(), "{name}: {e:?}");
        assert!(gait_pipeline::still::dimensions(&path).is_err() || name == "header_only.jpg");
    }
}

/// BlazePose (static: detection in the image, as `Pose(static_image_mode=True)`) on the
/// photographs decoded here, against mediapipe 0.10.14 on `cv2.imread` of the same files
/// (tools/jpeg/make_pose_fixtures.py): lower-limb landmarks within 0.3 px median, 1 px max.
fn photographs_match_mediapipe(backend: gait_core::Backend) {
    use gait_core::{Frame, StageContext};
    use gait_pose::PersonRule;
    use gait_pose::blazepose::{BlazeposeConfig, PersonChoice};
    let models = std::env::var_os("GAIT_MODELS_DIR")
        .expect("GAIT_MODELS_DIR: run the tests through tools/test.sh (it fetches BlazePose)");
    let config = BlazeposeConfig {
        backend,
        person: PersonChoice::Rule(PersonRule::MostConfident),
        tracking: false,
        ..Default::default()
    };
    let mut est = config
        .build(&StageContext::new(PathBuf::from(models)))
        .unwrap();
    let first = est
        .keypoint_names()
        .iter()
        .position(|n| n == "bp_nose")
        .unwrap();
    let text = std::fs::read_to_string(data().join("expected/mediapipe.json")).unwrap();
    let reference: serde_json::Value = serde_json::from_str(&text).unwrap();
    let images = reference["images"].as_object().unwrap();
    assert!(images.len() >= 3, "{} photographs", images.len());
    let mut failures = Vec::new();
    for (name, entry) in images {
        let still = gait_pipeline::still::read(&data().join(name)).unwrap();
        let (w, h) = still.image.dimensions();
        let pose = est
            .estimate(&[Frame::new(0, still.image)])
            .unwrap()
            .remove(0);
        let mut lower: Vec<f64> = entry["landmarks"].as_array().unwrap()[23..=32]
            .iter()
            .enumerate()
            .map(|(i, lm)| {
                let (x, y) = (lm[0].as_f64().unwrap(), lm[1].as_f64().unwrap());
                let k = pose.keypoints[first + 23 + i];
                (k.x - (x * f64::from(w) - 0.5)).hypot(k.y - (y * f64::from(h) - 0.5))
            })
            .collect();
        lower.sort_by(f64::total_cmp);
        let (median, max) = (lower[lower.len() / 2], lower[lower.len() - 1]);
        eprintln!("{backend} {name}: lower-limb median {median:.3} px, max {max:.3} px");
        if median > 0.3 || max > 1.0 {
            failures.push(format!("{name}: median {median:.3} px, max {max:.3} px"));
        }
    }
    assert!(failures.is_empty(), "{backend}: {failures:?}");
}

#[test]
fn photographs_match_mediapipe_on_candle() {
    photographs_match_mediapipe(gait_core::Backend::Candle);
}

#[test]
fn photographs_match_mediapipe_on_ort() {
    photographs_match_mediapipe(gait_core::Backend::Ort);
}
