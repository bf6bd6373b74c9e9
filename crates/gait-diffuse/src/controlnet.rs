//! ControlNet (Zhang et al. 2023) with diffusers' `ControlNetModel` structure
//! and tensor names: a trainable copy of the UNet's encoder, fed the latent
//! plus an embedding of the condition image, whose per-resolution outputs pass
//! through zero-initialised 1x1 convolutions into the UNet's skip connections.

use candle_core::{Result, Tensor};
use candle_nn::VarBuilder;

use crate::model_config::UnetConfig;
use crate::unet::encoder::Encoder;
use crate::unet::{CacheBranch, Conv2d, conv2d};

/// Residuals a ControlNet adds to the UNet: one per skip connection, and one
/// for the mid block. A call for DeepCache's shallow step gives the first
/// skip connections' only, and no mid residual.
#[derive(Debug, Clone)]
pub struct ControlResiduals {
    pub down: Vec<Tensor>,
    pub mid: Option<Tensor>,
}

impl ControlResiduals {
    /// Sums the residuals of several ControlNets (multi-condition control).
    pub fn add(&self, other: &ControlResiduals) -> Result<ControlResiduals> {
        let down = self
            .down
            .iter()
            .zip(&other.down)
            .map(|(a, b)| a + b)
            .collect::<Result<Vec<_>>>()?;
        let mid = match (&self.mid, &other.mid) {
            (Some(a), Some(b)) => Some((a + b)?),
            _ => None,
        };
        Ok(ControlResiduals { down, mid })
    }
}

/// `controlnet_cond_embedding`: strided 3x3 convolutions bringing the
/// condition image down to the latent resolution.
#[derive(Debug)]
struct CondEmbedding {
    conv_in: Conv2d,
    blocks: Vec<Conv2d>,
    conv_out: Conv2d,
}

impl CondEmbedding {
    fn new(vb: VarBuilder, cond_channels: usize, channels: &[usize], out: usize) -> Result<Self> {
        let first = channels.first().copied().unwrap_or(16);
        let conv_in = conv2d(cond_channels, first, 3, 1, 1, vb.pp("conv_in"))?;
        let mut blocks = Vec::new();
        let vbb = vb.pp("blocks");
        for (i, pair) in channels.windows(2).enumerate() {
            blocks.push(conv2d(pair[0], pair[0], 3, 1, 1, vbb.pp(2 * i))?);
            blocks.push(conv2d(pair[0], pair[1], 3, 2, 1, vbb.pp(2 * i + 1))?);
        }
        let last = channels.last().copied().unwrap_or(first);
        let conv_out = conv2d(last, out, 3, 1, 1, vb.pp("conv_out"))?;
        Ok(Self {
            conv_in,
            blocks,
            conv_out,
        })
    }

    fn forward(&self, cond: &Tensor) -> Result<Tensor> {
        let mut x = candle_nn::ops::silu(&self.conv_in.forward(cond)?)?;
        for b in &self.blocks {
            x = candle_nn::ops::silu(&b.forward(&x)?)?;
        }
        self.conv_out.forward(&x)
    }
}

/// diffusers' `ControlNetModel` (SD 1.x/2.x layout, no class embedding).
#[derive(Debug)]
pub struct ControlNet {
    conv_in: Conv2d,
    cond_embedding: CondEmbedding,
    encoder: Encoder,
    zero_convs: Vec<Conv2d>,
    mid_zero_conv: Conv2d,
}

impl ControlNet {
    /// Builds the model from `vb` (tensor names as in diffusers' safetensors).
    pub fn new(vb: VarBuilder, cfg: &UnetConfig) -> Result<Self> {
        let encoder = Encoder::new(vb.clone(), cfg)?;
        let ch0 = cfg.block_out_channels.first().copied().unwrap_or(320);
        let cond_embedding = CondEmbedding::new(
            vb.pp("controlnet_cond_embedding"),
            cfg.conditioning_channels,
            &cfg.conditioning_embedding_out_channels,
            ch0,
        )?;
        // One zero convolution per skip state: conv_in's, then each stage's.
        let zc = vb.pp("controlnet_down_blocks");
        let mut channels = vec![ch0];
        let n = cfg.block_out_channels.len();
        for (i, &c) in cfg.block_out_channels.iter().enumerate() {
            let states = cfg.layers_per_block + usize::from(i + 1 < n);
            channels.extend(std::iter::repeat_n(c, states));
        }
        let zero_convs = channels
            .iter()
            .enumerate()
            .map(|(k, &c)| conv2d(c, c, 1, 1, 0, zc.pp(k)))
            .collect::<Result<Vec<_>>>()?;
        let last = cfg.block_out_channels.last().copied().unwrap_or(ch0);
        Ok(Self {
            conv_in: conv2d(cfg.in_channels, ch0, 3, 1, 1, vb.pp("conv_in"))?,
            cond_embedding,
            encoder,
            zero_convs,
            mid_zero_conv: conv2d(last, last, 1, 1, 0, vb.pp("controlnet_mid_block"))?,
        })
    }

    /// Residuals for the UNet at `timestep`, scaled by `scale` (diffusers'
    /// `controlnet_conditioning_scale`). `cond` is the condition image in [0, 1]
    /// at 8x the latent size.
    pub fn forward(
        &self,
        sample: &Tensor,
        timestep: f64,
        context: &Tensor,
        cond: &Tensor,
        scale: f64,
    ) -> Result<ControlResiduals> {
        let temb = self.encoder.time(timestep, sample)?;
        let x = self.embed(sample, cond)?;
        let (x, states) = self.encoder.down(x, &temb, context, None)?;
        let mid = self.encoder.mid(&x, &temb, context, None)?;
        let mid = (self.mid_zero_conv.forward(&mid)? * scale)?;
        Ok(ControlResiduals {
            down: self.zero_convs(&states, scale)?,
            mid: Some(mid),
        })
    }

    /// The residuals of DeepCache's shallow step on `branch` only: the first
    /// skip connections' (the others would go to cached layers). Stock
    /// DeepCache runs the whole ControlNet and drops the rest; these are the
    /// same numbers. A branch that needs every skip state gets a full call.
    pub fn forward_shallow(
        &self,
        sample: &Tensor,
        timestep: f64,
        context: &Tensor,
        cond: &Tensor,
        scale: f64,
        branch: CacheBranch,
    ) -> Result<ControlResiduals> {
        if self.encoder.shallow_states(branch) >= self.zero_convs.len() {
            return self.forward(sample, timestep, context, cond, scale);
        }
        let temb = self.encoder.time(timestep, sample)?;
        let x = self.embed(sample, cond)?;
        let states = self.encoder.down_shallow(x, &temb, context, branch, None)?;
        Ok(ControlResiduals {
            down: self.zero_convs(&states, scale)?,
            mid: None,
        })
    }

    /// `conv_in` of the latents plus the condition image's embedding.
    fn embed(&self, sample: &Tensor, cond: &Tensor) -> Result<Tensor> {
        let emb = self.cond_embedding.forward(cond)?;
        self.conv_in.forward_with(sample, None, Some(&emb))
    }

    /// Each state through its zero convolution, times `scale`.
    fn zero_convs(&self, states: &[Tensor], scale: f64) -> Result<Vec<Tensor>> {
        states
            .iter()
            .zip(&self.zero_convs)
            .map(|(r, c)| c.forward(r)? * scale)
            .collect()
    }

    /// Number of skip-connection residuals (12 for SD 1.5).
    pub fn num_residuals(&self) -> usize {
        self.zero_convs.len()
    }
}
