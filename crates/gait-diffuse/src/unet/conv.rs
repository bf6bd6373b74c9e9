//! `nn.Conv2d` with diffusers' tensor names (`weight`, `bias`). Stride-1
//! 3x3 (padding 1) and 1x1 convolutions of f32 CPU tensors run as shifted
//! matrix products over a zero-padded copy of each image (no im2col matrix),
//! with the bias, a per-image bias (the ResNet's time embedding) and a
//! residual written into the product's destination first, so they cost no
//! extra pass; other convolutions go to candle's `conv2d`.

use candle_core::{Result, Tensor};
use candle_nn::VarBuilder;

use super::cpu::{self, View};
use super::winograd::{self, Start};

/// Images at least this large take the Winograd path for 3x3 kernels (below
/// it, SD's 8x8 level, the per-call weight transform outweighs the saved
/// products: examples/conv_bench).
const WINOGRAD_MIN_PIXELS: usize = 64;

/// A 2-D convolution (square kernel).
#[derive(Debug, Clone)]
pub struct Conv2d {
    weight: Tensor,
    bias: Tensor,
    kernel: usize,
    stride: usize,
    padding: usize,
}

/// Loads `weight` `(c_out, c_in, k, k)` and `bias` `(c_out)` from `vb`.
pub fn conv2d(
    c_in: usize,
    c_out: usize,
    kernel: usize,
    stride: usize,
    padding: usize,
    vb: VarBuilder,
) -> Result<Conv2d> {
    Ok(Conv2d {
        weight: vb.get((c_out, c_in, kernel, kernel), "weight")?,
        bias: vb.get(c_out, "bias")?,
        kernel,
        stride,
        padding,
    })
}

impl Conv2d {
    /// The convolution of `x` `(B, c_in, H, W)`.
    pub fn forward(&self, x: &Tensor) -> Result<Tensor> {
        self.forward_with(x, None, None)
    }

    /// `conv(x) + per_image[:, :, None, None] + residual`, where `per_image`
    /// is `(B, c_out)` and `residual` has the output's shape.
    pub fn forward_with(
        &self,
        x: &Tensor,
        per_image: Option<&Tensor>,
        residual: Option<&Tensor>,
    ) -> Result<Tensor> {
        let shifted = self.stride == 1 && 2 * self.padding + 1 == self.kernel && self.kernel <= 3;
        let all_f32 = cpu::is_cpu_f32(x)
            && cpu::is_cpu_f32(&self.weight)
            && per_image.is_none_or(cpu::is_cpu_f32)
            && residual.is_none_or(cpu::is_cpu_f32);
        if shifted && all_f32 {
            return self.shifted(x, per_image, residual);
        }
        let c_out = self.weight.dim(0)?;
        let y = x.conv2d(&self.weight, self.padding, self.stride, 1, 1)?;
        let mut y = y.broadcast_add(&self.bias.reshape((1, c_out, 1, 1))?)?;
        if let Some(p) = per_image {
            y = y.broadcast_add(&p.unsqueeze(2)?.unsqueeze(3)?)?;
        }
        match residual {
            Some(r) => y + r,
            None => Ok(y),
        }
    }

