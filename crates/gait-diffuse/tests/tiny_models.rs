//! Each component on tiny random diffusers models against diffusers' outputs
//! (fixtures from tools/diffuse/make_fixtures.py), f32, within 1e-4 relative.

mod common;

use candle_core::{DType, Device};
use candle_nn::VarBuilder;
use common::{assert_close, check_two_step_pipeline, expected, tiny};
use gait_diffuse::model_config::{TextConfig, UnetConfig, VaeConfig, read_config};
use gait_diffuse::weights::build_unet;
use gait_diffuse::{ClipTextModel, ControlNet, ControlnetPipeline, Scheduler, SchedulerKind};

const TOL: f64 = 1e-4;

fn vb(path: std::path::PathBuf) -> VarBuilder<'static> {
    unsafe { VarBuilder::from_mmaped_safetensors(&[path], DType::F32, &Device::Cpu) }.unwrap()
}

#[test]
fn text_encoder_matches_transformers() {
    let e = expected();
    let cfg: TextConfig = read_config(&tiny().join("text_encoder")).unwrap();
    let model =
        ClipTextModel::new(vb(tiny().join("text_encoder/model.safetensors")), &cfg).unwrap();
    let ids = e["text.input_ids"].to_dtype(DType::U32).unwrap();
    assert_close(
        "text encoder",
        &model.forward(&ids).unwrap(),
        &e["text.hidden"],
        TOL,
    );
}

#[test]
fn controlnet_residuals_and_unet_match_diffusers() {
    let e = expected();
    let cfg: UnetConfig = read_config(&tiny().join("controlnet")).unwrap();
    let cn = ControlNet::new(
        vb(tiny().join("controlnet/diffusion_pytorch_model.safetensors")),
        &cfg,
    )
    .unwrap();
    assert_eq!(cn.num_residuals(), 4);
    let t = f64::from(e["cn.t"].to_vec1::<f32>().unwrap()[0]);
    let res = cn
        .forward(&e["cn.sample"], t, &e["cn.ctx"], &e["cn.cond"], 0.7)
        .unwrap();
    for (i, d) in res.down.iter().enumerate() {
        assert_close(
            &format!("controlnet down {i}"),
            d,
            &e[&format!("cn.down.{i}")],
            TOL,
        );
    }
    assert_close(
        "controlnet mid",
        res.mid.as_ref().unwrap(),
        &e["cn.mid"],
        TOL,
    );

    let ucfg: UnetConfig = read_config(&tiny().join("unet")).unwrap();
    let unet = build_unet(
        vb(tiny().join("unet/diffusion_pytorch_model.safetensors")),
        &ucfg,
    )
    .unwrap();
    assert_eq!(unet.num_skips(), cn.num_residuals());
    let plain = unet.forward(&e["cn.sample"], t, &e["cn.ctx"]).unwrap();
    assert_close("unet", &plain, &e["unet.plain"], TOL);
    let out = unet
        .forward_with_residuals(&e["cn.sample"], t, &e["cn.ctx"], &res)
        .unwrap();
    assert_close("unet with residuals", &out, &e["unet.out"], TOL);
}

#[test]
fn vae_decode_matches_diffusers() {
    let e = expected();
    let cfg: VaeConfig = read_config(&tiny().join("vae")).unwrap();
    let vae = gait_diffuse::VaeDecoder::new(
        vb(tiny().join("vae/diffusion_pytorch_model.safetensors")),
        &cfg,
    )
    .unwrap();
    assert_close(
        "vae decode",
        &vae.decode(&e["vae.latents"]).unwrap(),
        &e["vae.decoded"],
        TOL,
    );
}

#[test]
fn schedulers_match_diffusers() {
    let e = expected();
    for (name, kind) in [
        ("ddim", SchedulerKind::Ddim),
        ("unipc", SchedulerKind::Unipc),
    ] {
        for n in [2usize, 10, 20] {
            let want: Vec<i64> = e[&format!("sched.{name}.timesteps.{n}")].to_vec1().unwrap();
            let got: Vec<i64> = Scheduler::new(kind, n)
                .timesteps()
                .iter()
                .map(|&t| t as i64)
                .collect();
            assert_eq!(got, want, "{name} timesteps for {n} steps");
        }
        let mut s = Scheduler::new(kind, 4);
        let mut x = e["sched.x0"].clone();
        for i in 0..4 {
            let eps = e["sched.eps"].get(i).unwrap();
            x = s.step(&eps, &x).unwrap();
            assert_close(
                &format!("{name} step {i}"),
                &x,
                &e[&format!("sched.{name}.step.{i}")],
                TOL,
            );
        }
        let s = Scheduler::new(kind, 10);
        let t = s.timesteps()[3];
        let noisy = s
            .add_noise(&e["sched.x0"], &e["sched.eps"].get(0).unwrap(), t)
            .unwrap();
        assert_close(
            &format!("{name} add_noise"),
            &noisy,
            &e[&format!("sched.{name}.add_noise")],
            TOL,
        );
    }
}

#[test]
fn two_step_pipeline_image_matches_diffusers() {
    let pipe = ControlnetPipeline::load(
        &tiny(),
        &tiny().join("controlnet"),
        DType::F32,
        &Device::Cpu,
    )
    .unwrap();
    check_two_step_pipeline("pipeline", &pipe, TOL);
}
