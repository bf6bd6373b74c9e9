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

impl Module for Linear {
    fn forward(&self, x: &Tensor) -> Result<Tensor> {
        let w = self.inner.weight();
        let fast = cpu::is_cpu_f32(x)
            && cpu::is_cpu_f32(w)
            && self.inner.bias().is_none_or(cpu::is_cpu_f32);
        if !fast {
            return self.inner.forward(x);
        }
        let (out_dim, in_dim) = w.dims2()?;
        let dims = x.dims();
        if dims.last() != Some(&in_dim) {
            candle_core::bail!("linear: input {dims:?}, weight ({out_dim}, {in_dim})");
        }
        let rows = x.elem_count() / in_dim;
        // Without a bias the product writes the fresh buffer without reading
        // it (reading untouched pages first costs a second fault per page).
        let bias = self.inner.bias();
        let mut out = vec![0f32; rows * out_dim];
        if let Some(b) = bias {
            // Filled on all threads: the first touch of each page faults.
            let b = b.to_vec1::<f32>()?;
            out.par_chunks_mut(out_dim)
                .for_each(|row| row.copy_from_slice(&b));
        }
        cpu::with_f32(x, |xs| {
            cpu::with_f32(w, |ws| {
                // SAFETY: xs is rows x in_dim, ws is out_dim x in_dim (read
                // transposed: in_dim x out_dim), out is rows x out_dim.
                unsafe {
                    cpu::matmul(
                        (rows, out_dim, in_dim),
                        out.as_mut_ptr(),
                        out_dim as isize,
                        bias.is_some(),
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
        })?;
        let mut shape = dims.to_vec();
        *shape.last_mut().expect("checked above") = out_dim;
        cpu::tensor(out, &shape)
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
