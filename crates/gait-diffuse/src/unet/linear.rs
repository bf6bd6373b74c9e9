//! `nn.Linear` with diffusers' tensor names (`weight` `(out, in)`, optional
//! `bias`). On f32 CPU tensors the product runs through `cpu::matmul` (the
//! transposed weight read in place, the bias written into the destination
//! first); elsewhere candle's `Linear`.

use candle_core::{Module, Result, Tensor};
use candle_nn::VarBuilder;
use rayon::prelude::*;

use super::cpu::{self, View};

/// A fully connected layer over the last axis.
#[derive(Debug, Clone)]
pub struct Linear {
    inner: candle_nn::Linear,
}

/// `in_dim -> out_dim` with a bias.
pub fn linear(in_dim: usize, out_dim: usize, vb: VarBuilder) -> Result<Linear> {
    Ok(Linear {
        inner: candle_nn::linear(in_dim, out_dim, vb)?,
    })
}

/// `in_dim -> out_dim` without a bias.
pub fn linear_no_bias(in_dim: usize, out_dim: usize, vb: VarBuilder) -> Result<Linear> {
    Ok(Linear {
        inner: candle_nn::linear_no_bias(in_dim, out_dim, vb)?,
    })
}

/// `dim -> dim` with a bias whose weight may also be stored as a 1x1
/// convolution `(dim, dim, 1, 1)` (older VAE checkpoints' attention).
pub fn square_linear_or_conv1x1(dim: usize, vb: VarBuilder) -> Result<Linear> {
    let weight = match vb.get((dim, dim), "weight") {
        Ok(w) => w,
        Err(_) => vb.get((dim, dim, 1, 1), "weight")?.reshape((dim, dim))?,
    };
    Ok(Linear {
        inner: candle_nn::Linear::new(weight, Some(vb.get(dim, "bias")?)),
    })
}

impl Module for Linear {
    fn forward(&self, x: &Tensor) -> Result<Tensor> {
        let w = self.inner.weight();
        if !(cpu::is_cpu_f32(x) && self.is_cpu_f32()) {
            return self.inner.forward(x);
        }
        let (out_dim, in_dim) = w.dims2()?;
        let dims = x.dims();
        if dims.last() != Some(&in_dim) {
            candle_core::bail!("linear: input {dims:?}, weight ({out_dim}, {in_dim})");
        }
        let rows = x.elem_count() / in_dim;
        let mut out = vec![0f32; rows * out_dim];
        cpu::with_f32(x, |xs| self.apply_f32(xs, rows, &mut out, false))?;
        let mut shape = dims.to_vec();
        *shape.last_mut().expect("checked above") = out_dim;
        cpu::tensor(out, &shape)
    }
}

impl Linear {
    /// True when the weights are f32 on the CPU ([`Linear::apply_f32`]'s domain).
    pub(crate) fn is_cpu_f32(&self) -> bool {
        cpu::is_cpu_f32(self.inner.weight()) && self.inner.bias().is_none_or(cpu::is_cpu_f32)
    }

    /// `out (rows x out) = [out +] x (rows x in) W^T + bias` on f32 CPU
    /// weights; `accumulate` adds to what `out` holds (a residual).
    pub(crate) fn apply_f32(
        &self,
        xs: &[f32],
        rows: usize,
        out: &mut [f32],
        accumulate: bool,
    ) -> Result<()> {
        let w = self.inner.weight();
        let (out_dim, in_dim) = w.dims2()?;
        if xs.len() != rows * in_dim || out.len() != rows * out_dim {
            candle_core::bail!("linear: buffers do not match {rows} x ({in_dim} -> {out_dim})");
        }
        let bias = self.inner.bias().map(|b| b.to_vec1::<f32>()).transpose()?;
        if let Some(b) = &bias {
            // On all threads: the first touch of each fresh page faults.
            out.par_chunks_mut(out_dim).for_each(|row| {
                if accumulate {
                    row.iter_mut().zip(b).for_each(|(o, b)| *o += b);
                } else {
                    row.copy_from_slice(b);
                }
            });
        }
        cpu::with_f32(w, |ws| {
            // SAFETY: xs is rows x in_dim, ws is out_dim x in_dim (read
            // transposed: in_dim x out_dim), out is rows x out_dim. Without
            // a bias or residual the fresh output is written without being
            // read (reading untouched pages first costs a second fault).
            unsafe {
                cpu::matmul(
                    (rows, out_dim, in_dim),
                    out.as_mut_ptr(),
                    out_dim as isize,
                    accumulate || bias.is_some(),
                    View {
                        ptr: xs.as_ptr(),
                        rs: in_dim as isize,
                        cs: 1,
                    },
                    View {
                        ptr: ws.as_ptr(),
                        rs: 1,
                        cs: in_dim as isize,
                    },
                    true,
                )
            };
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use candle_core::{DType, Device};

    use super::*;

    #[test]
    fn matches_candle_linear_with_and_without_bias() {
        let dev = Device::Cpu;
        let mut m = HashMap::new();
        m.insert(
            "weight".to_string(),
            Tensor::randn(0f32, 1.0, (70, 50), &dev).unwrap(),
        );
        m.insert(
            "bias".to_string(),
            Tensor::randn(0f32, 1.0, 70, &dev).unwrap(),
        );
        let vb = VarBuilder::from_tensors(m, DType::F32, &dev);
        let x = Tensor::randn(0f32, 1.0, (2, 90, 50), &dev).unwrap();
        for bias in [true, false] {
            let ours = if bias {
                linear(50, 70, vb.clone()).unwrap()
            } else {
                linear_no_bias(50, 70, vb.clone()).unwrap()
            };
            let got = ours.forward(&x).unwrap();
            let want = ours.inner.forward(&x).unwrap();
            assert_eq!(got.dims(), [2, 90, 70]);
            let d = (got - want).unwrap().abs().unwrap().max_all().unwrap();
            assert!(d.to_scalar::<f32>().unwrap() < 1e-4, "bias {bias}: {d}");
        }
    }
}
