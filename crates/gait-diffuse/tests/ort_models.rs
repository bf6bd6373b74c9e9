//! The ort backend on the ONNX exports of the tiny random diffusers models
//! (tools/diffuse/export_onnx.py on the fixtures of make_fixtures.py) against
//! diffusers' outputs, f32, each within 1e-4 relative, and the whole
//! regenerator on `backend = "ort"`.

mod common;

use candle_core::DType;
use common::{assert_close, check_two_step_pipeline, expected, require_ort, tiny, tiny_onnx};
use gait_core::{EdgeMap, Frame, ImageRegenerator, Resize, StageContext};
use gait_diffuse::{
    ControlnetConfig, ControlnetPipeline, ControlnetRegenerator, DiffusionModels, OrtModels,
    RegeneratorConfig,
};

const TOL: f64 = 1e-4;

fn models() -> OrtModels {
    require_ort();
    OrtModels::load(&tiny_onnx()).unwrap()
}

#[test]
fn text_encoder_matches_transformers() {
    let e = expected();
    let ids = e["text.input_ids"].to_dtype(DType::U32).unwrap();
    let hidden = models().encode_text(&ids).unwrap();
    assert_close("ort text encoder", &hidden, &e["text.hidden"], TOL);
}

#[test]
fn controlnet_residuals_and_unet_match_diffusers() {
    let e = expected();
    let m = models();
    assert_eq!(m.denoiser().num_residuals(), 4);
    let t = f64::from(e["cn.t"].to_vec1::<f32>().unwrap()[0]);
    let res = m
        .controlnet(&e["cn.sample"], t, &e["cn.ctx"], &e["cn.cond"], 0.7)
        .unwrap();
    for (i, d) in res.down.iter().enumerate() {
        assert_close(
            &format!("ort controlnet down {i}"),
            d,
            &e[&format!("cn.down.{i}")],
            TOL,
        );
    }
    assert_close(
        "ort controlnet mid",
        res.mid.as_ref().unwrap(),
        &e["cn.mid"],
        TOL,
    );
    let out = m
        .unet(&e["cn.sample"], t, &e["cn.ctx"], Some(&res))
        .unwrap();
    assert_close("ort unet with residuals", &out, &e["unet.out"], TOL);
    // Past a ControlNet cut-off the exported UNet gets residuals of zeros.
    let out = m.unet(&e["cn.sample"], t, &e["cn.ctx"], None).unwrap();
    assert_close("ort unet without residuals", &out, &e["unet.plain"], TOL);
}

#[test]
fn vae_decode_matches_diffusers() {
    let e = expected();
    let img = models().decode(&e["vae.latents"]).unwrap();
    assert_close("ort vae decode", &img, &e["vae.decoded"], TOL);
}

#[test]
fn two_step_pipeline_image_matches_diffusers() {
    require_ort();
    let pipe =
        ControlnetPipeline::load_ort(&tiny_onnx(), &tiny().join("tokenizer/merges.txt")).unwrap();
    check_two_step_pipeline("ort pipeline", &pipe, TOL);
}

/// A models folder holding the ONNX exports in the layout the config expects.
fn models_dir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let onnx = dir.path().join("onnx/sd15-controlnet-canny");
    for sub in ["text_encoder", "controlnet", "unet", "vae_decoder"] {
        std::fs::create_dir_all(onnx.join(sub)).unwrap();
        for f in ["model.onnx", "config.json"] {
            std::fs::copy(tiny_onnx().join(sub).join(f), onnx.join(sub).join(f)).unwrap();
        }
    }
    std::fs::create_dir_all(onnx.join("tokenizer")).unwrap();
    std::fs::copy(
        tiny().join("tokenizer/merges.txt"),
        onnx.join("tokenizer/merges.txt"),
    )
    .unwrap();
    dir
}

fn config(backend: &str) -> ControlnetConfig {
    let toml = format!(
        "kind = \"controlnet\"\nbackend = \"{backend}\"\nsteps = 2\nscheduler = \"ddim\"\n\
         resolution = 64\nseed = 3\nbatch = 2\nsd_path = \"sd\"\ncontrolnet_path = \"sd/controlnet\""
    );
    match toml::from_str::<RegeneratorConfig>(&toml).unwrap() {
        RegeneratorConfig::Controlnet(c) => c,
        other => panic!("parsed as {other:?}"),
    }
}

