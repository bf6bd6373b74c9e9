//! `nn.Conv2d` with diffusers' tensor names (`weight`, `bias`). 3x3
//! (padding 1) convolutions of f32 CPU tensors run by Winograd (stride 1,
//! large maps) or as one im2col product (small maps, stride 2), 1x1 ones as
//! a product per image, with the bias, a per-image bias (the ResNet's time
//! embedding) and a residual added in the same pass; other convolutions go
//! to candle's `conv2d`.

use candle_core::{Result, Tensor};
use candle_nn::VarBuilder;

use super::cpu::{self, View};
use super::im2col;
use super::winograd::{self, Start};

/// An f32 convolution of fixed kernel size and stride, "same" padding:
/// `(x, (b, c_in, h, w), weight, c_out, start)`.
type Kernel = fn(&[f32], (usize, usize, usize, usize), &[f32], usize, &Start) -> Result<Vec<f32>>;

/// Images at least this large take the Winograd path for 3x3 kernels; smaller
/// ones (SD's 8x8 level) one im2col product, where the per-call weight
/// transform would outweigh the saved products (examples/conv_bench).
const WINOGRAD_MIN_PIXELS: usize = 256;

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
        // 1x1 and 3x3 with "same" padding, at stride 1 or (3x3) 2.
        let supported = 2 * self.padding + 1 == self.kernel
            && (self.stride == 1 && self.kernel <= 3 || self.stride == 2 && self.kernel == 3);
        let all_f32 = cpu::is_cpu_f32(x)
            && cpu::is_cpu_f32(&self.weight)
            && per_image.is_none_or(cpu::is_cpu_f32)
            && residual.is_none_or(cpu::is_cpu_f32);
        if supported && all_f32 {
            return self.fast(x, per_image, residual);
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

    fn fast(
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
        let (ho, wo) = ((h - 1) / self.stride + 1, (w - 1) / self.stride + 1);
        if let Some(r) = residual
            && r.dims() != [b, c_out, ho, wo]
        {
            candle_core::bail!(
                "conv2d: residual {:?}, want [{b}, {c_out}, {ho}, {wo}]",
                r.dims()
            );
        }
        let kernel: Kernel = match (self.kernel, self.stride) {
            (1, _) => pointwise,
            (_, 2) => |x, dims, w, c_out, start| im2col::conv3x3(x, dims, w, c_out, 2, start),
            _ if h * w >= WINOGRAD_MIN_PIXELS => winograd::conv3x3,
            _ => |x, dims, w, c_out, start| im2col::conv3x3(x, dims, w, c_out, 1, start),
        };
        self.run(x, per_image, residual, (ho, wo), kernel)
    }

    /// [`Conv2d::fast`] through `kernel` on the f32 buffers (shapes already
    /// checked; the output is `(B, c_out, ho, wo)`).
    fn run(
        &self,
        x: &Tensor,
        per_image: Option<&Tensor>,
        residual: Option<&Tensor>,
        (ho, wo): (usize, usize),
        kernel: Kernel,
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
                        kernel(xs, (b, c_in, h, w), ws, c_out, &start)
                    })
                })
            })
        };
        let out = match residual {
            Some(r) => cpu::with_f32(r, |rs| run(Some(rs)))?,
            None => run(None)?,
        };
        cpu::tensor(out, &[b, c_out, ho, wo])
    }
}

/// The 1x1 convolution: one product per image, into a destination holding
/// the start terms.
fn pointwise(
    x: &[f32],
    (b, c_in, h, w): (usize, usize, usize, usize),
    weight: &[f32],
    c_out: usize,
    start: &Start,
) -> Result<Vec<f32>> {
    let hw = h * w;
    if x.len() != b * c_in * hw || weight.len() != c_out * c_in {
        candle_core::bail!("1x1 conv: buffer sizes do not match the shapes");
    }
    let mut out = vec![0f32; b * c_out * hw];
    for (i, dst_img) in out.chunks_exact_mut(c_out * hw).enumerate() {
        for (co, row) in dst_img.chunks_exact_mut(hw).enumerate() {
            let s = start.bias[co] + start.per_image.map_or(0.0, |p| p[i * c_out + co]);
            match start.residual {
                Some(r) => {
                    let r = &r[(i * c_out + co) * hw..][..hw];
                    row.iter_mut().zip(r).for_each(|(d, r)| *d = s + r)
                }
                None => row.fill(s),
            }
        }
        // SAFETY: weight (c_out x c_in), image i (c_in x hw), dst (c_out x hw).
        unsafe {
            cpu::matmul(
                (c_out, hw, c_in),
                dst_img.as_mut_ptr(),
                hw as isize,
                true,
                View {
                    ptr: weight.as_ptr(),
                    rs: c_in as isize,
                    cs: 1,
                },
                View {
                    ptr: x.as_ptr().add(i * c_in * hw),
                    rs: hw as isize,
                    cs: 1,
                },
                true,
            )
        };
    }
    Ok(out)
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
    fn fast_paths_match_candle_conv_with_fused_terms() {
        let dev = Device::Cpu;
        // 16x17 at stride 1 takes the Winograd path (at least
        // WINOGRAD_MIN_PIXELS), the other 3x3s im2col; odd and even sizes at stride 2.
        for (k, stride, h, w) in [
            (3, 1, 5, 7),
            (1, 1, 4, 3),
            (3, 1, 1, 1),
            (3, 1, 16, 17),
            (3, 2, 5, 7),
            (3, 2, 8, 8),
            (3, 2, 1, 1),
        ] {
            let c = conv(6, 5, k, stride, DType::F32);
            let x = Tensor::randn(0f32, 1.0, (2, 6, h, w), &dev).unwrap();
            let per = Tensor::randn(0f32, 1.0, (2, 5), &dev).unwrap();
            let (ho, wo) = ((h - 1) / stride + 1, (w - 1) / stride + 1);
            let res = Tensor::randn(0f32, 1.0, (2, 5, ho, wo), &dev).unwrap();
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
            let d = cpu::max_abs_diff(&fast, &slow);
            assert!(d < 1e-4, "k={k} stride {stride} {h}x{w}: {d}");
        }
    }
}
