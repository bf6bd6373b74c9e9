//! diffusers' `FeedForward` with the GEGLU activation of SD's transformer
//! blocks (`ff.net.0.proj`: `dim -> 2 inner`, hidden half times the exact
//! GELU of the gate half; `ff.net.2`: `inner -> dim`), plus the block's
//! residual. On f32 CPU tensors it runs over blocks of tokens in reused
//! buffers: at SD 1.5's 64x64 level the `(B, 4096, 2560)` projection would
//! otherwise be an 84 MB fresh tensor per call, and the gating three more
//! passes of half that size.

use candle_core::{Module, Result, Tensor};
use candle_nn::VarBuilder;
use rayon::prelude::*;

use super::cpu;
use super::linear::{Linear, linear};

/// Tokens per block of the fused path (projection buffer 1024 x 2 inner).
const TOKENS: usize = 1024;

/// The GEGLU feed-forward.
#[derive(Debug, Clone)]
pub(crate) struct FeedForward {
    proj: Linear,
    out: Linear,
    inner: usize,
}

impl FeedForward {
    /// `dim -> 2 inner` then `inner -> dim`, from `ff.net.0.proj` and `ff.net.2`.
    pub fn new(vb: VarBuilder, dim: usize, inner: usize) -> Result<Self> {
        Ok(Self {
            proj: linear(dim, 2 * inner, vb.pp("net.0.proj"))?,
            out: linear(inner, dim, vb.pp("net.2"))?,
            inner,
        })
    }

    /// `ff(x) + residual` for tokens `x` `(B, N, dim)` and a residual of that shape.
    pub fn forward(&self, x: &Tensor, residual: &Tensor) -> Result<Tensor> {
        let fast = cpu::is_cpu_f32(x)
            && cpu::is_cpu_f32(residual)
            && self.proj.is_cpu_f32()
            && self.out.is_cpu_f32();
        if !fast {
            let h = self.proj.forward(x)?;
            let gated =
                (h.narrow(2, 0, self.inner)? * h.narrow(2, self.inner, self.inner)?.gelu_erf()?)?;
            return self.out.forward(&gated)? + residual;
        }
        let dim = x.dim(2)?;
        if residual.dims() != x.dims() {
            candle_core::bail!(
                "feed-forward: residual {:?}, tokens {:?}",
                residual.dims(),
                x.dims()
            );
        }
        let rows = x.elem_count() / dim;
        let mut out = cpu::with_f32(residual, |r| Ok(r.to_vec()))?;
        let inner = self.inner;
        cpu::with_f32(x, |xs| {
            cpu::with_scratch(TOKENS.min(rows) * 2 * inner, |h| {
                cpu::with_scratch(TOKENS.min(rows) * inner, |g| {
                    for r0 in (0..rows).step_by(TOKENS) {
                        let n = TOKENS.min(rows - r0);
                        let (h, g) = (&mut h[..n * 2 * inner], &mut g[..n * inner]);
                        self.proj
                            .apply_f32(&xs[r0 * dim..(r0 + n) * dim], n, h, false)?;
                        g.par_chunks_mut(inner)
                            .zip(h.par_chunks(2 * inner))
                            .for_each(|(g, h)| geglu(h, g));
                        self.out
                            .apply_f32(g, n, &mut out[r0 * dim..(r0 + n) * dim], true)?;
                    }
                    Ok(())
                })
            })
        })?;
        cpu::tensor(out, x.dims())
    }
}

/// `g = hidden * gelu(gate)` for one token's `h = [hidden, gate]`.
fn geglu(h: &[f32], g: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    if is_x86_feature_detected!("avx512f") {
        // SAFETY: the feature was just detected.
        return unsafe { geglu_avx512(h, g) };
    }
    #[cfg(target_arch = "x86_64")]
    if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
        // SAFETY: the features were just detected.
        return unsafe { geglu_avx2(h, g) };
    }
    geglu_body(h, g)
}

/// The same compiled for AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn geglu_avx2(h: &[f32], g: &mut [f32]) {
    geglu_body(h, g)
}

/// The same compiled for AVX-512 (the body is branch-free and vectorises).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn geglu_avx512(h: &[f32], g: &mut [f32]) {
    geglu_body(h, g)
}

#[inline(always)]
fn geglu_body(h: &[f32], g: &mut [f32]) {
    let (hidden, gate) = h.split_at(g.len());
    for ((o, &a), &b) in g.iter_mut().zip(hidden).zip(gate) {
        *o = a * cpu::gelu_erf(b);
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use candle_core::{DType, Device};

    use super::*;

    #[test]
    fn fused_blocks_match_candle_ops() {
        let dev = Device::Cpu;
        let (dim, inner) = (24, 40);
        let mut m = HashMap::new();
        for (name, shape) in [("net.0.proj", (2 * inner, dim)), ("net.2", (dim, inner))] {
            m.insert(
                format!("{name}.weight"),
                Tensor::randn(0f32, 0.3, shape, &dev).unwrap(),
            );
            m.insert(
                format!("{name}.bias"),
                Tensor::randn(0f32, 0.3, shape.0, &dev).unwrap(),
            );
        }
        let ff =
            FeedForward::new(VarBuilder::from_tensors(m, DType::F32, &dev), dim, inner).unwrap();
        // 2 x 1100 tokens: two blocks, the second partial.
        let x = Tensor::randn(0f32, 2.0, (2, 1100, dim), &dev).unwrap();
        let res = Tensor::randn(0f32, 1.0, (2, 1100, dim), &dev).unwrap();
        let got = ff.forward(&x, &res).unwrap();
        // candle's ops in f64 (the fallback path).
        let h = ff.proj.forward(&x).unwrap().to_dtype(DType::F64).unwrap();
        let gated = (h.narrow(2, 0, inner).unwrap()
            * h.narrow(2, inner, inner).unwrap().gelu_erf().unwrap())
        .unwrap();
        let want = (ff
            .out
            .forward(&gated.to_dtype(DType::F32).unwrap())
            .unwrap()
            + &res)
            .unwrap();
        let d = cpu::max_abs_diff(&got, &want);
        assert!(d < 1e-4, "{d}");
    }
}
