//! One guided denoising step (ControlNet + UNet, batch 2 for classifier-free
//! guidance) at SD 1.5 size, on candle or on ONNX Runtime; driven by
//! tools/diffuse/bench_step.py, which writes random weights (and their ONNX
//! exports) and times diffusers on the same ones.
//!
//! Usage: bench_step candle SD_DIR CONTROLNET_DIR SIZE REPEATS [INPUTS OUTPUT]
//!        bench_step ort ONNX_DIR SIZE REPEATS      (needs ORT_DYLIB_PATH)
//! With INPUTS (a safetensors file holding `x`, `ctx` and `cond`) the step
//! runs on those instead of random inputs and writes the UNet's output as
//! `eps` to OUTPUT: bench_step.py --check compares it with diffusers'.

use std::time::Instant;

use candle_core::{DType, Device, Tensor};
use gait_diffuse::model_config::{UnetConfig, read_config};
use gait_diffuse::weights::build_unet;
use gait_diffuse::{ControlNet, OrtDenoiser};

const USAGE: &str = "usage: bench_step candle SD_DIR CONTROLNET_DIR SIZE REPEATS [INPUTS OUTPUT] | bench_step ort ONNX_DIR SIZE REPEATS";

/// Random inputs of one guided step: latents, text context, condition image.
fn inputs(size: usize, cross: usize) -> candle_core::Result<(Tensor, Tensor, Tensor)> {
    let dev = Device::Cpu;
    let l = size / 8;
    Ok((
        Tensor::randn(0f32, 1f32, (2, 4, l, l), &dev)?,
        Tensor::randn(0f32, 1f32, (2, 77, cross), &dev)?,
        Tensor::rand(0f32, 1f32, (2, 3, size, size), &dev)?,
    ))
}

fn candle(
    sd: &str,
    cn: &str,
    size: usize,
    repeats: usize,
    io: Option<(&str, &str)>,
) -> Result<(), Box<dyn std::error::Error>> {
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
    let (x, ctx, cond) = match io {
        Some((path, _)) => {
            let mut t = candle_core::safetensors::load(path, &dev)?;
            let mut take =
                |name: &str| t.remove(name).ok_or(format!("{path} has no tensor {name}"));
            (take("x")?, take("ctx")?, take("cond")?)
        }
        None => inputs(size, ucfg.cross_attention_dim)?,
    };
    for i in 0..repeats {
        let t0 = Instant::now();
        let r = controlnet.forward(&x, 501.0, &ctx, &cond, 1.0)?;
        let eps = unet.forward_with_residuals(&x, 501.0, &ctx, &r)?;
        let _ = eps.sum_all()?.to_scalar::<f32>()?;
        println!("candle step {i}: {:.3} s", t0.elapsed().as_secs_f64());
        if let Some((_, out)) = io {
            candle_core::safetensors::save(&std::collections::HashMap::from([("eps", eps)]), out)?;
        }
    }
    Ok(())
}

fn ort(onnx: &str, size: usize, repeats: usize) -> Result<(), Box<dyn std::error::Error>> {
    let t0 = Instant::now();
    let denoiser = OrtDenoiser::load(std::path::Path::new(onnx))?;
    println!("ort load: {:.3} s", t0.elapsed().as_secs_f64());
    // SD 1.5's text width; the export's context input is dynamic only in batch and length.
    let (x, ctx, cond) = inputs(size, 768)?;
    for i in 0..repeats {
        let t0 = Instant::now();
        let r = denoiser.controlnet(&x, 501.0, &ctx, &cond, 1.0)?;
        let eps = denoiser.unet(&x, 501.0, &ctx, &r)?;
        let _ = eps.sum_all()?.to_scalar::<f32>()?;
        println!("ort step {i}: {:.3} s", t0.elapsed().as_secs_f64());
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    match args.as_slice() {
        ["candle", sd, cn, size, repeats] => candle(sd, cn, size.parse()?, repeats.parse()?, None),
        ["candle", sd, cn, size, repeats, input, output] => candle(
            sd,
            cn,
            size.parse()?,
            repeats.parse()?,
            Some((input, output)),
        ),
        ["ort", onnx, size, repeats] => ort(onnx, size.parse()?, repeats.parse()?),
        _ => Err(USAGE.into()),
    }
}
