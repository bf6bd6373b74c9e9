//! The VAE encoder of SD 1.5 (diffusers' `AutoencoderKL.encode`), built from
//! candle-transformers' public blocks: candle's own `AutoEncoderKL::encode`
//! only hands back an unseeded sample, while image-to-image and inpainting
//! need the distribution's mean and standard deviation to draw a seeded one.

use candle_core::{Module, Result, Tensor};
use candle_nn as nn;
use candle_transformers::models::stable_diffusion::unet_2d_blocks::{
    DownEncoderBlock2D, DownEncoderBlock2DConfig, UNetMidBlock2D, UNetMidBlock2DConfig,
};

use crate::model_config::VaeConfig;

/// Encoder + `quant_conv` of an `AutoencoderKL` (tensor names `encoder.*`, `quant_conv.*`).
#[derive(Debug)]
pub struct VaeEncoder {
    conv_in: nn::Conv2d,
    down: Vec<DownEncoderBlock2D>,
    mid: UNetMidBlock2D,
    norm_out: nn::GroupNorm,
    conv_out: nn::Conv2d,
    quant_conv: Option<nn::Conv2d>,
}

impl VaeEncoder {
    /// Loads from a VarBuilder at the root of the VAE's safetensors.
    pub fn new(vb: nn::VarBuilder, cfg: &VaeConfig) -> Result<Self> {
        let ch = &cfg.block_out_channels;
        let first = *ch.first().ok_or_else(|| {
            candle_core::Error::Msg("VAE config has no block_out_channels".into())
        })?;
        let last = ch[ch.len() - 1];
        let pad1 = nn::Conv2dConfig {
            padding: 1,
            ..Default::default()
        };
        let venc = vb.pp("encoder");
        let conv_in = nn::conv2d(3, first, 3, pad1, venc.pp("conv_in"))?;
        let mut down = Vec::with_capacity(ch.len());
        for (i, &out) in ch.iter().enumerate() {
            let cfg = DownEncoderBlock2DConfig {
                num_layers: cfg.layers_per_block,
                resnet_eps: 1e-6,
                resnet_groups: cfg.norm_num_groups,
                add_downsample: i + 1 < ch.len(),
                // diffusers pads (0, 1, 0, 1) then convolves without padding.
                downsample_padding: 0,
                ..Default::default()
            };
            let input = if i == 0 { first } else { ch[i - 1] };
            down.push(DownEncoderBlock2D::new(
                venc.pp("down_blocks").pp(i.to_string()),
                input,
                out,
                cfg,
            )?);
        }
        let mid_cfg = UNetMidBlock2DConfig {
            resnet_eps: 1e-6,
            output_scale_factor: 1.0,
            attn_num_head_channels: None,
            resnet_groups: Some(cfg.norm_num_groups),
            ..Default::default()
        };
        let mid = UNetMidBlock2D::new(venc.pp("mid_block"), last, None, mid_cfg)?;
        let norm_out = nn::group_norm(cfg.norm_num_groups, last, 1e-6, venc.pp("conv_norm_out"))?;
        let z = 2 * cfg.latent_channels;
        let conv_out = nn::conv2d(last, z, 3, pad1, venc.pp("conv_out"))?;
        let quant_conv = if cfg.use_quant_conv {
            Some(nn::conv2d(
                z,
                z,
                1,
                Default::default(),
                vb.pp("quant_conv"),
            )?)
        } else {
            None
        };
        Ok(Self {
            conv_in,
            down,
            mid,
            norm_out,
            conv_out,
            quant_conv,
        })
    }

    /// Mean and standard deviation `(B, 4, H/8, W/8)` of the latent
    /// distribution of images `(B, 3, H, W)` in [-1, 1] (log-variance clamped
    /// to [-30, 20] as diffusers does).
    pub fn encode(&self, images: &Tensor) -> Result<(Tensor, Tensor)> {
        // One image at a time: candle-transformers 0.11.1's mid-block
        // attention mixes the images of a batch (see models.rs, decode).
        let mut means = Vec::new();
        let mut stds = Vec::new();
        for i in 0..images.dim(0)? {
            let mut x = images.narrow(0, i, 1)?.apply(&self.conv_in)?;
            for block in &self.down {
                x = block.forward(&x)?;
            }
            let x = self.mid.forward(&x, None)?.apply(&self.norm_out)?;
            let mut x = nn::ops::silu(&x)?.apply(&self.conv_out)?;
            if let Some(q) = &self.quant_conv {
                x = q.forward(&x)?;
            }
            let parts = x.chunk(2, 1)?;
            let logvar = parts[1].clamp(-30f32, 20f32)?;
            means.push(parts[0].clone());
            stds.push((logvar * 0.5)?.exp()?);
        }
        Ok((Tensor::cat(&means, 0)?, Tensor::cat(&stds, 0)?))
    }
}
