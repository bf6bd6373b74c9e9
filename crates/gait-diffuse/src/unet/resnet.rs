//! diffusers' `ResnetBlock2D`: GroupNorm, SiLU, 3x3 convolution, plus the
//! projected time embedding; GroupNorm, SiLU, 3x3 convolution; added to the
//! input (through a 1x1 `conv_shortcut` when the channel count changes).

use candle_core::{Module, Result, Tensor};
use candle_nn::{Linear, VarBuilder, linear};

use super::conv::{Conv2d, conv2d};
use super::norm::{GroupNorm, group_norm};

/// One residual block.
#[derive(Debug, Clone)]
pub struct ResnetBlock2D {
    norm1: GroupNorm,
    conv1: Conv2d,
    time_emb_proj: Option<Linear>,
    norm2: GroupNorm,
    conv2: Conv2d,
    conv_shortcut: Option<Conv2d>,
    output_scale: f64,
}

/// Shape of one [`ResnetBlock2D`].
#[derive(Debug, Clone, Copy)]
pub struct ResnetSpec {
    pub c_in: usize,
    pub c_out: usize,
    /// Width of the time embedding, `None` for blocks without one.
    pub temb: Option<usize>,
    pub groups: usize,
    pub eps: f64,
    pub output_scale: f64,
}

impl ResnetBlock2D {
    pub fn new(vb: VarBuilder, s: &ResnetSpec) -> Result<Self> {
        let conv_shortcut = if s.c_in != s.c_out {
            Some(conv2d(s.c_in, s.c_out, 1, 1, 0, vb.pp("conv_shortcut"))?)
        } else {
            None
        };
        Ok(Self {
            norm1: group_norm(s.groups, s.c_in, s.eps, vb.pp("norm1"))?,
            conv1: conv2d(s.c_in, s.c_out, 3, 1, 1, vb.pp("conv1"))?,
            time_emb_proj: s
                .temb
                .map(|t| linear(t, s.c_out, vb.pp("time_emb_proj")))
                .transpose()?,
            norm2: group_norm(s.groups, s.c_out, s.eps, vb.pp("norm2"))?,
            conv2: conv2d(s.c_out, s.c_out, 3, 1, 1, vb.pp("conv2"))?,
            conv_shortcut,
            output_scale: s.output_scale,
        })
    }

    /// `x` `(B, C, H, W)`; `temb_silu` is SiLU of the time embedding `(B, T)`
    /// (the same for every block, so the caller computes it once).
    pub fn forward(&self, x: &Tensor, temb_silu: Option<&Tensor>) -> Result<Tensor> {
        let t = match (&self.time_emb_proj, temb_silu) {
            (Some(p), Some(t)) => Some(p.forward(t)?),
            _ => None,
        };
        let h = self
            .conv1
            .forward_with(&self.norm1.forward(x, true)?, t.as_ref(), None)?;
        let shortcut = match &self.conv_shortcut {
            Some(c) => c.forward(x)?,
            None => x.clone(),
        };
        let y = self
            .conv2
            .forward_with(&self.norm2.forward(&h, true)?, None, Some(&shortcut))?;
        if self.output_scale == 1.0 {
            Ok(y)
        } else {
            y / self.output_scale
        }
    }
}
