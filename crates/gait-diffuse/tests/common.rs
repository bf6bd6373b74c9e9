//! Shared helpers for the fixture tests.
#![allow(dead_code)]

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use candle_core::{DType, Device, Tensor};

pub fn fixtures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

pub fn tiny() -> PathBuf {
    fixtures().join("tiny")
}

/// Reference tensors written by tools/diffuse/make_fixtures.py.
pub fn expected() -> HashMap<String, Tensor> {
    candle_core::safetensors::load(fixtures().join("expected.safetensors"), &Device::Cpu)
        .expect("expected.safetensors")
}

/// max |ours - ref| / max |ref|.
pub fn rel_err(ours: &Tensor, reference: &Tensor) -> f64 {
    assert_eq!(ours.dims(), reference.dims(), "shape");
    let a = ours
        .to_dtype(DType::F64)
        .unwrap()
        .flatten_all()
        .unwrap()
        .to_vec1::<f64>()
        .unwrap();
    let b = reference
        .to_dtype(DType::F64)
        .unwrap()
        .flatten_all()
        .unwrap()
        .to_vec1::<f64>()
        .unwrap();
    let diff = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    let scale = b.iter().map(|y| y.abs()).fold(0.0, f64::max).max(1e-12);
    diff / scale
}

pub fn assert_close(name: &str, ours: &Tensor, reference: &Tensor, tol: f64) {
    let e = rel_err(ours, reference);
    println!("{name}: max relative error {e:.3e}");
    assert!(e <= tol, "{name}: relative error {e:.3e} > {tol:.0e}");
}

/// The ONNX exports of the tiny models (tools/diffuse/export_onnx.py).
/// Copies a folder tree (fixture models to edit in a temporary folder).
pub fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), target).unwrap();
        }
    }
}

pub fn tiny_onnx() -> PathBuf {
    fixtures().join("tiny_onnx")
}

/// Fails the calling test, saying why, when ONNX Runtime cannot be found.
pub fn require_ort() {
    assert!(
        std::env::var_os("ORT_DYLIB_PATH").is_some_and(|p| !p.is_empty()),
        "ORT_DYLIB_PATH is not set: the ort tests need libonnxruntime.so \
         (from the PyPI onnxruntime==1.31.1 wheel; tools/setup.sh fetches it, tools/test.sh sets it)"
    );
}

/// The complete 2-step pipeline (DDIM and UniPC) on the fixture's edge map
/// and latents against diffusers' images, within `tol` relative.
pub fn check_two_step_pipeline(label: &str, pipe: &gait_diffuse::ControlnetPipeline, tol: f64) {
    use gait_diffuse::{DenoiseParams, SchedulerKind};
    let e = expected();
    let ctx = paper_context(pipe);
    let edge = (e["pipe.edge"].to_dtype(DType::F32).unwrap() / 255.0).unwrap();
    let control = Tensor::stack(&[&edge, &edge, &edge], 0)
        .unwrap()
        .unsqueeze(0)
        .unwrap();
    for (name, kind) in [
        ("ddim", SchedulerKind::Ddim),
        ("unipc", SchedulerKind::Unipc),
    ] {
        let p = DenoiseParams {
            steps: 2,
            guidance_scale: 7.5,
            conditioning_scale: 0.8,
            scheduler: kind,
            cutoffs: Default::default(),
            savings: Default::default(),
        };
        let img = pipe
            .generate(&ctx, &control, &e["pipe.latents"], &p)
            .unwrap();
        assert_close(
            &format!("{label} {name}"),
            &img,
            &e[&format!("pipe.{name}.image")],
            tol,
        );
    }
}

/// Tensors written by tools/diffuse/make_modes_fixtures.py (img2img, inpaint).
pub fn modes() -> HashMap<String, Tensor> {
    candle_core::safetensors::load(fixtures().join("modes.safetensors"), &Device::Cpu)
        .expect("modes.safetensors")
}

