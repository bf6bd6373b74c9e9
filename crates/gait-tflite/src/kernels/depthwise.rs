//! TFLite DEPTHWISE_CONV_2D on NHWC activations: per output pixel, all taps
//! accumulate in registers over a block of channels (the innermost, contiguous
//! axis), with bias and activation fused.

use candle_core::{Shape, bail};

use super::{Out, act, nhwc};
use crate::model::Activation;

/// A depthwise convolution with its weights, bias and geometry.
pub(crate) struct Depthwise {
    /// [kh][kw][out_channels], TFLite's own layout.
    pub weights: Vec<f32>,
    pub bias: Vec<f32>,
    pub kernel: (usize, usize),
    pub stride: (usize, usize),
    pub dilation: (usize, usize),
    /// Zero padding before the first row and column (TFLite SAME puts the odd one after).
    pub pad: (usize, usize),
    pub out_size: (usize, usize),
    pub multiplier: usize,
    pub act: Activation,
}

impl Depthwise {
    /// Runs on a [1, h, w, c] input.
    pub fn run(&self, x: &[f32], dims: &[usize]) -> Out {
        let (h, w, c) = nhwc(dims, "depthwise conv")?;
        let oc = c * self.multiplier;
        let (kh, kw) = self.kernel;
        if self.weights.len() != kh * kw * oc || self.bias.len() != oc {
            bail!("depthwise conv: weights do not fit input {dims:?}")
        }
        // A channel multiplier repeats each input channel; rare, so widen the
        // input once and run the plain kernel.
        let wide;
        let x = if self.multiplier == 1 {
            x
        } else {
            wide = x
                .chunks_exact(c)
                .flat_map(|px| {
                    px.iter()
                        .flat_map(|&v| std::iter::repeat_n(v, self.multiplier))
                })
                .collect::<Vec<f32>>();
            &wide[..]
        };
        let (oh, ow) = self.out_size;
        // Appended pixel by pixel, not zeroed first (a pass over memory per layer).
        let mut out = Vec::with_capacity(oh * ow * oc);
        #[cfg(target_arch = "x86_64")]
        if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
            // SAFETY: the CPU has the features the function is compiled for.
            unsafe { self.pixels_avx2(x, h, w, oc, &mut out) };
            return Ok((out, Shape::from((1, oh, ow, oc))));
        }
        self.pixels(x, h, w, oc, &mut out);
        Ok((out, Shape::from((1, oh, ow, oc))))
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn pixels_avx2(&self, x: &[f32], h: usize, w: usize, c: usize, out: &mut Vec<f32>) {
        self.pixels(x, h, w, c, out)
    }

    #[inline(always)]
    fn pixels(&self, x: &[f32], h: usize, w: usize, c: usize, out: &mut Vec<f32>) {
        let (kh, kw) = self.kernel;
        let (oh, ow) = self.out_size;
        let (sy, sx) = self.stride;
        let (dy, dx) = self.dilation;
        // Columns whose taps all fall inside the image share one tap list per
        // row, offset by the column: building a list per pixel cost as much as
        // the arithmetic on BlazePose's narrow early layers.
        let inside = |ox: usize| ox * sx >= self.pad.1 && ox * sx - self.pad.1 + (kw - 1) * dx < w;
        // (input offset, weight offset) of the taps inside the image.
        let mut row_taps: Vec<(usize, usize)> = Vec::with_capacity(kh * kw);
        let mut taps: Vec<(usize, usize)> = Vec::with_capacity(kh * kw);
        let (wt, bias) = (&self.weights[..], &self.bias[..]);
        let mut dst = vec![0f32; c];
        let mut emit = |dst: &mut [f32]| {
            act::apply(self.act, dst);
            out.extend_from_slice(dst);
        };
        for oy in 0..oh {
            let rows = (0..kh).filter_map(|ky| {
                let iy = (oy * sy + ky * dy).wrapping_sub(self.pad.0);
                (iy < h).then_some((ky, iy))
            });
            row_taps.clear();
            for (ky, iy) in rows.clone() {
                row_taps.extend((0..kw).map(|kx| ((iy * w + kx * dx) * c, (ky * kw + kx) * c)));
            }
            for ox in 0..ow {
                if inside(ox) {
                    let base = (ox * sx - self.pad.1) * c;
                    pixel(&mut dst, x, wt, bias, &row_taps, base);
                    emit(&mut dst);
                    continue;
                }
                taps.clear();
                for (ky, iy) in rows.clone() {
                    for kx in 0..kw {
                        let ix = (ox * sx + kx * dx).wrapping_sub(self.pad.1);
                        if ix < w {
                            taps.push(((iy * w + ix) * c, (ky * kw + kx) * c));
                        }
                    }
                }
                pixel(&mut dst, x, wt, bias, &taps, 0);
                emit(&mut dst);
            }
        }
    }
}

