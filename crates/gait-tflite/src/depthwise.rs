//! TFLite DEPTHWISE_CONV_2D as a candle CPU op on NCHW tensors: candle's
//! grouped conv2d runs one convolution per channel, far too slow here.

use candle_core::{CpuStorage, CustomOp1, Layout, Shape, bail};

/// A depthwise convolution with its weights, bias and geometry.
pub(crate) struct Depthwise {
    /// [out_channels][kh][kw].
    pub weights: Vec<f32>,
    pub bias: Vec<f32>,
    pub kernel: (usize, usize),
    pub stride: (usize, usize),
    pub dilation: (usize, usize),
    /// Zero padding before the first row and column (TFLite SAME puts the odd one after).
    pub pad: (usize, usize),
    pub out_size: (usize, usize),
    pub multiplier: usize,
}

impl CustomOp1 for Depthwise {
    fn name(&self) -> &'static str {
        "tflite-depthwise-conv2d"
    }

    fn cpu_fwd(
        &self,
        storage: &CpuStorage,
        layout: &Layout,
    ) -> candle_core::Result<(CpuStorage, Shape)> {
        let CpuStorage::F32(data) = storage else {
            bail!("depthwise conv: f32 input expected")
        };
        let Some((a, b)) = layout.contiguous_offsets() else {
            bail!("depthwise conv: contiguous input expected")
        };
        let x = &data[a..b];
        let &[n, c, h, w] = layout.dims() else {
            bail!(
                "depthwise conv: NCHW input expected, got {:?}",
                layout.dims()
            )
        };
        let (kh, kw) = self.kernel;
        let (oh, ow) = self.out_size;
        let oc = c * self.multiplier;
        if self.weights.len() != oc * kh * kw || self.bias.len() != oc || n != 1 {
            bail!(
                "depthwise conv: weights do not fit input {:?}",
                layout.dims()
            )
        }
        let (sy, sx) = self.stride;
        let (dy, dx) = self.dilation;
        let (py, px) = (self.pad.0 as isize, self.pad.1 as isize);
        let mut out = vec![0f32; oc * oh * ow];
        // Per kernel column: the output columns whose input lies inside the image.
        let cols: Vec<(usize, usize, isize)> = (0..kw)
            .map(|kx| {
                let off_x = (kx * dx) as isize - px;
                let lo = if off_x < 0 {
                    ((-off_x) as usize).div_ceil(sx)
                } else {
                    0
                };
                let hi = if (w as isize) > off_x {
                    ((w as isize - off_x - 1) as usize / sx + 1).min(ow)
                } else {
                    0
                };
                (lo, hi.max(lo), off_x)
            })
            .collect();
        for o in 0..oc {
            let plane = &x[(o / self.multiplier) * h * w..][..h * w];
            let dst = &mut out[o * oh * ow..][..oh * ow];
            let taps = &self.weights[o * kh * kw..][..kh * kw];
            // One output row at a time, all taps while it sits in L1.
            for (oy, row) in dst.chunks_exact_mut(ow).enumerate() {
                row.fill(self.bias[o]);
                for ky in 0..kh {
                    let iy = (oy * sy + ky * dy) as isize - py;
                    if iy < 0 || iy >= h as isize {
                        continue;
                    }
                    let src = &plane[iy as usize * w..][..w];
                    for (kx, &(lo, hi, off_x)) in cols.iter().enumerate() {
                        let wv = taps[ky * kw + kx];
                        if sx == 1 {
                            let s0 = (lo as isize + off_x) as usize;
                            for (d, s) in row[lo..hi].iter_mut().zip(&src[s0..]) {
                                *d += wv * s;
                            }
                        } else {
                            for (ox, d) in row.iter_mut().enumerate().take(hi).skip(lo) {
                                *d += wv * src[((ox * sx) as isize + off_x) as usize];
                            }
                        }
                    }
                }
            }
        }
        Ok((CpuStorage::F32(out), Shape::from((1, oc, oh, ow))))
    }
}
