//! diffusers' `Attention` (`to_q`, `to_k`, `to_v` without bias, `to_out.0`):
//! multi-head scaled dot-product attention over tokens `(B, N, C)`, self- or
//! cross- (keys and values from the text context). On f32 CPU tensors the
//! heads are read in place from the projections (no transposes) and each
//! block of query rows goes through scores, softmax and values while its
//! scores are still in cache, so the `(B, heads, N, M)` score tensor never
//! exists; elsewhere candle's ops.

use candle_core::{D, Module, Result, Tensor};
use candle_nn::VarBuilder;
use rayon::prelude::*;

use super::cpu::{self, SharedMut, View};
use super::linear::{Linear, linear, linear_no_bias};

/// Query rows per task of the fused kernel: 64 rows of 4096 f32 scores
/// (SD 1.5's 64x64 latents) are 1 MiB.
const ROWS: usize = 64;

/// Multi-head attention.
#[derive(Debug, Clone)]
pub struct Attention {
    to_q: Linear,
    to_k: Linear,
    to_v: Linear,
    to_out: Linear,
    heads: usize,
}

impl Attention {
    /// `dim` query channels, `context_dim` key/value channels (= `dim` for
    /// self-attention), `heads` heads splitting `dim`.
    pub fn new(vb: VarBuilder, dim: usize, context_dim: usize, heads: usize) -> Result<Self> {
        if heads == 0 || !dim.is_multiple_of(heads) {
            candle_core::bail!("attention: {dim} channels do not split into {heads} heads");
        }
        Ok(Self {
            to_q: linear_no_bias(dim, dim, vb.pp("to_q"))?,
            to_k: linear_no_bias(context_dim, dim, vb.pp("to_k"))?,
            to_v: linear_no_bias(context_dim, dim, vb.pp("to_v"))?,
            to_out: linear(dim, dim, vb.pp("to_out").pp(0))?,
            heads,
        })
    }

    /// Attention of `x` `(B, N, dim)` over itself or over `context` `(B, M, context_dim)`.
    pub fn forward(&self, x: &Tensor, context: Option<&Tensor>) -> Result<Tensor> {
        let ctx = context.unwrap_or(x);
        let q = self.to_q.forward(x)?;
        let k = self.to_k.forward(ctx)?;
        let v = self.to_v.forward(ctx)?;
        let y = if cpu::is_cpu_f32(&q) {
            fused(&q, &k, &v, self.heads)?
        } else {
            reference(&q, &k, &v, self.heads)?
        };
        self.to_out.forward(&y)
    }
}

/// softmax(q k^T / sqrt(d)) v per head, through candle's ops.
fn reference(q: &Tensor, k: &Tensor, v: &Tensor, heads: usize) -> Result<Tensor> {
    let (b, n, c) = q.dims3()?;
    let m = k.dim(1)?;
    let d = c / heads;
    let split = |t: &Tensor, len: usize| -> Result<Tensor> {
        t.reshape((b, len, heads, d))?.transpose(1, 2)?.contiguous()
    };
    let (q, k, v) = (split(q, n)?, split(k, m)?, split(v, m)?);
    let scores = (q.matmul(&k.t()?)? * (1.0 / (d as f64).sqrt()))?;
    let p = candle_nn::ops::softmax(&scores, D::Minus1)?;
    p.matmul(&v)?.transpose(1, 2)?.reshape((b, n, c))
}

