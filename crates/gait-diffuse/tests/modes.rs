//! Image-to-image and inpainting on the tiny random diffusers models against
//! diffusers' StableDiffusionControlNetImg2ImgPipeline and
//! StableDiffusionControlNetInpaintPipeline (fixtures from
//! tools/diffuse/make_modes_fixtures.py, same noise on both sides), and the
//! regenerator's handling of poses, masks and bad settings.

mod common;

use std::collections::HashMap;

use candle_core::{DType, Device, Tensor};
use common::{
    assert_close, fixtures, modes, modes_control, modes_mask, modes_params, paper_context, tiny,
};
use gait_core::{CANONICAL, EdgeMap, Frame, ImageRegenerator, Keypoint, Pose, Resize};
use gait_diffuse::{
    ControlnetConfig, ControlnetPipeline, ControlnetRegenerator, RegenMode, RegeneratorConfig,
    SchedulerKind,
};

const TOL: f64 = 1e-4;

fn pipeline() -> ControlnetPipeline {
    common::tiny_pipeline_with_encoder()
}

/// The frame as diffusers preprocesses it: CHW in [-1, 1].
fn init_image(e: &HashMap<String, Tensor>) -> Tensor {
    let hwc = (&e["modes.frame"] / 255.0).unwrap();
    ((hwc.permute((2, 0, 1)).unwrap().unsqueeze(0).unwrap() * 2.0).unwrap() - 1.0).unwrap()
}

#[test]
fn vae_encoder_matches_diffusers_latent_dist() {
    let e = modes();
    let pipe = pipeline();
    let init = init_image(&e);
    assert_close("frame preprocessing", &init, &e["modes.init"], 1e-6);
    let (mean, std) = pipe.models.encode_image(&e["modes.init"]).unwrap();
    assert_close("vae encode mean", &mean, &e["modes.enc_mean"], TOL);
    assert_close("vae encode std", &std, &e["modes.enc_std"], TOL);
    // The component fixture of make_fixtures.py too.
    let x = common::expected();
    let (mean, _) = pipe.models.encode_image(&x["vae.image"]).unwrap();
    assert_close(
        "vae encode mean (expected.safetensors)",
        &mean,
        &x["vae.encoded_mean"],
        TOL,
    );
}

#[test]
fn img2img_and_inpaint_match_diffusers() {
    common::check_modes("", &pipeline(), &init_image(&modes()), TOL);
}

#[test]
fn dpmpp2m_and_the_guidance_and_controlnet_cutoffs_match_diffusers() {
    common::check_cutoffs("", &pipeline(), &init_image(&modes()), TOL);
}

/// The tiny pipeline with the 9-channel inpainting UNet in place of SD's.
fn inpaint9_pipeline() -> ControlnetPipeline {
    let dir = tempfile::tempdir().unwrap();
    let sd = dir.path().join("sd");
    common::copy_dir(&tiny(), &sd);
    std::fs::remove_dir_all(sd.join("unet")).unwrap();
    common::copy_dir(&common::tiny_inpaint_unet(), &sd.join("unet"));
    ControlnetPipeline::load_with_encoder(&sd, &tiny().join("controlnet"), DType::F32, &Device::Cpu)
        .unwrap()
}

#[test]
fn nine_channel_inpainting_unet_matches_diffusers() {
    common::check_inpaint9("", &inpaint9_pipeline(), &init_image(&modes()), TOL);
}

#[test]
fn the_regenerator_drives_an_inpainting_unet_in_inpaint_mode_only() {
    let Err(err) = ControlnetRegenerator::from_pipeline(inpaint9_pipeline(), &config("")) else {
        panic!("text2img accepted a 9-channel UNet")
    };
    let err = err.to_string();
    assert!(
        err.contains("9 input channels") && err.contains("\"text2img\""),
        "{err}"
    );

    let (frames, edges) = inputs();
    let mut r = ControlnetRegenerator::from_pipeline(
        inpaint9_pipeline(),
        &config("mode = \"inpaint\"\nstrength = 0.75"),
    )
    .unwrap();
    let out = r
        .regenerate_with_poses(&frames[..1], Some(&edges[..1]), &[leg_pose()])
        .unwrap();
    assert_eq!(out[0].index, frames[0].index);
    assert_eq!(out[0].image.dimensions(), frames[0].image.dimensions());
    assert_ne!(out[0].image, frames[0].image, "the legs were redrawn");
}

fn config(toml: &str) -> ControlnetConfig {
    let text = format!(
        "kind = \"controlnet\"\nsteps = 3\nscheduler = \"ddim\"\nresolution = 64\nseed = 2\n{toml}"
    );
    match toml::from_str::<RegeneratorConfig>(&text).unwrap() {
        RegeneratorConfig::Controlnet(c) => c,
        other => panic!("parsed as {other:?}"),
    }
}

