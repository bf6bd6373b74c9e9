//! diffusers' `Attention` (`to_q`, `to_k`, `to_v` without bias, `to_out.0`):
//! multi-head scaled dot-product attention over tokens `(B, N, C)`, self- or
//! cross- (keys and values from the text context). On f32 CPU tensors each
//! block of queries goes through scores, softmax and values while its scores
//! are still in cache, so the `(B, heads, N, M)` score tensor never exists;
//! elsewhere candle's ops.

use candle_core::{D, Module, Result, Tensor};
use candle_nn::VarBuilder;
use rayon::prelude::*;

use super::cpu::{self, SharedMut, View};
use super::linear::{Linear, linear, linear_no_bias, square_linear_or_conv1x1};
use super::sgemm::{self, MR, NR};

/// Queries per task of the fused kernel (two register-tile strips): their
/// scores against SD 1.5's 4096 latent pixels are 1 MiB.
const QUERIES: usize = 2 * NR;

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

    /// One-head self-attention with biased projections, as in the VAE's mid
    /// block (diffusers' `Attention` with `bias=True`, head width `dim`).
    /// Older checkpoints name them `query`, `key`, `value`, `proj_attn`.
    pub fn vae(vb: VarBuilder, dim: usize) -> Result<Self> {
        let names = if vb.contains_tensor("to_q.weight") {
            ["to_q", "to_k", "to_v", "to_out.0"]
        } else {
            ["query", "key", "value", "proj_attn"]
        };
        let proj = |name: &str| square_linear_or_conv1x1(dim, vb.pp(name));
        Ok(Self {
            to_q: proj(names[0])?,
            to_k: proj(names[1])?,
            to_v: proj(names[2])?,
            to_out: proj(names[3])?,
            heads: 1,
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

/// The fused CPU kernel, on the packed 8x32 register tile of `sgemm`.
/// Per (image, head), K and V are packed once into the tile's A strips; per
/// block of [`QUERIES`] queries the scores are computed transposed
/// (`S^T = K Q^T`, keys down, queries across), so the softmax over keys runs
/// down columns with whole vectors of queries, and `S^T` already is the
/// packed B operand of `O^T = V^T P^T`: no copy or transpose of the scores.
/// The 1/sum of the softmax is applied to the d-wide outputs, not the scores.
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
    // Strips are zero-padded to whole tiles.
    let (m_pad, d_pad) = (m.div_ceil(MR) * MR, d.div_ceil(MR) * MR);
    let per_head = m_pad * d + d_pad * m;
    let mut packed = vec![0f32; b * heads * per_head];
    cpu::with_f32(k, |ks| {
        cpu::with_f32(v, |vs| {
            packed
                .par_chunks_mut(per_head)
                .enumerate()
                .for_each(|(task, buf)| {
                    let (img, h) = (task / heads, task % heads);
                    let (kp, vp) = buf.split_at_mut(m_pad * d);
                    let at = img * m * c + h * d;
                    // SAFETY: head h's d columns of the m tokens of image img.
                    unsafe {
                        // A of S^T = K Q^T: strips of MR keys, d deep.
                        let k_t = View {
                            ptr: ks.as_ptr().add(at),
                            rs: 1,
                            cs: c as isize,
                        };
                        sgemm::pack::<MR>(kp, k_t, 0, d, 0, m);
                        // A of O^T = V^T P^T: strips of MR channels, m deep.
                        let v_rows = View {
                            ptr: vs.as_ptr().add(at),
                            rs: c as isize,
                            cs: 1,
                        };
                        sgemm::pack::<MR>(vp, v_rows, 0, m, 0, d);
                    }
                });
            Ok(())
        })
    })?;
    let mut out = vec![0f32; b * n * c];
    let dst = SharedMut(out.as_mut_ptr());
    let blocks = n.div_ceil(QUERIES);
    let tile = sgemm::tile_kernel();
    cpu::with_f32(q, |qs| {
        (0..b * heads * blocks).into_par_iter().for_each(|task| {
            let (img, rest) = (task / (heads * blocks), task % (heads * blocks));
            let (h, blk) = (rest / blocks, rest % blocks);
            let r0 = blk * QUERIES;
            let nq = QUERIES.min(n - r0);
            let (kp, vp) = packed[(img * heads + h) * per_head..][..per_head].split_at(m_pad * d);
            cpu::with_scratch(QUERIES * (d + m + d_pad) + QUERIES, |work| {
                let (qp, rest) = work.split_at_mut(QUERIES * d);
                let (st, rest) = rest.split_at_mut(QUERIES * m);
                let (ot, inv) = rest.split_at_mut(QUERIES * d_pad);
                let strips = nq.div_ceil(NR);
                // SAFETY: the views stay inside q (nq rows of head h's d
                // columns from row r0), the packed strips hold whole tiles,
                // and each tile writes inside st / ot.
                unsafe {
                    let q_t = View {
                        ptr: qs.as_ptr().add((img * n + r0) * c + h * d),
                        rs: 1,
                        cs: c as isize,
                    };
                    sgemm::pack::<NR>(qp, q_t, 0, d, 0, nq);
                    for t in 0..m.div_ceil(MR) {
                        for s in 0..strips {
                            tile(
                                d,
                                kp.as_ptr().add(t * MR * d),
                                qp.as_ptr().add(s * NR * d),
                                st.as_mut_ptr().add(s * NR * m + t * MR * NR),
                                NR as isize,
                                false,
                                MR.min(m - t * MR),
                                NR.min(nq - s * NR),
                            );
                        }
                    }
                }
                for (s, inv) in inv.chunks_exact_mut(NR).take(strips).enumerate() {
                    softmax_columns(&mut st[s * NR * m..(s + 1) * NR * m], scale, inv);
                }
                // SAFETY: as above.
                unsafe {
                    for t in 0..d.div_ceil(MR) {
                        for s in 0..strips {
                            tile(
                                m,
                                vp.as_ptr().add(t * MR * m),
                                st.as_ptr().add(s * NR * m),
                                ot.as_mut_ptr().add(t * MR * QUERIES + s * NR),
                                QUERIES as isize,
                                false,
                                MR.min(d - t * MR),
                                NR.min(nq - s * NR),
                            );
                        }
                    }
                }
                for j in 0..nq {
                    // SAFETY: query r0 + j's d channels of head h belong to this task only.
                    let row = unsafe {
                        std::slice::from_raw_parts_mut(
                            dst.get().add((img * n + r0 + j) * c + h * d),
                            d,
                        )
                    };
                    for (e, o) in row.iter_mut().enumerate() {
                        *o = ot[e * QUERIES + j] * inv[j];
                    }
                }
            });
        });
        Ok(())
    })?;
    cpu::tensor(out, &[b, n, c])
}

/// Softmax over the rows of `st` (keys x NR queries, row-major), column by
/// column, of `scale * st`; leaves the exponentials in `st` and writes each
/// column's 1 / sum to `inv`.
fn softmax_columns(st: &mut [f32], scale: f32, inv: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    if is_x86_feature_detected!("avx512f") && inv.len() >= NR {
        // SAFETY: the feature was just detected.
        return unsafe { softmax_columns_avx512(st, scale, inv) };
    }
    #[cfg(target_arch = "x86_64")]
    if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
        // SAFETY: the features were just detected.
        return unsafe { softmax_columns_avx2(st, scale, inv) };
    }
    softmax_columns_body(st, scale, inv)
}

/// The plain body compiled for AVX2 and FMA (branch-free `exp`, so it vectorises).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn softmax_columns_avx2(st: &mut [f32], scale: f32, inv: &mut [f32]) {
    softmax_columns_body(st, scale, inv)
}