/// The fused CPU kernel: tasks of (image, head, block of query rows).
fn fused(q: &Tensor, k: &Tensor, v: &Tensor, heads: usize) -> Result<Tensor> {
    let (b, n, c) = q.dims3()?;
    let (kb, m, kc) = k.dims3()?;
    if kb != b || kc != c || v.dims() != k.dims() {
        candle_core::bail!(
            "attention: q {:?}, k {:?}, v {:?}",
            q.dims(),
            k.dims(),
            v.dims()
        );
    }
    let d = c / heads;
    let scale = (1.0 / (d as f64).sqrt()) as f32;
    let mut out = vec![0f32; b * n * c];
    let dst = SharedMut(out.as_mut_ptr());
    let blocks = n.div_ceil(ROWS);
    // K^T per image and head, (d, m) row-major: every block of query rows
    // reads it, and the matrix product copies contiguous rows far faster
    // than it gathers a transposed view.
    let mut kt = vec![0f32; b * m * c];
    cpu::with_f32(k, |ks| {
        let dst = SharedMut(kt.as_mut_ptr());
        (0..b * heads).into_par_iter().for_each(|task| {
            let (img, h) = (task / heads, task % heads);
            // SAFETY: task (img, h) writes only its own d x m block.
            let out = unsafe { std::slice::from_raw_parts_mut(dst.get().add(task * d * m), d * m) };
            // In blocks of 16 tokens, so their rows stay in L1 while each
            // channel's 16 values are written side by side.
            for t0 in (0..m).step_by(16) {
                let t1 = (t0 + 16).min(m);
                for e in 0..d {
                    let col = &mut out[e * m + t0..e * m + t1];
                    for (t, o) in (t0..t1).zip(col) {
                        *o = ks[(img * m + t) * c + h * d + e];
                    }
                }
            }
        });
        Ok(())
    })?;
    cpu::with_f32(q, |qs| {
        let ks = &kt;
        cpu::with_f32(v, |vs| {
            (0..b * heads * blocks).into_par_iter().for_each_init(
                || vec![0f32; ROWS * m],
                |scores, task| {
                    let (img, rest) = (task / (heads * blocks), task % (heads * blocks));
                    let (h, blk) = (rest / blocks, rest % blocks);
                    let r0 = blk * ROWS;
                    let rows = ROWS.min(n - r0);
                    let q0 = (img * n + r0) * c + h * d;
                    let kv0 = img * m * c + h * d;
                    // SAFETY: the views stay inside q (rows x d from row r0),
                    // kt (head h's d x m block of image img), v (m tokens
                    // of image img, head h's d columns),
                    // and each task writes only its rows x d block of out.
                    unsafe {
                        cpu::matmul(
                            (rows, m, d),
                            scores.as_mut_ptr(),
                            m as isize,
                            false,
                            View {
                                ptr: qs.as_ptr().add(q0),
                                rs: c as isize,
                                cs: 1,
                            },
                            View {
                                ptr: ks.as_ptr().add((img * heads + h) * d * m),
                                rs: m as isize,
                                cs: 1,
                            },
                            false,
                        );
                    }
                    for row in scores[..rows * m].chunks_exact_mut(m) {
                        softmax_row(row, scale);
                    }
                    // SAFETY: as above.
                    unsafe {
                        cpu::matmul(
                            (rows, d, m),
                            dst.get().add(q0),
                            c as isize,
                            false,
                            View {
                                ptr: scores.as_ptr(),
                                rs: m as isize,
                                cs: 1,
                            },
                            View {
                                ptr: vs.as_ptr().add(kv0),
                                rs: c as isize,
                                cs: 1,
                            },
                            false,
                        );
                    }
                },
            );
            Ok(())
        })
    })?;
    cpu::tensor(out, &[b, n, c])
}

/// In place: softmax(scale * row).
fn softmax_row(row: &mut [f32], scale: f32) {
    #[cfg(target_arch = "x86_64")]
    if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
        // SAFETY: the features were just detected.
        return unsafe { softmax_row_avx2(row, scale) };
    }
    softmax_row_portable(row, scale)
}

