//! diffusers' `UNet2DConditionModel` (SD 1.x/2.x layout): `conv_in`, the
//! [`Encoder`] (time embedding, down stages, mid block), up stages fed the
//! skip states in reverse, `conv_norm_out` + SiLU + `conv_out`; with a
//! ControlNet's residuals added to the skip states and the mid block output.

use candle_core::{Result, Tensor};
use candle_nn::VarBuilder;

use super::blocks::UpBlock;
use super::conv::{Conv2d, conv2d};
use super::encoder::{Encoder, common, stages};
use super::norm::{GroupNorm, group_norm};
use crate::controlnet::ControlResiduals;
use crate::model_config::UnetConfig;

/// The denoising UNet of Stable Diffusion.
#[derive(Debug, Clone)]
pub struct UNet2DConditionModel {
    conv_in: Conv2d,
    encoder: Encoder,
    up: Vec<UpBlock>,
    norm_out: GroupNorm,
    conv_out: Conv2d,
}

impl UNet2DConditionModel {
    /// Builds the model from `vb` (diffusers' tensor names); `in_channels`
    /// comes from the config (4 for SD 1.5, 9 for inpainting UNets).
    pub fn new(vb: VarBuilder, cfg: &UnetConfig) -> Result<Self> {
        let st = stages(cfg)?;
        let c = common(cfg)?;
        let ch0 = st[0].channels;
        let encoder = Encoder::new(vb.clone(), cfg)?;
        // Channels of the skip states in the order the down path makes them.
        let mut skip_ch = vec![ch0];
        for (i, s) in st.iter().enumerate() {
            let n = cfg.layers_per_block + usize::from(i + 1 < st.len());
            skip_ch.extend(std::iter::repeat_n(s.channels, n));
        }
        let mut up = Vec::with_capacity(st.len());
        let mut prev = st[st.len() - 1].channels;
        for (i, s) in st.iter().rev().enumerate() {
            let layers = cfg.layers_per_block + 1;
            let split = skip_ch.len().saturating_sub(layers);
            let mut skips: Vec<usize> = skip_ch.split_off(split);
            skips.reverse();
            let last = i + 1 == st.len();
            up.push(UpBlock::new(
                vb.pp("up_blocks").pp(i),
                &c,
                prev,
                s.channels,
                &skips,
                s.heads,
                !last,
            )?);
            prev = s.channels;
        }
        Ok(Self {
            conv_in: conv2d(cfg.in_channels, ch0, 3, 1, 1, vb.pp("conv_in"))?,
            encoder,
            up,
            norm_out: group_norm(
                cfg.norm_num_groups,
                ch0,
                cfg.norm_eps,
                vb.pp("conv_norm_out"),
            )?,
            conv_out: conv2d(ch0, cfg.out_channels, 3, 1, 1, vb.pp("conv_out"))?,
        })
    }

    /// The noise prediction for `sample` `(B, in_channels, h, w)` at `timestep`
    /// under the text `context` `(B, n, dim)`.
    pub fn forward(&self, sample: &Tensor, timestep: f64, context: &Tensor) -> Result<Tensor> {
        self.run(sample, timestep, context, None)
    }

    /// As [`Self::forward`], with a ControlNet's residuals added.
    pub fn forward_with_residuals(
        &self,
        sample: &Tensor,
        timestep: f64,
        context: &Tensor,
        residuals: &ControlResiduals,
    ) -> Result<Tensor> {
        self.run(sample, timestep, context, Some(residuals))
    }

    fn run(
        &self,
        sample: &Tensor,
        timestep: f64,
        ctx: &Tensor,
        res: Option<&ControlResiduals>,
    ) -> Result<Tensor> {
        let temb = self.encoder.time(timestep, sample)?;
        let x = self.conv_in.forward(sample)?;
        let (x, mut skips) = self.encoder.down(x, &temb, ctx)?;
        let mut x = self.encoder.mid(&x, &temb, ctx)?;
        if let Some(r) = res {
            if r.down.len() != skips.len() {
                candle_core::bail!(
                    "ControlNet gives {} residuals, the UNet has {} skip connections",
                    r.down.len(),
                    skips.len()
                );
            }
            skips = skips
                .iter()
                .zip(&r.down)
                .map(|(s, d)| s + d)
                .collect::<Result<Vec<_>>>()?;
            x = (x + &r.mid)?;
        }
        for block in &self.up {
            // Upsample to the size of the skip state the next stage starts with.
            let next = skips
                .len()
                .checked_sub(block.num_skips() + 1)
                .and_then(|i| skips.get(i));
            let size = next
                .map(|t| t.dims4())
                .transpose()?
                .map(|(_, _, h, w)| (h, w));
            x = block.forward(&x, &mut skips, &temb, ctx, size)?;
        }
        let x = self.norm_out.forward(&x, true)?;
        self.conv_out.forward(&x)
    }

    /// Skip connections a ControlNet must supply residuals for.
    pub fn num_skips(&self) -> usize {
        self.encoder.num_states()
    }
}