/// The same with AVX-512 intrinsics (the compiler does not vectorise `exp`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn softmax_columns_avx512(st: &mut [f32], scale: f32, inv: &mut [f32]) {
    use std::arch::x86_64::*;
    let rows = st.len() / NR;
    let p = st.as_mut_ptr();
    // SAFETY: every access is inside the rows x NR values of st (NR = 32).
    unsafe {
        let (mut m0, mut m1) = (
            _mm512_set1_ps(f32::NEG_INFINITY),
            _mm512_set1_ps(f32::NEG_INFINITY),
        );
        for r in 0..rows {
            m0 = _mm512_max_ps(m0, _mm512_loadu_ps(p.add(r * NR)));
            m1 = _mm512_max_ps(m1, _mm512_loadu_ps(p.add(r * NR + 16)));
        }
        let vs = _mm512_set1_ps(scale);
        let (s0, s1) = (_mm512_mul_ps(m0, vs), _mm512_mul_ps(m1, vs));
        let (mut a0, mut a1) = (_mm512_setzero_ps(), _mm512_setzero_ps());
        for r in 0..rows {
            let (q0, q1) = (p.add(r * NR), p.add(r * NR + 16));
            let e0 = cpu::exp_avx512(_mm512_fmsub_ps(_mm512_loadu_ps(q0), vs, s0));
            let e1 = cpu::exp_avx512(_mm512_fmsub_ps(_mm512_loadu_ps(q1), vs, s1));
            _mm512_storeu_ps(q0, e0);
            _mm512_storeu_ps(q1, e1);
            a0 = _mm512_add_ps(a0, e0);
            a1 = _mm512_add_ps(a1, e1);
        }
        let one = _mm512_set1_ps(1.0);
        _mm512_storeu_ps(inv.as_mut_ptr(), _mm512_div_ps(one, a0));
        _mm512_storeu_ps(inv.as_mut_ptr().add(16), _mm512_div_ps(one, a1));
    }
}

