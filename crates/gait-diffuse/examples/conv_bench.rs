//! Throughput of gait-diffuse's 3x3 convolution (the UNet's ResNet convs), of
//! its linear layer and of candle's own linear layer (the `gemm` crate) at
//! SD 1.5's shapes, in GFLOP/s (best of 5), and the time of its attention
//! layer (projections included). Pair it with
//! tools/diffuse/conv_bench.py, which times torch on the same shapes.

use std::collections::HashMap;
use std::time::Instant;

use candle_core::Module;
use candle_core::{DType, Device, Tensor};
use candle_nn::VarBuilder;
use gait_diffuse::unet::{Attention, conv2d, linear_no_bias};

fn best(mut f: impl FnMut()) -> f64 {
    f();
    (0..5)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() -> candle_core::Result<()> {
    let dev = Device::Cpu;
    for (c, hw) in [(320, 64), (640, 32), (1280, 16), (1280, 8)] {
        let mut m = HashMap::new();
        m.insert(
            "weight".to_string(),
            Tensor::randn(0f32, 0.02, (c, c, 3, 3), &dev)?,
        );
        m.insert("bias".to_string(), Tensor::zeros(c, DType::F32, &dev)?);
        let conv = conv2d(c, c, 3, 1, 1, VarBuilder::from_tensors(m, DType::F32, &dev))?;
        let x = Tensor::randn(0f32, 1.0, (2, c, hw, hw), &dev)?;
        let s = best(|| {
            conv.forward(&x).unwrap();
        });
        let flop = 2.0 * 2.0 * (hw * hw) as f64 * (9 * c * c) as f64;
        println!(
            "conv3x3 c={c} {hw}x{hw} b2: {:.1} GFLOP/s ({:.1} ms)",
            flop / s / 1e9,
            s * 1e3
        );
    }
    // x (m, k) through a k -> n layer: ours, then candle_nn's.
    for (m, k, n) in [(8192, 320, 2560), (4096, 2880, 320), (2048, 640, 640)] {
        let mut w = HashMap::new();
        w.insert(
            "weight".to_string(),
            Tensor::randn(0f32, 1.0, (n, k), &dev)?,
        );
        let vb = VarBuilder::from_tensors(w, DType::F32, &dev);
        let ours = linear_no_bias(k, n, vb.clone())?;
        let theirs = candle_nn::linear_no_bias(k, n, vb)?;
        let x = Tensor::randn(0f32, 1.0, (m, k), &dev)?;
        let flop = 2.0 * (m * k * n) as f64;
        let s = best(|| {
            ours.forward(&x).unwrap();
        });
        println!(
            "linear {m}x{k}x{n} (ours): {:.1} GFLOP/s ({:.1} ms)",
            flop / s / 1e9,
            s * 1e3
        );
        let s = best(|| {
            theirs.forward(&x).unwrap();
        });
        println!(
            "linear {m}x{k}x{n} (candle_nn): {:.1} GFLOP/s ({:.1} ms)",
            flop / s / 1e9,
            s * 1e3
        );
    }
    // Self-attention at the first two levels, cross-attention over 77 tokens.
    for (n, c, m, ctx_c) in [
        (4096, 320, 4096, 320),
        (1024, 640, 1024, 640),
        (4096, 320, 77, 768),
    ] {
        let mut w = HashMap::new();
        for (name, k) in [
            ("to_q", c),
            ("to_k", ctx_c),
            ("to_v", ctx_c),
            ("to_out.0", c),
        ] {
            w.insert(
                format!("{name}.weight"),
                Tensor::randn(0f32, 0.05, (c, k), &dev)?,
            );
        }
        w.insert(
            "to_out.0.bias".to_string(),
            Tensor::zeros(c, DType::F32, &dev)?,
        );
        let attn = Attention::new(VarBuilder::from_tensors(w, DType::F32, &dev), c, ctx_c, 8)?;
        let x = Tensor::randn(0f32, 1.0, (2, n, c), &dev)?;
        let ctx = Tensor::randn(0f32, 1.0, (2, m, ctx_c), &dev)?;
        let cross = (m != n).then_some(&ctx);
        let s = best(|| {
            attn.forward(&x, cross).unwrap();
        });
        println!(
            "attention b2 {n}x{c} over {m}x{ctx_c}, 8 heads: {:.1} ms",
            s * 1e3
        );
    }
    Ok(())
}
