//! 3x3, stride-1, padding-1 convolutions of f32 CPU images by Winograd's
//! minimal filtering F(2x2, 3x3) (Lavin & Gray, 2016): each 2x2 output tile
//! needs 16 multiplications per input/output channel pair instead of 36, so
//! the 16 matrix products that carry them do 2.25x fewer FLOPs than a direct
//! convolution. The weights are transformed on every call rather than kept,
//! which would add 16/9 of the 3x3 weights to memory. Rounding differs from a
//! direct convolution by a few ulp of the sums, as in cuDNN's and oneDNN's
//! Winograd kernels.

use candle_core::Result;
use rayon::prelude::*;

use super::cpu::{self, SharedMut, View};

/// Terms added to every output value before the convolution's sum: the bias
/// `(c_out)`, a per-image bias `(B, c_out)` and a residual with the output's
/// shape `(B, c_out, H, W)`.
pub(crate) struct Start<'a> {
    pub bias: &'a [f32],
    pub per_image: Option<&'a [f32]>,
    pub residual: Option<&'a [f32]>,
}

/// `conv3x3(x) + start` for `x` `(b, c_in, h, w)` and `weight`
/// `(c_out, c_in, 3, 3)`, row-major; returns `(b, c_out, h, w)`.
pub(crate) fn conv3x3(
    x: &[f32],
    (b, c_in, h, w): (usize, usize, usize, usize),
    weight: &[f32],
    c_out: usize,
    start: &Start,
) -> Result<Vec<f32>> {
    if x.len() != b * c_in * h * w || weight.len() != c_out * c_in * 9 {
        candle_core::bail!("winograd conv3x3: buffer sizes do not match the shapes");
    }
    let (th, tw) = (h.div_ceil(2), w.div_ceil(2));
    let tiles = b * th * tw;
    cpu::with_scratch(16 * c_out * c_in, |u| {
        cpu::with_scratch(16 * c_in * tiles, |v| {
            cpu::with_scratch(16 * c_out * tiles, |m| {
                transform_weights(weight, c_out, c_in, u);
                transform_input(x, (b, c_in, h, w), v);
                for xi in 0..16 {
                    // SAFETY: U_xi is c_out x c_in, V_xi is c_in x tiles and M_xi
                    // is c_out x tiles, each a contiguous block of its buffer.
                    unsafe {
                        cpu::matmul(
                            (c_out, tiles, c_in),
                            m.as_mut_ptr().add(xi * c_out * tiles),
                            tiles as isize,
                            false,
                            View {
                                ptr: u.as_ptr().add(xi * c_out * c_in),
                                rs: c_in as isize,
                                cs: 1,
                            },
                            View {
                                ptr: v.as_ptr().add(xi * c_in * tiles),
                                rs: tiles as isize,
                                cs: 1,
                            },
                            true,
                        );
                    }
                }
                Ok(transform_output(m, (b, c_out, h, w), start))
            })
        })
    })
}

/// `U = G g G^T` for every channel pair, as 16 matrices `(c_out, c_in)` in `u`.
/// Per output channel the 9 taps are first laid out along the input channels,
/// so both passes of G run over contiguous rows (and vectorise) and write 16
/// contiguous rows.
fn transform_weights(weight: &[f32], c_out: usize, c_in: usize, u: &mut [f32]) {
    let dst = SharedMut(u.as_mut_ptr());
    (0..c_out).into_par_iter().for_each_init(
        || vec![0f32; 12 * c_in],
        |work, co| {
            let (taps, gg) = work.split_at_mut(9 * c_in);
            let g = &weight[co * c_in * 9..(co + 1) * c_in * 9];
            for (ci, k) in g.chunks_exact(9).enumerate() {
                for (t, v) in k.iter().enumerate() {
                    taps[t * c_in + ci] = *v;
                }
            }
            let tap = |t: usize| &taps[t * c_in..(t + 1) * c_in];
            for r in 0..4 {
                // Row r of G g: one row of c_in values per kernel column.
                for kx in 0..3 {
                    let out = &mut gg[kx * c_in..(kx + 1) * c_in];
                    g_row(r, tap(kx), tap(3 + kx), tap(6 + kx), out);
                }
                let (g0, rest) = gg.split_at(c_in);
                let (g1, g2) = rest.split_at(c_in);
                for s in 0..4 {
                    // SAFETY: row (r * 4 + s, co) of U is written by this task only.
                    let out = unsafe {
                        std::slice::from_raw_parts_mut(
                            dst.get().add(((r * 4 + s) * c_out + co) * c_in),
                            c_in,
                        )
                    };
                    g_row(s, g0, g1, g2, out);
                }
            }
        },
    );
}