    fn shifted(
        &self,
        x: &Tensor,
        per_image: Option<&Tensor>,
        residual: Option<&Tensor>,
    ) -> Result<Tensor> {
        let (b, c_in, h, w) = x.dims4()?;
        let (c_out, wc_in, _, _) = self.weight.dims4()?;
        if wc_in != c_in {
            candle_core::bail!("conv2d: input has {c_in} channels, weight expects {wc_in}");
        }
        if let Some(p) = per_image
            && p.dims() != [b, c_out]
        {
            candle_core::bail!("conv2d: per-image bias {:?}, want [{b}, {c_out}]", p.dims());
        }
        if let Some(r) = residual
            && r.dims() != [b, c_out, h, w]
        {
            candle_core::bail!(
                "conv2d: residual {:?}, want [{b}, {c_out}, {h}, {w}]",
                r.dims()
            );
        }
        let k = self.kernel;
        if k == 3 && h * w >= WINOGRAD_MIN_PIXELS {
            return self.winograd(x, per_image, residual);
        }
        let pad = self.padding;
        let (wp, hp) = (w + 2 * pad, h + 2 * pad);
        // Output columns run over the padded width; the last 2*pad of each row are dropped.
        let n = h * wp;
        // Per-channel stride of the padded copy: the last tap reads 2*pad past the image.
        let plane = hp * wp + 2 * pad;
        let mut out = vec![0f32; b * c_out * h * w];
        cpu::with_f32(x, |xs| {
            cpu::with_f32(&self.weight, |ws| {
                cpu::with_f32(&self.bias, |bias| {
                    let per = per_image.map(|p| p.flatten_all()).transpose()?;
                    let res = residual.map(|r| r.flatten_all()).transpose()?;
                    let per_v = per.as_ref().map(|p| p.to_vec1::<f32>()).transpose()?;
                    let res_v = res.map(|r| r.contiguous()).transpose()?;
                    let mut run = |res_s: Option<&[f32]>| -> Result<()> {
                        let mut padded = vec![0f32; if pad > 0 { c_in * plane } else { 0 }];
                        let mut acc = vec![0f32; if pad > 0 { c_out * n } else { 0 }];
                        for i in 0..b {
                            let img = &xs[i * c_in * h * w..(i + 1) * c_in * h * w];
                            let dst_img = &mut out[i * c_out * h * w..(i + 1) * c_out * h * w];
                            // Start value: bias + per-image bias + residual.
                            let start = |co: usize| {
                                bias[co] + per_v.as_ref().map_or(0.0, |p| p[i * c_out + co])
                            };
                            let res_img =
                                res_s.map(|r| &r[i * c_out * h * w..(i + 1) * c_out * h * w]);
                            if pad == 0 {
                                for co in 0..c_out {
                                    let s = start(co);
                                    let row = &mut dst_img[co * h * w..(co + 1) * h * w];
                                    match res_img {
                                        Some(r) => row
                                            .iter_mut()
                                            .zip(&r[co * h * w..(co + 1) * h * w])
                                            .for_each(|(d, r)| *d = s + r),
                                        None => row.fill(s),
                                    }
                                }
                                // SAFETY: weight (c_out x c_in), image (c_in x hw), dst (c_out x hw).
                                unsafe {
                                    cpu::matmul(
                                        (c_out, h * w, c_in),
                                        dst_img.as_mut_ptr(),
                                        (h * w) as isize,
                                        true,
                                        View {
                                            ptr: ws.as_ptr(),
                                            rs: c_in as isize,
                                            cs: 1,
                                        },
                                        View {
                                            ptr: img.as_ptr(),
                                            rs: (h * w) as isize,
                                            cs: 1,
                                        },
                                        true,
                                    )
                                };
                                continue;
                            }
                            for ci in 0..c_in {
                                for y in 0..h {
                                    let src = &img[(ci * h + y) * w..(ci * h + y + 1) * w];
                                    let o = ci * plane + (y + pad) * wp + pad;
                                    padded[o..o + w].copy_from_slice(src);
                                }
                            }
                            for co in 0..c_out {
                                let s = start(co);
                                for y in 0..h {
                                    let row = &mut acc[co * n + y * wp..co * n + y * wp + w];
                                    match res_img {
                                        Some(r) => {
                                            let rr = &r[(co * h + y) * w..(co * h + y + 1) * w];
                                            row.iter_mut().zip(rr).for_each(|(d, r)| *d = s + r)
                                        }
                                        None => row.fill(s),
                                    }
                                }
                            }
                            for ky in 0..k {
                                for kx in 0..k {
                                    let tap = ky * k + kx;
                                    // SAFETY: the weight view (c_out x c_in) steps k*k per input
                                    // channel; the image view (c_in x n) starts at the tap's
                                    // offset and ends at most 2*pad past the padded plane,
                                    // inside `plane`; acc is c_out x n.
                                    unsafe {
                                        cpu::matmul(
                                            (c_out, n, c_in),
                                            acc.as_mut_ptr(),
                                            n as isize,
                                            true,
                                            View {
                                                ptr: ws.as_ptr().add(tap),
                                                rs: (c_in * k * k) as isize,
                                                cs: (k * k) as isize,
                                            },
                                            View {
                                                ptr: padded.as_ptr().add(ky * wp + kx),
                                                rs: plane as isize,
                                                cs: 1,
                                            },
                                            true,
                                        )
                                    };
                                }
                            }
                            for co in 0..c_out {
                                for y in 0..h {
                                    let src = &acc[co * n + y * wp..co * n + y * wp + w];
                                    dst_img[(co * h + y) * w..(co * h + y + 1) * w]
                                        .copy_from_slice(src);
                                }
                            }
                        }
                        Ok(())
                    };
                    match &res_v {
                        Some(r) => cpu::with_f32(r, |rs| run(Some(rs))),
                        None => run(None),
                    }
                })
            })
        })?;
        cpu::tensor(out, &[b, c_out, h, w])
    }

