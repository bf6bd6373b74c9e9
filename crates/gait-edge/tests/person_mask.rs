//! The selfie person mask on a real frame: edges survive only inside the
//! thresholded, dilated mask, and the mask removes some background edges.

use std::path::PathBuf;

use gait_core::{EdgeDetector, Frame, StageContext};
use gait_edge::{CannyConfig, CannyDetector, MaskKind, MaskSettings};

fn models() -> PathBuf {
    PathBuf::from(std::env::var_os("GAIT_MODELS_DIR").expect(
        "set GAIT_MODELS_DIR to a models folder with blazepose/selfie_segmentation.tflite (`gait models fetch blazepose`)",
    ))
}

fn frame() -> image::RgbImage {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../gait-pose/tests/fixtures/blazepose/astronaut.png");
    image::open(p).unwrap().to_rgb8()
}

#[test]
fn edges_outside_the_dilated_mask_are_zero() {
    let ctx = StageContext::new(models());
    let plain = CannyConfig::default();
    let masked = CannyConfig {
        mask: MaskKind::Selfie,
        ..CannyConfig::default()
    };
    let img = frame();
    let f = Frame::new(0, img);
    let all = CannyDetector::build(&plain, &ctx)
        .unwrap()
        .detect(std::slice::from_ref(&f))
        .unwrap();
    let kept = CannyDetector::build(&masked, &ctx)
        .unwrap()
        .detect(std::slice::from_ref(&f))
        .unwrap();
    let settings = masked.mask_settings();
    let mask = settings.build(&ctx).unwrap().unwrap();
    let (work, _) = gait_edge::to_working_size(&f, masked.resolution);
    let m = mask.mask(&work).unwrap();
    let (mut outside, mut removed, mut inside_kept) = (0, 0, 0);
    for ((a, k), mm) in all[0]
        .image
        .pixels()
        .zip(kept[0].image.pixels())
        .zip(m.pixels())
    {
        if mm[0] == 0 {
            outside += usize::from(k[0] != 0);
            removed += usize::from(a[0] != 0);
        } else {
            assert_eq!(a[0], k[0], "edges inside the mask must be unchanged");
            inside_kept += usize::from(k[0] != 0);
        }
    }
    println!("edges removed {removed}, kept {inside_kept}");
    assert_eq!(outside, 0);
    assert!(
        removed > 0 && inside_kept > 0,
        "removed {removed}, kept {inside_kept}"
    );
}

#[test]
fn model_files_list_the_mask_model_when_on() {
    let ctx = StageContext::new("/models");
    let c: gait_edge::EdgeConfig = toml::from_str("kind = \"canny\"\nmask = \"selfie\"").unwrap();
    assert_eq!(
        c.model_files(&ctx),
        vec![PathBuf::from(
            "/models/blazepose/selfie_segmentation.tflite"
        )]
    );
    let c: gait_edge::EdgeConfig = toml::from_str("kind = \"canny\"").unwrap();
    assert!(c.model_files(&ctx).is_empty());
    let s = MaskSettings {
        kind: MaskKind::None,
        threshold: 0.5,
        dilate: 8,
        model: None,
    };
    assert!(s.model_path(&ctx).is_none());
}
