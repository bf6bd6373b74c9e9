//! ControlNet (Zhang et al. 2023) with diffusers' `ControlNetModel` structure
//! and tensor names: a trainable copy of the UNet's encoder, fed the latent
//! plus an embedding of the condition image, whose per-resolution outputs pass
//! through zero-initialised 1x1 convolutions into the UNet's skip connections.

use candle_core::{Module, Result, Tensor};
use candle_nn::{Conv2d, Conv2dConfig, VarBuilder, conv2d};
use candle_transformers::models::stable_diffusion::embeddings::{TimestepEmbedding, Timesteps};
use candle_transformers::models::stable_diffusion::unet_2d_blocks::{
    CrossAttnDownBlock2D, CrossAttnDownBlock2DConfig, DownBlock2D, DownBlock2DConfig,
    UNetMidBlock2DCrossAttn, UNetMidBlock2DCrossAttnConfig,
};

use crate::model_config::UnetConfig;

/// Residuals a ControlNet adds to the UNet: one per skip connection, and one
/// for the mid block.
#[derive(Debug, Clone)]
pub struct ControlResiduals {
    pub down: Vec<Tensor>,
    pub mid: Tensor,
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
        Ok(ControlResiduals {
            down,
            mid: (&self.mid + &other.mid)?,
        })
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
        let pad = Conv2dConfig {
            padding: 1,
            ..Default::default()
        };
        let stride2 = Conv2dConfig {
            padding: 1,
            stride: 2,
            ..Default::default()
        };
        let first = channels.first().copied().unwrap_or(16);
        let conv_in = conv2d(cond_channels, first, 3, pad, vb.pp("conv_in"))?;
        let mut blocks = Vec::new();
        let vbb = vb.pp("blocks");
        for (i, pair) in channels.windows(2).enumerate() {
            blocks.push(conv2d(pair[0], pair[0], 3, pad, vbb.pp(2 * i))?);
            blocks.push(conv2d(pair[0], pair[1], 3, stride2, vbb.pp(2 * i + 1))?);
        }
        let last = channels.last().copied().unwrap_or(first);
        let conv_out = conv2d(last, out, 3, pad, vb.pp("conv_out"))?;
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

#[derive(Debug)]
enum Down {
    Plain(DownBlock2D),
    CrossAttn(CrossAttnDownBlock2D),
}

/// diffusers' `ControlNetModel` (SD 1.x/2.x layout, no class embedding).
#[derive(Debug)]
pub struct ControlNet {
    conv_in: Conv2d,
    time_proj: Timesteps,
    time_embedding: TimestepEmbedding,
    cond_embedding: CondEmbedding,
    down_blocks: Vec<Down>,
    zero_convs: Vec<Conv2d>,
    mid_block: UNetMidBlock2DCrossAttn,
    mid_zero_conv: Conv2d,
}

impl ControlNet {
    /// Builds the model from `vb` (tensor names as in diffusers' safetensors).
    pub fn new(vb: VarBuilder, cfg: &UnetConfig) -> Result<Self> {
        let unet = cfg
            .to_candle()
            .map_err(|e| candle_core::Error::Msg(e.to_string()))?;
        let ch0 = cfg.block_out_channels.first().copied().unwrap_or(320);
        let temb = ch0 * 4;
        let pad = Conv2dConfig {
            padding: 1,
            ..Default::default()
        };
        let conv_in = conv2d(cfg.in_channels, ch0, 3, pad, vb.pp("conv_in"))?;
        let time_proj = Timesteps::new(ch0, cfg.flip_sin_to_cos, cfg.freq_shift);
        let time_embedding = TimestepEmbedding::new(vb.pp("time_embedding"), ch0, temb)?;
        let cond_embedding = CondEmbedding::new(
            vb.pp("controlnet_cond_embedding"),
            cfg.conditioning_channels,
            &cfg.conditioning_embedding_out_channels,
            ch0,
        )?;

        let zc = vb.pp("controlnet_down_blocks");
        let one = Conv2dConfig::default();
        let mut zero_convs = vec![conv2d(ch0, ch0, 1, one, zc.pp(0))?];
        let mut down_blocks = Vec::new();
        let n = unet.blocks.len();
        for (i, block) in unet.blocks.iter().enumerate() {
            let in_ch = if i == 0 {
                ch0
            } else {
                unet.blocks[i - 1].out_channels
            };
            let out = block.out_channels;
            let db = DownBlock2DConfig {
                num_layers: unet.layers_per_block,
                resnet_eps: unet.norm_eps,
                resnet_groups: unet.norm_num_groups,
                add_downsample: i + 1 < n,
                downsample_padding: unet.downsample_padding,
                ..Default::default()
            };
            let vbi = vb.pp("down_blocks").pp(i);
            down_blocks.push(match block.use_cross_attn {
                Some(layers) => Down::CrossAttn(CrossAttnDownBlock2D::new(
                    vbi,
                    in_ch,
                    out,
                    Some(temb),
                    false,
                    CrossAttnDownBlock2DConfig {
                        downblock: db,
                        attn_num_head_channels: block.attention_head_dim,
                        cross_attention_dim: unet.cross_attention_dim,
                        sliced_attention_size: None,
                        use_linear_projection: unet.use_linear_projection,
                        transformer_layers_per_block: layers,
                    },
                )?),
                None => Down::Plain(DownBlock2D::new(vbi, in_ch, out, Some(temb), db)?),
            });
            let convs = unet.layers_per_block + usize::from(i + 1 < n);
            for _ in 0..convs {
                let k = zero_convs.len();
                zero_convs.push(conv2d(out, out, 1, one, zc.pp(k))?);
            }
        }
        let last = unet.blocks.last().map_or(ch0, |b| b.out_channels);
        let mid_block = UNetMidBlock2DCrossAttn::new(
            vb.pp("mid_block"),
            last,
            Some(temb),
            false,
            UNetMidBlock2DCrossAttnConfig {
                resnet_eps: unet.norm_eps,
                output_scale_factor: unet.mid_block_scale_factor,
                cross_attn_dim: unet.cross_attention_dim,
                attn_num_head_channels: unet.blocks.last().map_or(8, |b| b.attention_head_dim),
                resnet_groups: Some(unet.norm_num_groups),
                use_linear_projection: unet.use_linear_projection,
                transformer_layers_per_block: unet
                    .blocks
                    .last()
                    .and_then(|b| b.use_cross_attn)
                    .unwrap_or(1),
                ..Default::default()
            },
        )?;
        let mid_zero_conv = conv2d(last, last, 1, one, vb.pp("controlnet_mid_block"))?;
        Ok(Self {
            conv_in,
            time_proj,
            time_embedding,
            cond_embedding,
            down_blocks,
            zero_convs,
            mid_block,
            mid_zero_conv,
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
        let b = sample.dim(0)?;
        let t = (Tensor::ones(b, sample.dtype(), sample.device())? * timestep)?;
        let emb = self.time_embedding.forward(&self.time_proj.forward(&t)?)?;
        let x = (self.conv_in.forward(sample)? + self.cond_embedding.forward(cond)?)?;
        let mut res = vec![x.clone()];
        let mut x = x;
        for block in &self.down_blocks {
            let (next, r) = match block {
                Down::Plain(d) => d.forward(&x, Some(&emb))?,
                Down::CrossAttn(d) => d.forward(&x, Some(&emb), Some(context))?,
            };
            res.extend(r);
            x = next;
        }
        let mid = self.mid_block.forward(&x, Some(&emb), Some(context))?;
        let down = res
            .iter()
            .zip(&self.zero_convs)
            .map(|(r, c)| c.forward(r)? * scale)
            .collect::<Result<Vec<_>>>()?;
        let mid = (self.mid_zero_conv.forward(&mid)? * scale)?;
        Ok(ControlResiduals { down, mid })
    }

    /// Number of skip-connection residuals (12 for SD 1.5).
    pub fn num_residuals(&self) -> usize {
        self.zero_convs.len()
    }
}
