//! The VAE decoder of SD 1.5 (diffusers' `AutoencoderKL.decode`: `post_quant_conv`,
//! then `Decoder`) on the UNet's CPU kernels (Winograd convolutions, fused
//! GroupNorm + SiLU, fused attention). candle-transformers' decoder runs
//! candle's generic convolutions, and at 512x512 one decode cost as much as
//! several UNet steps (BENCHMARKS.md, "Regeneration per frame on the CPU").

use candle_core::{Result, Tensor};
use candle_nn::VarBuilder;

use crate::model_config::VaeConfig;
use crate::unet::{Attention, Conv2d, GroupNorm, ResnetBlock2D, ResnetSpec, conv2d, group_norm};

/// diffusers' VAE blocks use this GroupNorm epsilon throughout.
const EPS: f64 = 1e-6;

/// `post_quant_conv` + `decoder.*` of an `AutoencoderKL`.
#[derive(Debug)]
pub struct VaeDecoder {
    post_quant_conv: Option<Conv2d>,
    conv_in: Conv2d,
    mid: MidBlock,
    /// Per up block: its resnets and its 2x upsampling convolution (none on the last).
    up: Vec<(Vec<ResnetBlock2D>, Option<Conv2d>)>,
    norm_out: GroupNorm,
    conv_out: Conv2d,
}

/// Resnet, one-head attention over the pixels, resnet.
#[derive(Debug)]
struct MidBlock {
    resnets: [ResnetBlock2D; 2],
    norm: GroupNorm,
    attention: Attention,
}

impl VaeDecoder {
    /// Loads from a VarBuilder at the root of the VAE's safetensors.
    pub fn new(vb: VarBuilder, cfg: &VaeConfig) -> Result<Self> {
        let ch: Vec<usize> = cfg.block_out_channels.iter().rev().copied().collect();
        let top = *ch.first().ok_or_else(|| {
            candle_core::Error::Msg("VAE config has no block_out_channels".into())
        })?;
        let g = cfg.norm_num_groups;
        let spec = |c_in, c_out| ResnetSpec {
            c_in,
            c_out,
            temb: None,
            groups: g,
            eps: EPS,
            output_scale: 1.0,
        };
        let dec = vb.pp("decoder");
        let vm = dec.pp("mid_block");
        let mid = MidBlock {
            resnets: [
                ResnetBlock2D::new(vm.pp("resnets.0"), &spec(top, top))?,
                ResnetBlock2D::new(vm.pp("resnets.1"), &spec(top, top))?,
            ],
            norm: group_norm(g, top, EPS, vm.pp("attentions.0.group_norm"))?,
            attention: Attention::vae(vm.pp("attentions.0"), top)?,
        };
        let mut up = Vec::with_capacity(ch.len());
        let mut c_prev = top;
        for (i, &c) in ch.iter().enumerate() {
            let vu = dec.pp("up_blocks").pp(i.to_string());
            let resnets = (0..cfg.layers_per_block + 1)
                .map(|j| {
                    let c_in = if j == 0 { c_prev } else { c };
                    ResnetBlock2D::new(vu.pp("resnets").pp(j.to_string()), &spec(c_in, c))
                })
                .collect::<Result<Vec<_>>>()?;
            let upsample = (i + 1 < ch.len())
                .then(|| conv2d(c, c, 3, 1, 1, vu.pp("upsamplers.0.conv")))
                .transpose()?;
            up.push((resnets, upsample));
            c_prev = c;
        }
        let z = cfg.latent_channels;
        Ok(Self {
            post_quant_conv: cfg
                .use_post_quant_conv
                .then(|| conv2d(z, z, 1, 1, 0, vb.pp("post_quant_conv")))
                .transpose()?,
            conv_in: conv2d(z, top, 3, 1, 1, dec.pp("conv_in"))?,
            mid,
            up,
            norm_out: group_norm(g, c_prev, EPS, dec.pp("conv_norm_out"))?,
            conv_out: conv2d(c_prev, 3, 3, 1, 1, dec.pp("conv_out"))?,
        })
    }

    /// Images `(B, 3, 8h, 8w)` in about [-1, 1] from latents `(B, 4, h, w)`
    /// already divided by the scaling factor.
    pub fn decode(&self, z: &Tensor) -> Result<Tensor> {
        let z = match &self.post_quant_conv {
            Some(c) => c.forward(z)?,
            None => z.clone(),
        };
        let mut x = self.mid.forward(&self.conv_in.forward(&z)?)?;
        for (resnets, upsample) in &self.up {
            for r in resnets {
                x = r.forward(&x, None)?;
            }
            if let Some(conv) = upsample {
                let (_, _, h, w) = x.dims4()?;
                x = conv.forward(&x.upsample_nearest2d(2 * h, 2 * w)?)?;
            }
        }
        self.conv_out.forward(&self.norm_out.forward(&x, true)?)
    }
}

impl MidBlock {
    fn forward(&self, x: &Tensor) -> Result<Tensor> {
        let x = self.resnets[0].forward(x, None)?;
        let (b, c, h, w) = x.dims4()?;
        let tokens = self
            .norm
            .forward(&x, false)?
            .reshape((b, c, h * w))?
            .transpose(1, 2)?
            .contiguous()?;
        let y = self.attention.forward(&tokens, None)?;
        let y = y.transpose(1, 2)?.reshape((b, c, h, w))?;
        self.resnets[1].forward(&(y + x)?, None)
    }
}