fn regenerator(toml: &str) -> ControlnetRegenerator {
    ControlnetRegenerator::from_pipeline(pipeline(), &config(toml)).unwrap()
}

fn inputs() -> (Vec<Frame>, Vec<EdgeMap>) {
    let frames: Vec<Frame> = (0..2)
        .map(|i| {
            Frame::new(
                7 + i,
                image::RgbImage::from_fn(80, 60, |x, y| {
                    image::Rgb([(3 * x) as u8, (4 * y) as u8, 90 + 40 * i as u8])
                }),
            )
        })
        .collect();
    let edges = frames
        .iter()
        .map(|f| EdgeMap {
            index: f.index,
            image: image::GrayImage::from_fn(40, 30, |x, y| {
                image::Luma([if (x + 2 * y) % 5 == 0 { 255 } else { 0 }])
            }),
            resize: Resize::stretch(80, 60, 40, 30),
        })
        .collect();
    (frames, edges)
}

fn leg_pose() -> Pose {
    let mut p = Pose::empty(CANONICAL.len());
    for (name, x, y) in [
        ("left_hip", 30.0, 20.0),
        ("left_knee", 32.0, 38.0),
        ("left_ankle", 30.0, 55.0),
    ] {
        let i = gait_core::keypoint::canonical_index(name).unwrap();
        p.keypoints[i] = Keypoint::new(x, y, 0.9);
    }
    p
}

#[test]
fn inpainting_regenerates_the_legs_and_passes_legless_frames_with_a_warning() {
    let (frames, edges) = inputs();
    let mut r =
        regenerator("mode = \"inpaint\"\nstrength = 0.75\nbatch = 2\n[mask]\npaste_back = true");
    let Err(err) = r.regenerate(&frames, Some(&edges)) else {
        panic!("inpainted without poses")
    };
    assert!(err.to_string().contains("pose"), "{err}");

    let poses = [leg_pose(), Pose::empty(CANONICAL.len())];
    let out = r
        .regenerate_with_poses(&frames, Some(&edges), &poses)
        .unwrap();
    assert_eq!(out.len(), 2);
    assert_eq!(
        out[1], frames[1],
        "a frame without legs is handed on unchanged"
    );
    let warnings = r.take_warnings();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].contains("frame 8"), "{warnings:?}");
    assert!(r.take_warnings().is_empty(), "warnings are handed out once");

    let mask = gait_diffuse::LegMask::from_pose(&poses[0], &Default::default()).unwrap();
    let (mut inside, mut changed) = (0, 0);
    for (x, y, p) in out[0].image.enumerate_pixels() {
        let o = frames[0].image.get_pixel(x, y);
        if mask.contains(f64::from(x), f64::from(y)) {
            inside += 1;
            changed += usize::from(p != o);
        } else {
            assert_eq!(p, o, "pixel ({x}, {y}) outside the leg mask is pasted back");
        }
    }
    assert!(
        inside > 100 && changed > inside / 2,
        "{changed} of {inside} leg pixels redrawn"
    );

    // Without paste-back the VAE round trip touches the whole frame (diffusers' output).
    let mut plain = regenerator("mode = \"inpaint\"\nstrength = 0.75");
    let out2 = plain
        .regenerate_with_poses(&frames[..1], Some(&edges[..1]), &poses[..1])
        .unwrap();
    assert_ne!(
        out2[0].image.get_pixel(75, 5),
        frames[0].image.get_pixel(75, 5)
    );
}

#[test]
fn img2img_frames_are_reproducible_and_ignore_poses() {
    let (frames, edges) = inputs();
    let mut r = regenerator("mode = \"img2img\"\nstrength = 0.75\nbatch = 2");
    let a = r.regenerate(&frames, Some(&edges)).unwrap();
    let b = r
        .regenerate_with_poses(&frames, Some(&edges), &[Pose::empty(0), Pose::empty(0)])
        .unwrap();
    assert_eq!(a, b);
    for (f, o) in frames.iter().zip(&a) {
        assert_eq!((o.index, o.width(), o.height()), (f.index, 80, 60));
    }
    // The frame matters: another frame under the same seed and edges differs.
    let mut other = frames[0].clone();
    other.image = image::RgbImage::from_pixel(80, 60, image::Rgb([200, 10, 10]));
    let c = r.regenerate(&[other], Some(&edges[..1])).unwrap();
    assert_ne!(c[0].image, a[0].image);
}