/// The modes fixture's edge map as the 1x3xHxW control image in [0, 1].
pub fn modes_control(e: &HashMap<String, Tensor>) -> Tensor {
    let edge = (&e["modes.edge"] / 255.0).unwrap();
    Tensor::stack(&[&edge, &edge, &edge], 0)
        .unwrap()
        .unsqueeze(0)
        .unwrap()
}

/// The modes fixture's inpainting mask as 1x1xHxW in [0, 1].
pub fn modes_mask(e: &HashMap<String, Tensor>) -> Tensor {
    (&e["modes.mask"] / 255.0)
        .unwrap()
        .unsqueeze(0)
        .unwrap()
        .unsqueeze(0)
        .unwrap()
}

/// The denoising settings the modes fixtures were made with.
pub fn modes_params(kind: gait_diffuse::SchedulerKind) -> gait_diffuse::DenoiseParams {
    gait_diffuse::DenoiseParams {
        steps: 3,
        guidance_scale: 7.5,
        conditioning_scale: 0.8,
        scheduler: kind,
        cutoffs: Default::default(),
        savings: Default::default(),
    }
}

/// The paper's prompts, guidance 7.5, encoded by `pipe`.
pub fn paper_context(pipe: &gait_diffuse::ControlnetPipeline) -> Tensor {
    pipe.context(
        gait_diffuse::PAPER_PROMPT,
        gait_diffuse::PAPER_NEGATIVE_PROMPT,
        7.5,
    )
    .unwrap()
}

/// Image-to-image (DDIM, UniPC at strength 0.75) and inpainting (both at
/// 0.75, UniPC at 1.0) against diffusers' pipelines (modes fixture), from the
/// preprocessed frame `init` (1x3xHxW in [-1, 1]).
pub fn check_modes(label: &str, pipe: &gait_diffuse::ControlnetPipeline, init: &Tensor, tol: f64) {
    use gait_diffuse::SchedulerKind;
    let e = modes();
    let ctx = paper_context(pipe);
    let control = modes_control(&e);
    for (name, kind) in [
        ("ddim", SchedulerKind::Ddim),
        ("unipc", SchedulerKind::Unipc),
    ] {
        let img = pipe
            .img2img(
                &ctx,
                &control,
                init,
                &e["modes.enc_eps"],
                &e["modes.noise"],
                0.75,
                &modes_params(kind),
            )
            .unwrap();
        let key = format!("modes.img2img.{name}.image");
        assert_close(&format!("{label}img2img {name}"), &img, &e[&key], tol);
    }
    let inpaint = [
        (
            "ddim",
            SchedulerKind::Ddim,
            0.75,
            "modes.inpaint.ddim.image",
        ),
        (
            "unipc",
            SchedulerKind::Unipc,
            0.75,
            "modes.inpaint.unipc.image",
        ),
        (
            "unipc",
            SchedulerKind::Unipc,
            1.0,
            "modes.inpaint_full.unipc.image",
        ),
    ];
    check_inpaint(label, pipe, init, &inpaint, tol);
}

/// Inpainting `(scheduler name, scheduler, strength, fixture key)` cases
/// against the modes fixture's images.
pub fn check_inpaint(
    label: &str,
    pipe: &gait_diffuse::ControlnetPipeline,
    init: &Tensor,
    cases: &[(&str, gait_diffuse::SchedulerKind, f64, &str)],
    tol: f64,
) {
    let e = modes();
    let ctx = paper_context(pipe);
    let (control, mask) = (modes_control(&e), modes_mask(&e));
    for &(name, kind, strength, key) in cases {
        let img = pipe
            .inpaint(
                &ctx,
                &control,
                init,
                &mask,
                &e["modes.enc_eps"],
                &e["modes.noise"],
                strength,
                &modes_params(kind),
            )
            .unwrap();
        let what = format!("{label}inpaint {name} strength {strength}");
        assert_close(&what, &img, &e[key], tol);
    }
}

