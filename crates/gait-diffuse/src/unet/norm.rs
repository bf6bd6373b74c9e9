//! `nn.GroupNorm` (diffusers' `norm*` tensors `weight`, `bias`), optionally
//! followed by SiLU as every ResNet and the UNet's output use it: one pass for
//! the statistics and one for normalise + affine + activation on f32 CPU
//! tensors (groups in parallel); candle's ops elsewhere.

use candle_core::{Result, Tensor};
use candle_nn::VarBuilder;
use rayon::prelude::*;

use super::cpu;

/// Group normalisation over `(B, C, ...)`.
#[derive(Debug, Clone)]
pub struct GroupNorm {
    weight: Tensor,
    bias: Tensor,
    groups: usize,
    eps: f64,
}

/// Loads `weight` and `bias` `(channels)` from `vb`.
pub fn group_norm(groups: usize, channels: usize, eps: f64, vb: VarBuilder) -> Result<GroupNorm> {
    if groups == 0 || !channels.is_multiple_of(groups) {
        candle_core::bail!("group norm: {channels} channels do not split into {groups} groups");
    }
    Ok(GroupNorm {
        weight: vb.get(channels, "weight")?,
        bias: vb.get(channels, "bias")?,
        groups,
        eps,
    })
}

impl GroupNorm {
    /// The normalised `x`, through SiLU when `silu`.
    pub fn forward(&self, x: &Tensor, silu: bool) -> Result<Tensor> {
        if cpu::is_cpu_f32(x) && cpu::is_cpu_f32(&self.weight) {
            return self.fused(x, silu);
        }
        let c = self.weight.dim(0)?;
        let gn = candle_nn::GroupNorm::new(
            self.weight.clone(),
            self.bias.clone(),
            c,
            self.groups,
            self.eps,
        )?;
        let y = x.apply(&gn)?;
        if silu {
            candle_nn::ops::silu(&y)
        } else {
            Ok(y)
        }
    }

    fn fused(&self, x: &Tensor, silu: bool) -> Result<Tensor> {
        let dims = x.dims().to_vec();
        let (b, c) = (dims[0], dims.get(1).copied().unwrap_or(1));
        if c != self.weight.dim(0)? {
            candle_core::bail!(
                "group norm: input has {c} channels, weights {}",
                self.weight.dim(0)?
            );
        }
        let spatial: usize = dims[2..].iter().product();
        let per_group = c / self.groups;
        let len = per_group * spatial;
        let mut out = vec![0f32; b * c * spatial];
        let eps = self.eps;
        cpu::with_f32(x, |xs| {
            cpu::with_f32(&self.weight, |gamma| {
                cpu::with_f32(&self.bias, |beta| {
                    out.par_chunks_mut(len)
                        .zip(xs.par_chunks(len))
                        .enumerate()
                        .for_each(|(bg, (dst, src))| {
                            // f64 sums: groups hold up to ~1e6 values.
                            let mean = src.iter().map(|&v| f64::from(v)).sum::<f64>() / len as f64;
                            let var = src
                                .iter()
                                .map(|&v| (f64::from(v) - mean).powi(2))
                                .sum::<f64>()
                                / len as f64;
                            let inv = 1.0 / (var + eps).sqrt();
                            let g0 = (bg % self.groups) * per_group;
                            for j in 0..per_group {
                                let scale = (f64::from(gamma[g0 + j]) * inv) as f32;
                                let shift = (f64::from(beta[g0 + j])
                                    - mean * f64::from(gamma[g0 + j]) * inv)
                                    as f32;
                                let s = &src[j * spatial..(j + 1) * spatial];
                                let d = &mut dst[j * spatial..(j + 1) * spatial];
                                if silu {
                                    d.iter_mut()
                                        .zip(s)
                                        .for_each(|(d, &v)| *d = cpu::silu(v * scale + shift));
                                } else {
                                    d.iter_mut()
                                        .zip(s)
                                        .for_each(|(d, &v)| *d = v * scale + shift);
                                }
                            }
                        });
                    Ok(())
                })
            })
        })?;
        cpu::tensor(out, &dims)
    }
}

#[cfg(test)]
mod tests {
    use candle_core::{DType, Device, Tensor};

    use super::*;

    #[test]
    fn fused_path_matches_candle_group_norm_and_silu() {
        let dev = Device::Cpu;
        let x = Tensor::randn(1.5f32, 3.0, (2, 8, 5, 3), &dev).unwrap();
        let gn = GroupNorm {
            weight: Tensor::randn(1f32, 0.2, 8, &dev).unwrap(),
            bias: Tensor::randn(0f32, 0.2, 8, &dev).unwrap(),
            groups: 4,
            eps: 1e-5,
        };
        let g64 = GroupNorm {
            weight: gn.weight.to_dtype(DType::F64).unwrap(),
            bias: gn.bias.to_dtype(DType::F64).unwrap(),
            ..gn.clone()
        };
        for silu in [false, true] {
            let fast = gn.forward(&x, silu).unwrap();
            let slow = g64.forward(&x.to_dtype(DType::F64).unwrap(), silu).unwrap();
            let d = cpu::max_abs_diff(&fast.to_dtype(DType::F64).unwrap(), &slow);
            assert!(d < 1e-5, "silu {silu}: {d}");
        }
    }
}