#[inline(always)]
fn softmax_columns_body(st: &mut [f32], scale: f32, inv: &mut [f32]) {
    let mut max = [f32::NEG_INFINITY; NR];
    for row in st.chunks_exact(NR) {
        for (m, &v) in max.iter_mut().zip(row) {
            *m = if v > *m { v } else { *m };
        }
    }
    let shift = max.map(|m| m * scale);
    let mut sum = [0f32; NR];
    for row in st.chunks_exact_mut(NR) {
        for ((v, s), sh) in row.iter_mut().zip(&mut sum).zip(&shift) {
            *v = cpu::exp(*v * scale - sh);
            *s += *v;
        }
    }
    for (i, s) in inv.iter_mut().zip(sum) {
        *i = 1.0 / s;
    }
}

#[cfg(test)]
mod tests {
    use candle_core::{Device, Tensor};

    use super::*;

    #[test]
    fn fused_kernel_matches_candle_ops() {
        let dev = Device::Cpu;
        // 150 queries: two full blocks and a partial one (a partial tile
        // strip); 77 keys (a text context, a partial key strip); 4-wide heads
        // (one partial channel strip) and 40-wide ones (SD 1.5's first level).
        for (n, m, c, heads) in [
            (150, 77, 12, 3),
            (9, 9, 12, 3),
            (70, 300, 12, 3),
            (130, 200, 80, 2),
        ] {
            let q = (Tensor::randn(0f32, 1.0, (2, n, c), &dev).unwrap() * 2.0).unwrap();
            let k = (Tensor::randn(0f32, 1.0, (2, m, c), &dev).unwrap() * 2.0).unwrap();
            let v = Tensor::randn(0f32, 1.0, (2, m, c), &dev).unwrap();
            let a = fused(&q, &k, &v, heads).unwrap();
            let r = reference(&q, &k, &v, heads).unwrap();
            let d = cpu::max_abs_diff(&a, &r);
            assert!(d < 1e-5, "{n}x{m}: {d}");
        }
    }
}