/// The 9-channel inpainting UNet's runs (DDIM at 0.75, UniPC at 1) against
/// diffusers; `pipe` must have loaded that UNet.
pub fn check_inpaint9(
    label: &str,
    pipe: &gait_diffuse::ControlnetPipeline,
    init: &Tensor,
    tol: f64,
) {
    use gait_diffuse::SchedulerKind;
    assert_eq!(
        pipe.models.unet_in_channels(),
        9,
        "{label}not the inpainting UNet"
    );
    let cases = [
        (
            "ddim",
            SchedulerKind::Ddim,
            0.75,
            "modes.inpaint9.ddim.image",
        ),
        (
            "unipc",
            SchedulerKind::Unipc,
            1.0,
            "modes.inpaint9_full.unipc.image",
        ),
    ];
    check_inpaint(&format!("{label}9-channel "), pipe, init, &cases, tol);
    // The other modes cannot drive an inpainting UNet.
    let e = modes();
    let err = pipe
        .generate(
            &paper_context(pipe),
            &modes_control(&e),
            &e["modes.noise"],
            &modes_params(SchedulerKind::Ddim),
        )
        .unwrap_err()
        .to_string();
    assert!(err.contains("mode = \"inpaint\""), "{err}");
}

/// The 9-channel inpainting UNet of make_modes_fixtures.py (diffusers layout).
pub fn tiny_inpaint_unet() -> PathBuf {
    fixtures().join("tiny_inpaint_unet")
}

/// Its ONNX export (`unet/model.onnx`).
pub fn tiny_onnx_inpaint() -> PathBuf {
    fixtures().join("tiny_onnx_inpaint")
}

/// The speed settings' cases of tools/diffuse/make_cutoff_fixtures.py (DPM-Solver++ 2M,
/// the CFG and ControlNet cut-offs, in the three modes) against diffusers' images, from
/// the modes fixture's frame `init` (1x3xHxW in [-1, 1]), edge map, mask and noise.
pub fn check_cutoffs(
    label: &str,
    pipe: &gait_diffuse::ControlnetPipeline,
    init: &Tensor,
    tol: f64,
) {
    use gait_diffuse::{Cutoffs, DenoiseParams, SchedulerKind};
    let text = std::fs::read_to_string(fixtures().join("cutoffs.json")).unwrap();
    let cases: Vec<serde_json::Value> = serde_json::from_str(&text).unwrap();
    let images =
        candle_core::safetensors::load(fixtures().join("cutoffs.safetensors"), &Device::Cpu)
            .unwrap();
    let e = modes();
    let ctx = paper_context(pipe);
    let (control, mask) = (modes_control(&e), modes_mask(&e));
    let (eps, noise) = (&e["modes.enc_eps"], &e["modes.noise"]);
    assert_eq!(cases.len(), 6, "cutoffs.json lists every case");
    for c in &cases {
        let f = |k: &str| c[k].as_f64().unwrap();
        let name = c["name"].as_str().unwrap();
        let p = DenoiseParams {
            steps: c["steps"].as_u64().unwrap() as usize,
            guidance_scale: f("guidance_scale"),
            conditioning_scale: f("conditioning_scale"),
            scheduler: serde_json::from_value::<SchedulerKind>(c["scheduler"].clone()).unwrap(),
            cutoffs: Cutoffs {
                guidance_end: f("guidance_end"),
                control_start: f("control_guidance_start"),
                control_end: f("control_guidance_end"),
            },
            savings: Default::default(),
        };
        let strength = f("strength");
        let img = match c["mode"].as_str().unwrap() {
            "text2img" => pipe.generate(&ctx, &control, noise, &p),
            "img2img" => pipe.img2img(&ctx, &control, init, eps, noise, strength, &p),
            _ => pipe.inpaint(&ctx, &control, init, &mask, eps, noise, strength, &p),
        }
        .unwrap();
        let want = &images[&format!("cut.{name}.image")];
        assert_close(&format!("{label}{name}"), &img, want, tol);
    }
}

/// The tiny SD 1.5 + ControlNet with the VAE encoder (image-to-image, inpainting), f32 on the CPU.
pub fn tiny_pipeline_with_encoder() -> gait_diffuse::ControlnetPipeline {
    gait_diffuse::ControlnetPipeline::load_with_encoder(
        &tiny(),
        &tiny().join("controlnet"),
        DType::F32,
        &Device::Cpu,
    )
    .unwrap()
}