/// Row `r` of `G (a, b, c)^T`, element-wise over the slices, for
/// G = [[1,0,0],[1/2,1/2,1/2],[1/2,-1/2,1/2],[0,0,1]].
#[inline(always)]
fn g_row(r: usize, a: &[f32], b: &[f32], c: &[f32], out: &mut [f32]) {
    let n = out.len();
    let (a, b, c) = (&a[..n], &b[..n], &c[..n]);
    match r {
        0 => out.copy_from_slice(a),
        1 => (0..n).for_each(|i| out[i] = 0.5 * (a[i] + b[i] + c[i])),
        2 => (0..n).for_each(|i| out[i] = 0.5 * (a[i] - b[i] + c[i])),
        _ => out.copy_from_slice(c),
    }
}

/// `V = B^T d B` for every 4x4 input patch (tile stride 2, zero padding 1),
/// as 16 matrices `(c_in, tiles)` in `v`, tiles numbered image by image.
fn transform_input(x: &[f32], (b, c_in, h, w): (usize, usize, usize, usize), v: &mut [f32]) {
    let (th, tw) = (h.div_ceil(2), w.div_ceil(2));
    let tiles = b * th * tw;
    // Padded plane: one zero row/column before, enough after for the last tile.
    let (ph, pw) = (2 * th + 2, 2 * tw + 2);
    let dst = SharedMut(v.as_mut_ptr());
    (0..b * c_in).into_par_iter().for_each_init(
        || (vec![0f32; ph * pw], vec![0f32; 16 * tw]),
        |(plane, cols), task| {
            let (img, ci) = (task / c_in, task % c_in);
            let src = &x[task * h * w..(task + 1) * h * w];
            for y in 0..h {
                plane[(y + 1) * pw + 1..(y + 1) * pw + 1 + w]
                    .copy_from_slice(&src[y * w..(y + 1) * w]);
            }
            for ti in 0..th {
                // Columns first: cols[(r*4 + s) * tw + j] = (d B)[r][s] of tile j.
                for r in 0..4 {
                    let row = &plane[(2 * ti + r) * pw..(2 * ti + r + 1) * pw];
                    let c = &mut cols[r * 4 * tw..(r + 1) * 4 * tw];
                    for j in 0..tw {
                        let d = &row[2 * j..2 * j + 4];
                        c[j] = d[0] - d[2];
                        c[tw + j] = d[1] + d[2];
                        c[2 * tw + j] = d[2] - d[1];
                        c[3 * tw + j] = d[1] - d[3];
                    }
                }
                // Then rows, vectorised over the tiles of this tile row.
                let t0 = (img * th + ti) * tw;
                for s in 0..4 {
                    let d0 = &cols[s * tw..(s + 1) * tw];
                    let d1 = &cols[(4 + s) * tw..(5 + s) * tw];
                    let d2 = &cols[(8 + s) * tw..(9 + s) * tw];
                    let d3 = &cols[(12 + s) * tw..(13 + s) * tw];
                    let out = |q: usize| {
                        // SAFETY: (q*4+s, ci, t0..t0+tw) belongs to this task only.
                        unsafe {
                            std::slice::from_raw_parts_mut(
                                dst.get().add(((q * 4 + s) * c_in + ci) * tiles + t0),
                                tw,
                            )
                        }
                    };
                    let (o0, o1, o2, o3) = (out(0), out(1), out(2), out(3));
                    for j in 0..tw {
                        o0[j] = d0[j] - d2[j];
                        o1[j] = d1[j] + d2[j];
                        o2[j] = d2[j] - d1[j];
                        o3[j] = d1[j] - d3[j];
                    }
                }
            }
        },
    );
}