    /// The 3x3 case of [`Conv2d::shifted`] by Winograd's F(2x2, 3x3)
    /// (shapes already checked).
    fn winograd(
        &self,
        x: &Tensor,
        per_image: Option<&Tensor>,
        residual: Option<&Tensor>,
    ) -> Result<Tensor> {
        let (b, c_in, h, w) = x.dims4()?;
        let c_out = self.weight.dim(0)?;
        let per_v = per_image
            .map(|p| p.flatten_all()?.to_vec1::<f32>())
            .transpose()?;
        let run = |res: Option<&[f32]>| {
            cpu::with_f32(x, |xs| {
                cpu::with_f32(&self.weight, |ws| {
                    cpu::with_f32(&self.bias, |bias| {
                        let start = Start {
                            bias,
                            per_image: per_v.as_deref(),
                            residual: res,
                        };
                        winograd::conv3x3(xs, (b, c_in, h, w), ws, c_out, &start)
                    })
                })
            })
        };
        let out = match residual {
            Some(r) => cpu::with_f32(r, |rs| run(Some(rs)))?,
            None => run(None)?,
        };
        cpu::tensor(out, &[b, c_out, h, w])
    }
}

#[cfg(test)]
mod tests {
    use candle_core::{DType, Device, Tensor};

    use super::*;

    fn conv(c_in: usize, c_out: usize, k: usize, stride: usize, dtype: DType) -> Conv2d {
        let dev = Device::Cpu;
        Conv2d {
            weight: Tensor::randn(0f32, 1.0, (c_out, c_in, k, k), &dev)
                .unwrap()
                .to_dtype(dtype)
                .unwrap(),
            bias: Tensor::randn(0f32, 1.0, c_out, &dev)
                .unwrap()
                .to_dtype(dtype)
                .unwrap(),
            kernel: k,
            stride,
            padding: k / 2,
        }
    }

    #[test]
    fn shifted_products_match_candle_conv_with_fused_terms() {
        let dev = Device::Cpu;
        // 9x8 takes the Winograd path (at least WINOGRAD_MIN_PIXELS).
        for (k, h, w) in [(3, 5, 7), (1, 4, 3), (3, 1, 1), (3, 9, 8)] {
            let c = conv(6, 5, k, 1, DType::F32);
            let x = Tensor::randn(0f32, 1.0, (2, 6, h, w), &dev).unwrap();
            let per = Tensor::randn(0f32, 1.0, (2, 5), &dev).unwrap();
            let res = Tensor::randn(0f32, 1.0, (2, 5, h, w), &dev).unwrap();
            let fast = c.forward_with(&x, Some(&per), Some(&res)).unwrap();
            // The same through candle's ops (f64 takes the fallback).
            let c64 = Conv2d {
                weight: c.weight.to_dtype(DType::F64).unwrap(),
                bias: c.bias.to_dtype(DType::F64).unwrap(),
                ..c.clone()
            };
            let slow = c64
                .forward_with(
                    &x.to_dtype(DType::F64).unwrap(),
                    Some(&per.to_dtype(DType::F64).unwrap()),
                    Some(&res.to_dtype(DType::F64).unwrap()),
                )
                .unwrap()
                .to_dtype(DType::F32)
                .unwrap();
            let d = (fast - slow)
                .unwrap()
                .abs()
                .unwrap()
                .max_all()
                .unwrap()
                .to_scalar::<f32>()
                .unwrap();
            assert!(d < 1e-4, "k={k} {h}x{w}: {d}");
        }
    }
}
