//! The timestep embedding: diffusers' sinusoidal `Timesteps` (`time_proj`,
//! no weights) and the two-layer `TimestepEmbedding` (`time_embedding`).

use candle_core::{DType, Device, Module, Result, Tensor};
use candle_nn::{Linear, VarBuilder, linear};

/// Sinusoidal features of a timestep.
#[derive(Debug, Clone)]
pub struct Timesteps {
    channels: usize,
    flip_sin_to_cos: bool,
    freq_shift: f64,
}

impl Timesteps {
    pub fn new(channels: usize, flip_sin_to_cos: bool, freq_shift: f64) -> Self {
        Self {
            channels,
            flip_sin_to_cos,
            freq_shift,
        }
    }

    /// `(batch, channels)` features of `timestep` in `dtype`, computed in f32
    /// as diffusers does (the products reach ~1000, where f32 rounding shows).
    pub fn forward(
        &self,
        timestep: f64,
        batch: usize,
        dtype: DType,
        device: &Device,
    ) -> Result<Tensor> {
        let half = self.channels / 2;
        let t = timestep as f32;
        let denom = half as f64 - self.freq_shift;
        let args: Vec<f32> = (0..half)
            .map(|i| {
                let exponent = (-(10000f64.ln()) * i as f64 / denom) as f32;
                t * f64::from(exponent).exp() as f32
            })
            .collect();
        let sin = args.iter().map(|&a| f64::from(a).sin() as f32);
        let cos = args.iter().map(|&a| f64::from(a).cos() as f32);
        let mut row: Vec<f32> = if self.flip_sin_to_cos {
            cos.chain(sin).collect()
        } else {
            sin.chain(cos).collect()
        };
        // An odd channel count gets a zero column, as in diffusers.
        row.resize(self.channels, 0.0);
        let data: Vec<f32> = (0..batch).flat_map(|_| row.iter().copied()).collect();
        Tensor::from_vec(data, (batch, self.channels), device)?.to_dtype(dtype)
    }
}

/// `linear_1`, SiLU, `linear_2`.
#[derive(Debug, Clone)]
pub struct TimestepEmbedding {
    linear_1: Linear,
    linear_2: Linear,
}

impl TimestepEmbedding {
    pub fn new(vb: VarBuilder, c_in: usize, c_out: usize) -> Result<Self> {
        Ok(Self {
            linear_1: linear(c_in, c_out, vb.pp("linear_1"))?,
            linear_2: linear(c_out, c_out, vb.pp("linear_2"))?,
        })
    }

    pub fn forward(&self, x: &Tensor) -> Result<Tensor> {
        let h = candle_nn::ops::silu(&self.linear_1.forward(x)?)?;
        self.linear_2.forward(&h)
    }
}
