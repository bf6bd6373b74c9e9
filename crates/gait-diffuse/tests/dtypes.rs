//! The pipeline in f16 on the tiny models stays near the f32 image; bf16 is
//! refused on CPU (candle 0.11.1 has no CPU bf16 matmul) with a clear error.

mod common;

use candle_core::{DType, Device, Tensor};
use gait_diffuse::{ControlnetPipeline, DenoiseParams, SchedulerKind};

#[test]
fn half_precision_pipelines_track_f32() {
    let e = common::expected();
    let edge = (e["pipe.edge"].to_dtype(DType::F32).unwrap() / 255.0).unwrap();
    let control = Tensor::stack(&[&edge, &edge, &edge], 0)
        .unwrap()
        .unsqueeze(0)
        .unwrap();
    let p = DenoiseParams {
        steps: 2,
        guidance_scale: 7.5,
        conditioning_scale: 0.8,
        scheduler: SchedulerKind::Unipc,
        cutoffs: Default::default(),
        savings: Default::default(),
    };
    let reference = &e["pipe.unipc.image"];
    let (dtype, tol) = (DType::F16, 5e-2);
    {
        let pipe = ControlnetPipeline::load(
            &common::tiny(),
            &common::tiny().join("controlnet"),
            dtype,
            &Device::Cpu,
        )
        .unwrap();
        let ctx = pipe
            .context(
                gait_diffuse::PAPER_PROMPT,
                gait_diffuse::PAPER_NEGATIVE_PROMPT,
                7.5,
            )
            .unwrap();
        let img = pipe
            .generate(&ctx, &control, &e["pipe.latents"], &p)
            .unwrap();
        assert_eq!(img.dtype(), DType::F32);
        common::assert_close(&format!("pipeline {dtype:?}"), &img, reference, tol);
    }
}

#[test]
fn bf16_on_cpu_is_refused_with_a_reason() {
    let cfg: gait_diffuse::RegeneratorConfig =
        toml::from_str("kind = \"controlnet\"\ndtype = \"bf16\"").unwrap();
    let ctx = gait_core::StageContext::new(common::fixtures());
    let Err(err) = cfg.build(&ctx) else {
        panic!("bf16 accepted on CPU")
    };
    assert!(err.to_string().contains("bf16"), "{err}");
}