#[test]
fn regenerator_on_ort_matches_candle_frames() {
    require_ort();
    let dir = models_dir();
    // The candle side reads the diffusers-layout fixtures from `sd`.
    common::copy_dir(&tiny(), &dir.path().join("sd"));
    let ctx = StageContext::new(dir.path());
    let frames: Vec<Frame> = (0..3)
        .map(|i| Frame::new(4 + i, image::RgbImage::new(80, 60)))
        .collect();
    let edges: Vec<EdgeMap> = frames
        .iter()
        .map(|f| EdgeMap {
            index: f.index,
            image: image::GrayImage::from_fn(40, 30, |x, y| {
                image::Luma([if (2 * x + y) % 9 == 0 { 255 } else { 0 }])
            }),
            resize: Resize::stretch(80, 60, 40, 30),
        })
        .collect();
    let mut ort = ControlnetRegenerator::new(&config("ort"), &ctx).unwrap();
    let a = ort.regenerate(&frames, Some(&edges)).unwrap();
    let mut candle = ControlnetRegenerator::new(&config("candle"), &ctx).unwrap();
    let b = candle.regenerate(&frames, Some(&edges)).unwrap();
    for (x, y) in a.iter().zip(&b) {
        assert_eq!((x.index, x.width(), x.height()), (y.index, 80, 60));
        // Both backends are within ~1e-5 of diffusers (tiny_models.rs), so
        // 8-bit frames differ at most where a value sits on a rounding boundary.
        let d = x
            .image
            .as_raw()
            .iter()
            .zip(y.image.as_raw())
            .map(|(p, q)| p.abs_diff(*q))
            .max()
            .unwrap_or(0);
        assert!(d <= 1, "ort and candle frames differ by {d} levels");
    }
    assert_ne!(a[0].image, a[1].image, "per-frame seeds differ on ort");
}

#[test]
fn missing_onnx_files_name_the_file_and_the_export_script() {
    let dir = tempfile::tempdir().unwrap();
    let ctx = StageContext::new(dir.path());
    let Err(err) = ControlnetRegenerator::new(&config("ort"), &ctx) else {
        panic!("built without ONNX files")
    };
    let msg = err.to_string();
    for f in [
        "onnx/sd15-controlnet-canny/unet/model.onnx",
        "controlnet/model.onnx",
        "vae_decoder/model.onnx",
        "text_encoder/model.onnx",
        "tokenizer/merges.txt",
        "tools/diffuse/export_onnx.py",
    ] {
        assert!(msg.contains(f), "{f} not in: {msg}");
    }
    let cfg = RegeneratorConfig::Controlnet(config("ort"));
    assert_eq!(cfg.model_files(&ctx).len(), 5);
}

#[test]
fn half_precision_is_refused_on_ort() {
    let dir = models_dir();
    let ctx = StageContext::new(dir.path());
    let cfg = ControlnetConfig {
        dtype: gait_diffuse::Dtype::F16,
        ..config("ort")
    };
    let Err(err) = ControlnetRegenerator::new(&cfg, &ctx) else {
        panic!("f16 accepted on ort")
    };
    let msg = err.to_string();
    assert!(msg.contains("f16") && msg.contains("ort"), "{msg}");
}

#[test]
fn a_unet_graph_without_residual_inputs_is_named() {
    require_ort();
    let dir = models_dir();
    let onnx = dir.path().join("onnx/sd15-controlnet-canny");
    // The ControlNet graph where the UNet belongs: it takes no residuals.
    std::fs::copy(
        onnx.join("controlnet/model.onnx"),
        onnx.join("unet/model.onnx"),
    )
    .unwrap();
    let Err(err) = OrtModels::load(&onnx) else {
        panic!("loaded a UNet without residual inputs")
    };
    let msg = err.to_string();
    assert!(
        msg.contains("unet/model.onnx") && msg.contains("down_block_res_0"),
        "{msg}"
    );
}