/// `Y = A^T M A` for every tile, plus the start terms, into `(b, c_out, h, w)`.
fn transform_output(
    m: &[f32],
    (b, c_out, h, w): (usize, usize, usize, usize),
    start: &Start,
) -> Vec<f32> {
    let (th, tw) = (h.div_ceil(2), w.div_ceil(2));
    let tiles = b * th * tw;
    let mut out = vec![0f32; b * c_out * h * w];
    out.par_chunks_mut(h * w).enumerate().for_each_init(
        || vec![0f32; 8 * tw],
        |rows, (task, dst)| {
            let (img, co) = (task / c_out, task % c_out);
            let s0 = start.bias[co] + start.per_image.map_or(0.0, |p| p[img * c_out + co]);
            let res = start.residual.map(|r| &r[task * h * w..(task + 1) * h * w]);
            for ti in 0..th {
                let t0 = (img * th + ti) * tw;
                let mv = |xi: usize| &m[(xi * c_out + co) * tiles + t0..][..tw];
                // Rows first: rows[(r*4 + s) * tw + j] = (A^T M)[r][s] of tile j.
                for s in 0..4 {
                    let (m0, m1, m2, m3) = (mv(s), mv(4 + s), mv(8 + s), mv(12 + s));
                    let (a, bb) = rows.split_at_mut(4 * tw);
                    let (z0, z1) = (&mut a[s * tw..(s + 1) * tw], &mut bb[s * tw..(s + 1) * tw]);
                    for j in 0..tw {
                        z0[j] = m0[j] + m1[j] + m2[j];
                        z1[j] = m1[j] - m2[j] - m3[j];
                    }
                }
                for r in 0..2 {
                    let y = 2 * ti + r;
                    if y >= h {
                        break;
                    }
                    let z = &rows[r * 4 * tw..(r + 1) * 4 * tw];
                    let line = &mut dst[y * w..(y + 1) * w];
                    for j in 0..tw {
                        let (a0, a1, a2, a3) = (z[j], z[tw + j], z[2 * tw + j], z[3 * tw + j]);
                        line[2 * j] = s0 + a0 + a1 + a2;
                        if 2 * j + 1 < w {
                            line[2 * j + 1] = s0 + a1 - a2 - a3;
                        }
                    }
                    if let Some(res) = res {
                        line.iter_mut()
                            .zip(&res[y * w..(y + 1) * w])
                            .for_each(|(d, r)| *d += r);
                    }
                }
            }
        },
    );
    out
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Direct 3x3 convolution in f64 (the definition).
    fn direct(
        x: &[f32],
        (b, ci, h, w): (usize, usize, usize, usize),
        wt: &[f32],
        co: usize,
    ) -> Vec<f64> {
        let mut out = vec![0f64; b * co * h * w];
        for i in 0..b {
            for o in 0..co {
                for y in 0..h {
                    for xx in 0..w {
                        let mut s = 0f64;
                        for c in 0..ci {
                            for ky in 0..3 {
                                for kx in 0..3 {
                                    let (sy, sx) = (y + ky, xx + kx);
                                    if sy < 1 || sx < 1 || sy > h || sx > w {
                                        continue;
                                    }
                                    s += f64::from(x[((i * ci + c) * h + sy - 1) * w + sx - 1])
                                        * f64::from(wt[((o * ci + c) * 3 + ky) * 3 + kx]);
                                }
                            }
                        }
                        out[((i * co + o) * h + y) * w + xx] = s;
                    }
                }
            }
        }
        out
    }

    fn values(n: usize, seed: u32) -> Vec<f32> {
        // A small deterministic pseudo-random sequence in [-1, 1).
        let mut s = seed.wrapping_mul(2_654_435_761).wrapping_add(1);
        (0..n)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 17;
                s ^= s << 5;
                (s as f32 / u32::MAX as f32) * 2.0 - 1.0
            })
            .collect()
    }

    /// Checks `conv` (stride 1) against [`direct`] plus the start terms on `cases` of
    /// `(batch, c_in, c_out, h, w)`.
    pub(crate) fn check_against_direct(
        conv: impl Fn(&[f32], (usize, usize, usize, usize), &[f32], usize, &Start) -> Vec<f32>,
        cases: &[(usize, usize, usize, usize, usize)],
    ) {
        for &(b, ci, co, h, w) in cases {
            let x = values(b * ci * h * w, 1);
            let wt = values(co * ci * 9, 2);
            let bias = values(co, 3);
            let per = values(b * co, 4);
            let res = values(b * co * h * w, 5);
            let start = Start {
                bias: &bias,
                per_image: Some(&per),
                residual: Some(&res),
            };
            let got = conv(&x, (b, ci, h, w), &wt, co, &start);
            let want = direct(&x, (b, ci, h, w), &wt, co);
            for (k, (g, d)) in got.iter().zip(&want).enumerate() {
                let (i, o) = (k / (co * h * w), (k / (h * w)) % co);
                let e = d + f64::from(bias[o] + per[i * co + o] + res[k]);
                assert!(
                    (f64::from(*g) - e).abs() < 1e-5,
                    "{b}x{ci}->{co} {h}x{w} at {k}: {g} vs {e}"
                );
            }
        }
    }

    #[test]
    fn matches_a_direct_convolution_with_start_terms_on_odd_and_even_sizes() {
        check_against_direct(
            |x, dims, wt, co, start| conv3x3(x, dims, wt, co, start).unwrap(),
            &[
                (2, 5, 3, 6, 8),
                (1, 4, 6, 7, 5),
                (2, 3, 2, 1, 1),
                (1, 2, 2, 2, 9),
            ],
        );
    }
}