/// One output pixel over all channels into `dst`; the taps' input offsets
/// are relative to `base`.
#[inline(always)]
fn pixel(
    dst: &mut [f32],
    x: &[f32],
    wt: &[f32],
    bias: &[f32],
    taps: &[(usize, usize)],
    base: usize,
) {
    let c = dst.len();
    let x = &x[base..];
    let mut c0 = 0;
    while c0 + 32 <= c {
        block::<32>(&mut dst[c0..c0 + 32], x, wt, &bias[c0..c0 + 32], taps, c0);
        c0 += 32;
    }
    while c0 + 16 <= c {
        block::<16>(&mut dst[c0..c0 + 16], x, wt, &bias[c0..c0 + 16], taps, c0);
        c0 += 16;
    }
    while c0 + 8 <= c {
        block::<8>(&mut dst[c0..c0 + 8], x, wt, &bias[c0..c0 + 8], taps, c0);
        c0 += 8;
    }
    for j in c0..c {
        let mut acc = bias[j];
        for &(s, k) in taps {
            acc += x[s + j] * wt[k + j];
        }
        dst[j] = acc;
    }
}

/// `N` channels starting at `c0`, accumulated in registers.
#[inline(always)]
fn block<const N: usize>(
    dst: &mut [f32],
    x: &[f32],
    wt: &[f32],
    bias: &[f32],
    taps: &[(usize, usize)],
    c0: usize,
) {
    let mut acc = [0f32; N];
    acc.copy_from_slice(&bias[..N]);
    for &(s, k) in taps {
        let xs = &x[s + c0..][..N];
        let ws = &wt[k + c0..][..N];
        for j in 0..N {
            acc[j] += xs[j] * ws[j];
        }
    }
    dst[..N].copy_from_slice(&acc);
}

#[cfg(test)]
mod tests {
    use candle_core::{Device, Tensor};

    use super::*;
    use crate::kernels::testutil::{max_diff, tensor};

    /// candle's grouped NCHW conv2d with TFLite-style padding.
    fn reference(x: &Tensor, w_hwc: &Tensor, b: &Tensor, d: &Depthwise) -> Tensor {
        let (_, h, wd, c) = x.dims4().unwrap();
        let oc = c * d.multiplier;
        let (oh, ow) = d.out_size;
        let (kh, kw) = d.kernel;
        let pb = ((oh - 1) * d.stride.0 + (kh - 1) * d.dilation.0 + 1).saturating_sub(h + d.pad.0);
        let pr = ((ow - 1) * d.stride.1 + (kw - 1) * d.dilation.1 + 1).saturating_sub(wd + d.pad.1);
        let x = x.permute((0, 3, 1, 2)).unwrap();
        let x = x.pad_with_zeros(2, d.pad.0, pb).unwrap();
        let x = x.pad_with_zeros(3, d.pad.1, pr).unwrap();
        // [kh, kw, oc] -> [oc, 1, kh, kw]
        let w = w_hwc
            .reshape((kh, kw, oc))
            .unwrap()
            .permute((2, 0, 1))
            .unwrap()
            .reshape((oc, 1, kh, kw))
            .unwrap();
        let y = x.conv2d(&w, 0, d.stride.0, d.dilation.0, c).unwrap();
        let y = y.broadcast_add(&b.reshape((1, oc, 1, 1)).unwrap()).unwrap();
        y.permute((0, 2, 3, 1)).unwrap().relu().unwrap()
    }

    fn check(
        (h, w, c): (usize, usize, usize),
        mult: usize,
        k: usize,
        s: usize,
        dil: usize,
        pad: usize,
        out: (usize, usize),
    ) {
        let oc = c * mult;
        let x = tensor(&[1, h, w, c], 4);
        let wt = tensor(&[1, k, k, oc], 5);
        let b = tensor(&[oc], 6);
        let d = Depthwise {
            weights: wt.flatten_all().unwrap().to_vec1().unwrap(),
            bias: b.to_vec1().unwrap(),
            kernel: (k, k),
            stride: (s, s),
            dilation: (dil, dil),
            pad: (pad, pad),
            out_size: out,
            multiplier: mult,
            act: Activation::Relu,
        };
        let xs = x.flatten_all().unwrap().to_vec1::<f32>().unwrap();
        let (v, shape) = d.run(&xs, x.dims()).unwrap();
        let ours = Tensor::from_vec(v, shape, &Device::Cpu).unwrap();
        let diff = max_diff(&ours, &reference(&x, &wt, &b, &d));
        assert!(diff < 1e-5, "{h}x{w}x{c} k{k} s{s} d{dil}: max diff {diff}");
    }

    #[test]
    fn matches_candle_grouped_conv2d() {
        // 5x5 SAME stride 1 with 16 + 8 + 3 channels (every block width).
        check((9, 7, 27), 1, 5, 1, 1, 2, (9, 7));
        // 3x3 SAME stride 2 (odd padding pixel after), 3x3 dilated.
        check((10, 9, 24), 1, 3, 2, 1, 0, (5, 5));
        check((8, 8, 5), 1, 3, 1, 2, 2, (8, 8));
        // Channel multiplier 2, VALID.
        check((6, 6, 3), 2, 3, 1, 1, 0, (4, 4));
    }
}