#[test]
fn bad_strengths_and_unsupported_backends_are_named() {
    for (toml, want) in [
        ("mode = \"img2img\"\nstrength = 0.0", "(0, 1]"),
        ("mode = \"img2img\"\nstrength = 1.5", "(0, 1]"),
        ("mode = \"inpaint\"\nstrength = -1.0", "(0, 1]"),
        ("mode = \"img2img\"\nstrength = 0.2", "no denoising step"),
        ("strength = 0.5", "needs mode"),
        ("mode = \"inpaint\"\n[mask]\nradius = 0.0", "mask.radius"),
    ] {
        let err = config(toml).validate().unwrap_err();
        assert!(err.contains(want), "{toml}: {err}");
    }
    let err = toml::from_str::<RegeneratorConfig>("kind = \"controlnet\"\nmode = \"outpaint\"")
        .unwrap_err()
        .to_string();
    assert!(err.contains("img2img") && err.contains("inpaint"), "{err}");
    let err = toml::from_str::<RegeneratorConfig>("kind = \"controlnet\"\n[mask]\nradiu = 1.0")
        .unwrap_err()
        .to_string();
    assert!(err.contains("radius"), "{err}");
    assert!(config("mode = \"img2img\"").validate().is_ok());
    assert_eq!(config("mode = \"img2img\"").strength(), 0.8);
    assert_eq!(config("mode = \"inpaint\"").strength(), 1.0);
    assert_eq!(config("").mode, RegenMode::Text2img);
    assert!(RegeneratorConfig::Controlnet(config("mode = \"inpaint\"")).needs_poses());
    assert!(!RegeneratorConfig::Controlnet(config("mode = \"img2img\"")).needs_poses());

    // On ort the optional VAE encoder export is asked for before anything loads.
    let dir = tempfile::tempdir().unwrap();
    let ctx = gait_core::StageContext::new(dir.path());
    let cfg = config("backend = \"ort\"\nmode = \"img2img\"");
    let Err(err) = ControlnetRegenerator::new(&cfg, &ctx) else {
        panic!("ort ran img2img without an encoder")
    };
    let msg = err.to_string();
    assert!(
        msg.contains("img2img") && msg.contains("vae_encoder/model.onnx"),
        "{msg}"
    );
    let files = RegeneratorConfig::Controlnet(cfg).model_files(&ctx);
    assert!(
        files.iter().any(|f| f.ends_with("vae_encoder/model.onnx")),
        "{files:?}"
    );
}

#[test]
fn half_precision_modes_track_the_reference() {
    let e = modes();
    let pipe = ControlnetPipeline::load_with_encoder(
        &tiny(),
        &tiny().join("controlnet"),
        DType::F16,
        &Device::Cpu,
    )
    .unwrap();
    let ctx = paper_context(&pipe);
    let p = modes_params(SchedulerKind::Unipc);
    let img = pipe
        .img2img(
            &ctx,
            &modes_control(&e),
            &init_image(&e),
            &e["modes.enc_eps"],
            &e["modes.noise"],
            0.75,
            &p,
        )
        .unwrap();
    assert_eq!(img.dtype(), DType::F32);
    // As dtypes.rs: f16 weights and activations, within 5e-2 of f32 diffusers.
    assert_close("img2img f16", &img, &e["modes.img2img.unipc.image"], 5e-2);
    let mask = modes_mask(&e);
    let img = pipe
        .inpaint(
            &ctx,
            &modes_control(&e),
            &init_image(&e),
            &mask,
            &e["modes.enc_eps"],
            &e["modes.noise"],
            0.75,
            &p,
        )
        .unwrap();
    assert_close("inpaint f16", &img, &e["modes.inpaint.unipc.image"], 5e-2);
}

#[test]
fn vae_encoder_asks_for_exactly_the_real_vae_encoder_tensors() {
    use gait_diffuse::model_config::{TextConfig, UnetConfig, VaeConfig};
    use gait_diffuse::weights::{Component, requested_tensors};
    use std::collections::BTreeMap;

    let text = std::fs::read_to_string(fixtures().join("sd15_manifest.json")).unwrap();
    let manifest: BTreeMap<String, BTreeMap<String, Vec<usize>>> =
        serde_json::from_str(&text).unwrap();
    let want: BTreeMap<&String, &Vec<usize>> = manifest["vae"]
        .iter()
        .filter(|(k, _)| k.starts_with("encoder.") || k.starts_with("quant_conv."))
        .collect();
    let got = requested_tensors(
        Component::VaeEncoder,
        &UnetConfig::default(),
        &VaeConfig::default(),
        &TextConfig::default(),
        manifest["vae"].keys().cloned().collect(),
    )
    .unwrap();
    let got_names: Vec<&String> = got.keys().collect();
    let want_names: Vec<&String> = want.keys().copied().collect();
    assert_eq!(got_names, want_names);
    for (name, shape) in want {
        // The mid-block attention's linear weights are 1x1 convolutions in some files.
        let ours = &got[name];
        assert!(
            ours == shape || ours.iter().product::<usize>() == shape.iter().product::<usize>(),
            "{name}: requested {ours:?}, checkpoint has {shape:?}"
        );
    }
    println!("vae encoder: {} tensors match", got.len());
}
