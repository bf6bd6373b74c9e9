//! One guided denoising step (ControlNet + UNet, batch 2 for classifier-free
//! guidance) at SD 1.5 size; driven by tools/diffuse/bench_step.py, which
//! writes random weights and times diffusers on the same ones.
//!
//! Usage: bench_step SD_DIR CONTROLNET_DIR SIZE REPEATS

use std::time::Instant;

use candle_core::{DType, Device, Tensor};
use gait_diffuse::ControlNet;
use gait_diffuse::model_config::{UnetConfig, read_config};
use gait_diffuse::weights::build_unet;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let [_, sd, cn, size, repeats] = args.as_slice() else {
        return Err("usage: bench_step SD_DIR CONTROLNET_DIR SIZE REPEATS".into());
    };
    let size: usize = size.parse()?;
    let repeats: usize = repeats.parse()?;
    let dev = Device::Cpu;
    let sd = std::path::Path::new(sd);
    let cn = std::path::Path::new(cn);
    let load = |p: std::path::PathBuf| unsafe {
        candle_nn::VarBuilder::from_mmaped_safetensors(&[p], DType::F32, &dev)
    };
    let ucfg: UnetConfig = read_config(&sd.join("unet"))?;
    let unet = build_unet(
        load(sd.join("unet/diffusion_pytorch_model.safetensors"))?,
        &ucfg,
    )?;
    let ccfg: UnetConfig = read_config(cn)?;
    let controlnet = ControlNet::new(load(cn.join("diffusion_pytorch_model.safetensors"))?, &ccfg)?;
    let l = size / 8;
    let x = Tensor::randn(0f32, 1f32, (2, 4, l, l), &dev)?;
    let ctx = Tensor::randn(0f32, 1f32, (2, 77, ucfg.cross_attention_dim), &dev)?;
    let cond = Tensor::rand(0f32, 1f32, (2, 3, size, size), &dev)?;
    for i in 0..repeats {
        let t0 = Instant::now();
        let r = controlnet.forward(&x, 501.0, &ctx, &cond, 1.0)?;
        let eps =
            unet.forward_with_additional_residuals(&x, 501.0, &ctx, Some(&r.down), Some(&r.mid))?;
        let _ = eps.sum_all()?.to_scalar::<f32>()?;
        println!("candle step {i}: {:.3} s", t0.elapsed().as_secs_f64());
    }
    Ok(())
}