/// The same with AVX2 intrinsics (the compiler would not vectorise `exp`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn softmax_row_avx2(row: &mut [f32], scale: f32) {
    use std::arch::x86_64::*;
    let n8 = row.len() / 8 * 8;
    let p = row.as_mut_ptr();
    // SAFETY: every load/store below is at i + 8 <= n8 <= row.len().
    unsafe {
        let mut vmax = _mm256_set1_ps(f32::NEG_INFINITY);
        for i in (0..n8).step_by(8) {
            vmax = _mm256_max_ps(vmax, _mm256_loadu_ps(p.add(i)));
        }
        let mut lanes = [0f32; 8];
        _mm256_storeu_ps(lanes.as_mut_ptr(), vmax);
        let mx = row[n8..]
            .iter()
            .chain(&lanes)
            .fold(f32::NEG_INFINITY, |a, &v| a.max(v));
        let shift = _mm256_set1_ps(mx * scale);
        let vscale = _mm256_set1_ps(scale);
        let mut vsum = _mm256_setzero_ps();
        for i in (0..n8).step_by(8) {
            let x = _mm256_fmsub_ps(_mm256_loadu_ps(p.add(i)), vscale, shift);
            let e = cpu::exp_avx2(x);
            _mm256_storeu_ps(p.add(i), e);
            vsum = _mm256_add_ps(vsum, e);
        }
        _mm256_storeu_ps(lanes.as_mut_ptr(), vsum);
        let mut total: f32 = lanes.iter().sum();
        for v in &mut row[n8..] {
            *v = cpu::exp(*v * scale - mx * scale);
            total += *v;
        }
        let inv = _mm256_set1_ps(1.0 / total);
        for i in (0..n8).step_by(8) {
            _mm256_storeu_ps(p.add(i), _mm256_mul_ps(_mm256_loadu_ps(p.add(i)), inv));
        }
        for v in &mut row[n8..] {
            *v *= 1.0 / total;
        }
    }
}

fn softmax_row_portable(row: &mut [f32], scale: f32) {
    let mut max = [f32::NEG_INFINITY; 8];
    let mut chunks = row.chunks_exact(8);
    for ch in &mut chunks {
        for (m, &v) in max.iter_mut().zip(ch) {
            *m = if v > *m { v } else { *m };
        }
    }
    let mut mx = chunks
        .remainder()
        .iter()
        .fold(f32::NEG_INFINITY, |a, &v| a.max(v));
    mx = max.iter().fold(mx, |a, &v| a.max(v));
    let shift = mx * scale;
    row.iter_mut()
        .for_each(|v| *v = cpu::exp(*v * scale - shift));
    let mut sum = [0f32; 8];
    let chunks = row.chunks_exact(8);
    let mut total: f32 = chunks.remainder().iter().sum();
    for ch in chunks {
        for (s, &v) in sum.iter_mut().zip(ch) {
            *s += v;
        }
    }
    total += sum.iter().sum::<f32>();
    let inv = 1.0 / total;
    row.iter_mut().for_each(|v| *v *= inv);
}

#[cfg(test)]
mod tests {
    use candle_core::{Device, Tensor};

    use super::*;

    #[test]
    fn fused_kernel_matches_candle_ops() {
        let dev = Device::Cpu;
        // 150 queries: two full row blocks and a partial one; 77 keys (a text context).
        for (n, m) in [(150, 77), (9, 9), (70, 300)] {
            let q = (Tensor::randn(0f32, 1.0, (2, n, 12), &dev).unwrap() * 2.0).unwrap();
            let k = (Tensor::randn(0f32, 1.0, (2, m, 12), &dev).unwrap() * 2.0).unwrap();
            let v = Tensor::randn(0f32, 1.0, (2, m, 12), &dev).unwrap();
            let a = fused(&q, &k, &v, 3).unwrap();
            let r = reference(&q, &k, &v, 3).unwrap();
            let d = (a - r)
                .unwrap()
                .abs()
                .unwrap()
                .max_all()
                .unwrap()
                .to_scalar::<f32>()
                .unwrap();
            assert!(d < 1e-5, "{n}x{m}: {d}");
        }
    }
}
