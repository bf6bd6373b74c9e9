//! Image-to-image and inpainting on the ort backend (ONNX exports of the
//! tiny models, with `vae_encoder/model.onnx`) against diffusers' pipelines
//! (fixtures from tools/diffuse/make_modes_fixtures.py), within 1e-4 relative.

mod common;

use std::collections::HashMap;

use candle_core::{Device, Tensor};
use common::{assert_close, fixtures, require_ort, tiny, tiny_onnx};
use gait_diffuse::{ControlnetPipeline, DenoiseParams, SchedulerKind};

const TOL: f64 = 1e-4;

fn modes() -> HashMap<String, Tensor> {
    candle_core::safetensors::load(fixtures().join("modes.safetensors"), &Device::Cpu)
        .expect("modes.safetensors")
}

fn pipeline() -> ControlnetPipeline {
    require_ort();
    ControlnetPipeline::load_ort(&tiny_onnx(), &tiny().join("tokenizer/merges.txt")).unwrap()
}

fn params(kind: SchedulerKind) -> DenoiseParams {
    DenoiseParams {
        steps: 3,
        guidance_scale: 7.5,
        conditioning_scale: 0.8,
        scheduler: kind,
    }
}

fn control(e: &HashMap<String, Tensor>) -> Tensor {
    let edge = (&e["modes.edge"] / 255.0).unwrap();
    Tensor::stack(&[&edge, &edge, &edge], 0)
        .unwrap()
        .unsqueeze(0)
        .unwrap()
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
    let e = modes();
    let pipe = pipeline();
    let ctx = pipe
        .context(
            gait_diffuse::PAPER_PROMPT,
            gait_diffuse::PAPER_NEGATIVE_PROMPT,
            7.5,
        )
        .unwrap();
    let mask = (&e["modes.mask"] / 255.0)
        .unwrap()
        .unsqueeze(0)
        .unwrap()
        .unsqueeze(0)
        .unwrap();
    for (name, kind) in [
        ("ddim", SchedulerKind::Ddim),
        ("unipc", SchedulerKind::Unipc),
    ] {
        let img = pipe
            .img2img(
                &ctx,
                &control(&e),
                &e["modes.init"],
                &e["modes.enc_eps"],
                &e["modes.noise"],
                0.75,
                &params(kind),
            )
            .unwrap();
        assert_close(
            &format!("ort img2img {name}"),
            &img,
            &e[&format!("modes.img2img.{name}.image")],
            TOL,
        );
        for (strength, key) in [
            (0.75, format!("modes.inpaint.{name}.image")),
            (1.0, "modes.inpaint_full.unipc.image".to_string()),
        ] {
            if strength == 1.0 && kind != SchedulerKind::Unipc {
                continue;
            }
            let img = pipe
                .inpaint(
                    &ctx,
                    &control(&e),
                    &e["modes.init"],
                    &mask,
                    &e["modes.enc_eps"],
                    &e["modes.noise"],
                    strength,
                    &params(kind),
                )
                .unwrap();
            assert_close(
                &format!("ort inpaint {name} strength {strength}"),
                &img,
                &e[&key],
                TOL,
            );
        }
    }
}
