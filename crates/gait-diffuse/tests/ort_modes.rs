//! Image-to-image and inpainting on the ort backend (ONNX exports of the
//! tiny models, with `vae_encoder/model.onnx`) against diffusers' pipelines
//! (fixtures from tools/diffuse/make_modes_fixtures.py), within 1e-4 relative.

mod common;

use common::{assert_close, modes, require_ort, tiny, tiny_onnx};
use gait_diffuse::ControlnetPipeline;

const TOL: f64 = 1e-4;

fn pipeline() -> ControlnetPipeline {
    require_ort();
    ControlnetPipeline::load_ort(&tiny_onnx(), &tiny().join("tokenizer/merges.txt")).unwrap()
}

#[test]
fn ort_vae_encoder_matches_diffusers() {
    let e = modes();
    let (mean, std) = pipeline().models.encode_image(&e["modes.init"]).unwrap();
    assert_close("ort vae encode mean", &mean, &e["modes.enc_mean"], TOL);
    assert_close("ort vae encode std", &std, &e["modes.enc_std"], TOL);
}

#[test]
fn ort_img2img_and_inpaint_match_diffusers() {
    common::check_modes("ort ", &pipeline(), &modes()["modes.init"], TOL);
}

#[test]
fn ort_dpmpp2m_and_the_guidance_and_controlnet_cutoffs_match_diffusers() {
    common::check_cutoffs("ort ", &pipeline(), &modes()["modes.init"], TOL);
}

#[test]
fn ort_nine_channel_inpainting_unet_matches_diffusers() {
    require_ort();
    let dir = tempfile::tempdir().unwrap();
    common::copy_dir(&tiny_onnx(), dir.path());
    std::fs::remove_dir_all(dir.path().join("unet")).unwrap();
    common::copy_dir(
        &common::tiny_onnx_inpaint().join("unet"),
        &dir.path().join("unet"),
    );
    let pipe =
        ControlnetPipeline::load_ort(dir.path(), &tiny().join("tokenizer/merges.txt")).unwrap();
    common::check_inpaint9("ort ", &pipe, &modes()["modes.init"], TOL);
}

/// The whole regenerator in inpaint mode on ort and on candle, from one
/// models folder: the same frames within a rounding level.
#[test]
fn inpainting_regenerator_on_ort_matches_candle() {
    use gait_core::{CANONICAL, EdgeMap, Frame, ImageRegenerator, Keypoint, Pose, Resize};
    use gait_diffuse::{ControlnetRegenerator, RegeneratorConfig};

    require_ort();
    let dir = tempfile::tempdir().unwrap();
    common::copy_dir(&tiny(), &dir.path().join("sd"));
    let onnx = dir.path().join("onnx/sd15-controlnet-canny");
    common::copy_dir(&tiny_onnx(), &onnx);
    common::copy_dir(&tiny().join("tokenizer"), &onnx.join("tokenizer"));
    let ctx = gait_core::StageContext::new(dir.path());
    let config = |backend: &str| {
        let toml = format!(
            "kind = \"controlnet\"\nbackend = \"{backend}\"\nsteps = 3\nscheduler = \"unipc\"\n\
             resolution = 64\nseed = 4\nsd_path = \"sd\"\ncontrolnet_path = \"sd/controlnet\"\n\
             mode = \"inpaint\"\nstrength = 0.75"
        );
        match toml::from_str::<RegeneratorConfig>(&toml).unwrap() {
            RegeneratorConfig::Controlnet(c) => c,
            other => panic!("parsed as {other:?}"),
        }
    };
    let frames = vec![Frame::new(
        3,
        image::RgbImage::from_fn(80, 60, |x, y| {
            image::Rgb([(3 * x) as u8, (4 * y) as u8, 120])
        }),
    )];
    let edges = vec![EdgeMap {
        index: 3,
        image: image::GrayImage::from_fn(40, 30, |x, y| {
            image::Luma([if (x + 3 * y) % 6 == 0 { 255 } else { 0 }])
        }),
        resize: Resize::stretch(80, 60, 40, 30),
    }];
    let mut pose = Pose::empty(CANONICAL.len());
    for (name, x, y) in [("right_knee", 50.0, 30.0), ("right_ankle", 48.0, 55.0)] {
        let i = gait_core::keypoint::canonical_index(name).unwrap();
        pose.keypoints[i] = Keypoint::new(x, y, 0.8);
    }
    let poses = [pose];
    let a = ControlnetRegenerator::new(&config("ort"), &ctx)
        .unwrap()
        .regenerate_with_poses(&frames, Some(&edges), &poses)
        .unwrap();
    let b = ControlnetRegenerator::new(&config("candle"), &ctx)
        .unwrap()
        .regenerate_with_poses(&frames, Some(&edges), &poses)
        .unwrap();
    let d = a[0]
        .image
        .as_raw()
        .iter()
        .zip(b[0].image.as_raw())
        .map(|(p, q)| p.abs_diff(*q))
        .max()
        .unwrap_or(0);
    assert!(
        d <= 1,
        "ort and candle inpainted frames differ by {d} levels"
    );
    assert_ne!(a[0].image, frames[0].image);
}
