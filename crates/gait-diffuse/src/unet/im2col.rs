//! 3x3, padding-1 convolutions of f32 CPU images (small ones at stride 1,
//! any at stride 2) as one matrix product over an im2col matrix:
//! `(c_out, 9 c_in)` weights, read in their stored layout, times
//! `(9 c_in, B H' W')` patches. At SD 1.5's 8x8
//! level (1280-2560 channels, 128 output columns for a guided batch) this
//! reads every weight once, where Winograd would first write 16/9 of them
//! transformed and then run 16 products too narrow for the packed kernel.

use candle_core::Result;
use rayon::prelude::*;

use super::cpu::{self, SharedMut, View};
use super::winograd::Start;

/// `conv3x3(x) + start` at `stride` for `x` `(b, c_in, h, w)` and `weight`
/// `(c_out, c_in, 3, 3)`, row-major; returns `(b, c_out, h', w')` with
/// `h' = (h - 1) / stride + 1` (likewise `w'`), as torch's padding 1.
pub(crate) fn conv3x3(
    x: &[f32],
    (b, c_in, h, w): (usize, usize, usize, usize),
    weight: &[f32],
    c_out: usize,
    stride: usize,
    start: &Start,
) -> Result<Vec<f32>> {
    if x.len() != b * c_in * h * w || weight.len() != c_out * c_in * 9 || stride == 0 {
        candle_core::bail!("im2col conv3x3: buffer sizes do not match the shapes");
    }
    let (ho, wo) = ((h - 1) / stride + 1, (w - 1) / stride + 1);
    let hw = ho * wo;
    let cols = b * hw;
    cpu::with_scratch(9 * c_in * cols, |patches| {
        cpu::with_scratch(c_out * cols, |m| {
            fill_patches(x, (b, c_in, h, w), stride, patches);
            // SAFETY: weight is c_out x 9c_in, patches 9c_in x cols, m c_out x cols.
            unsafe {
                cpu::matmul(
                    (c_out, cols, 9 * c_in),
                    m.as_mut_ptr(),
                    cols as isize,
                    false,
                    View {
                        ptr: weight.as_ptr(),
                        rs: (9 * c_in) as isize,
                        cs: 1,
                    },
                    View {
                        ptr: patches.as_ptr(),
                        rs: cols as isize,
                        cs: 1,
                    },
                    true,
                );
            }
            let mut out = vec![0f32; b * c_out * hw];
            out.par_chunks_mut(hw).enumerate().for_each(|(task, dst)| {
                let (img, co) = (task / c_out, task % c_out);
                let s0 = start.bias[co] + start.per_image.map_or(0.0, |p| p[img * c_out + co]);
                let src = &m[co * cols + img * hw..][..hw];
                match start.residual {
                    Some(r) => {
                        let r = &r[task * hw..(task + 1) * hw];
                        for ((d, s), r) in dst.iter_mut().zip(src).zip(r) {
                            *d = s + s0 + r;
                        }
                    }
                    None => dst.iter_mut().zip(src).for_each(|(d, s)| *d = s + s0),
                }
            });
            Ok(out)
        })
    })
}

/// Row `ci * 9 + ky * 3 + kx`, column `img * h' * w' + y * w' + x` of
/// `patches` is `x[img, ci, s y + ky - 1, s x + kx - 1]`, zero outside the image.
fn fill_patches(
    x: &[f32],
    (b, c_in, h, w): (usize, usize, usize, usize),
    stride: usize,
    patches: &mut [f32],
) {
    let (ho, wo) = ((h - 1) / stride + 1, (w - 1) / stride + 1);
    let cols = b * ho * wo;
    let dst = SharedMut(patches.as_mut_ptr());
    (0..b * c_in).into_par_iter().for_each(|task| {
        let (img, ci) = (task / c_in, task % c_in);
        let src = &x[task * h * w..(task + 1) * h * w];
        for ky in 0..3 {
            for kx in 0..3 {
                // SAFETY: (row, image) blocks are disjoint between tasks.
                let row = unsafe {
                    std::slice::from_raw_parts_mut(
                        dst.get().add((ci * 9 + ky * 3 + kx) * cols + img * ho * wo),
                        ho * wo,
                    )
                };
                for (y, line) in row.chunks_exact_mut(wo).enumerate() {
                    let sy = (stride * y + ky).wrapping_sub(1);
                    if sy >= h {
                        line.fill(0.0);
                        continue;
                    }
                    let s = &src[sy * w..(sy + 1) * w];
                    if stride > 1 {
                        for (x, v) in line.iter_mut().enumerate() {
                            let sx = (stride * x + kx).wrapping_sub(1);
                            *v = if sx < w { s[sx] } else { 0.0 };
                        }
                        continue;
                    }
                    // Column x reads s[x + kx - 1]: shifted left, right or not at all.
                    match kx {
                        0 => {
                            line[0] = 0.0;
                            line[1..].copy_from_slice(&s[..w - 1]);
                        }
                        1 => line.copy_from_slice(s),
                        _ => {
                            line[..w - 1].copy_from_slice(&s[1..]);
                            line[w - 1] = 0.0;
                        }
                    }
                }
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::unet::winograd::tests::check_against_direct;

    #[test]
    fn matches_a_direct_convolution_with_start_terms() {
        // Stride 2 (torch's output size) is checked against candle in conv.rs.
        check_against_direct(
            |x, dims, wt, co, start| conv3x3(x, dims, wt, co, 1, start).unwrap(),
            &[(2, 5, 3, 6, 8), (1, 4, 6, 7, 5), (2, 3, 2, 1, 1)],
        );
    }
}
