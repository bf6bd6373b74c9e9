//! The UNet's stages with diffusers' names: `CrossAttnDownBlock2D` /
//! `DownBlock2D` (`resnets`, `attentions`, `downsamplers.0.conv`),
//! `UNetMidBlock2DCrossAttn`, and `CrossAttnUpBlock2D` / `UpBlock2D`
//! (`upsamplers.0.conv`), which take the skip connections back in.

use candle_core::{Result, Tensor};
use candle_nn::VarBuilder;

use super::conv::{Conv2d, conv2d};
use super::resnet::{ResnetBlock2D, ResnetSpec};
use super::token_merge::TokenMerge;
use super::transformer::{Transformer2D, TransformerSpec};

/// What the blocks of one UNet (or ControlNet) share.
#[derive(Debug, Clone, Copy)]
pub struct BlockCommon {
    pub temb: usize,
    pub groups: usize,
    pub eps: f64,
    pub context_dim: usize,
    pub transformer_layers: usize,
    pub linear_projection: bool,
    pub downsample_padding: usize,
}

impl BlockCommon {
    fn resnet(&self, c_in: usize, c_out: usize, output_scale: f64) -> ResnetSpec {
        ResnetSpec {
            c_in,
            c_out,
            temb: Some(self.temb),
            groups: self.groups,
            eps: self.eps,
            output_scale,
        }
    }

    fn transformer(&self, channels: usize, heads: usize) -> TransformerSpec {
        TransformerSpec {
            channels,
            heads,
            context_dim: self.context_dim,
            layers: self.transformer_layers,
            groups: self.groups,
            linear_projection: self.linear_projection,
        }
    }
}

/// A down stage: `layers` resnets (each followed by a transformer when
/// `heads` is set), then a stride-2 convolution unless it is the last.
#[derive(Debug, Clone)]
pub struct DownBlock {
    resnets: Vec<ResnetBlock2D>,
    attentions: Vec<Transformer2D>,
    downsample: Option<Conv2d>,
    /// diffusers pads (0, 1, 0, 1) itself when `downsample_padding` is 0.
    pad_right: bool,
}

impl DownBlock {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        vb: VarBuilder,
        c: &BlockCommon,
        c_in: usize,
        c_out: usize,
        layers: usize,
        heads: Option<usize>,
        downsample: bool,
    ) -> Result<Self> {
        let mut resnets = Vec::with_capacity(layers);
        let mut attentions = Vec::new();
        for i in 0..layers {
            let input = if i == 0 { c_in } else { c_out };
            resnets.push(ResnetBlock2D::new(
                vb.pp("resnets").pp(i),
                &c.resnet(input, c_out, 1.0),
            )?);
            if let Some(h) = heads {
                attentions.push(Transformer2D::new(
                    vb.pp("attentions").pp(i),
                    &c.transformer(c_out, h),
                )?);
            }
        }
        let downsample = if downsample {
            let pad = c.downsample_padding;
            Some(conv2d(
                c_out,
                c_out,
                3,
                2,
                pad,
                vb.pp("downsamplers.0.conv"),
            )?)
        } else {
            None
        };
        Ok(Self {
            resnets,
            attentions,
            downsample,
            pad_right: c.downsample_padding == 0,
        })
    }

    /// The stage's output and the states it hands to the up path (one per
    /// resnet, plus the downsampled one).
    pub fn forward(
        &self,
        x: &Tensor,
        temb: &Tensor,
        ctx: &Tensor,
        merge: Option<&mut TokenMerge>,
    ) -> Result<(Tensor, Vec<Tensor>)> {
        let (x, mut states) = self.resnet_layers(x, temb, ctx, self.resnets.len(), merge)?;
        let Some(d) = &self.downsample else {
            return Ok((x, states));
        };
        let input = if self.pad_right {
            x.pad_with_zeros(2, 0, 1)?.pad_with_zeros(3, 0, 1)?
        } else {
            x
        };
        let x = d.forward(&input)?;
        states.push(x.clone());
        Ok((x, states))
    }

    /// The first `layers` resnets (each with its transformer) and their
    /// states: DeepCache's shallow branch stops inside a stage.
    pub fn resnet_layers(
        &self,
        x: &Tensor,
        temb: &Tensor,
        ctx: &Tensor,
        layers: usize,
        mut merge: Option<&mut TokenMerge>,
    ) -> Result<(Tensor, Vec<Tensor>)> {
        let mut x = x.clone();
        let mut states = Vec::with_capacity(self.resnets.len() + 1);
        for (i, r) in self.resnets.iter().take(layers).enumerate() {
            x = r.forward(&x, Some(temb))?;
            if let Some(a) = self.attentions.get(i) {
                x = a.forward(&x, ctx, merge.as_deref_mut())?;
            }
            states.push(x.clone());
        }
        Ok((x, states))
    }

    /// Resnets in the stage (DeepCache numbers its layers by them).
    pub fn num_resnets(&self) -> usize {
        self.resnets.len()
    }

    pub fn num_states(&self) -> usize {
        self.resnets.len() + usize::from(self.downsample.is_some())
    }
}

/// `UNetMidBlock2DCrossAttn`: resnet, (transformer, resnet) per layer.
#[derive(Debug, Clone)]
pub struct MidBlock {
    first: ResnetBlock2D,
    rest: Vec<(Transformer2D, ResnetBlock2D)>,
}

impl MidBlock {
    pub fn new(
        vb: VarBuilder,
        c: &BlockCommon,
        channels: usize,
        heads: usize,
        output_scale: f64,
    ) -> Result<Self> {
        let spec = c.resnet(channels, channels, output_scale);
        Ok(Self {
            first: ResnetBlock2D::new(vb.pp("resnets.0"), &spec)?,
            rest: vec![(
                Transformer2D::new(vb.pp("attentions.0"), &c.transformer(channels, heads))?,
                ResnetBlock2D::new(vb.pp("resnets.1"), &spec)?,
            )],
        })
    }

    pub fn forward(
        &self,
        x: &Tensor,
        temb: &Tensor,
        ctx: &Tensor,
        mut merge: Option<&mut TokenMerge>,
    ) -> Result<Tensor> {
        let mut x = self.first.forward(x, Some(temb))?;
        for (a, r) in &self.rest {
            x = r.forward(&a.forward(&x, ctx, merge.as_deref_mut())?, Some(temb))?;
        }
        Ok(x)
    }
}

/// An up stage: resnets over (input ++ skip state), each optionally
/// followed by a transformer, then 2x nearest upsampling + 3x3 convolution
/// unless it is the last.
#[derive(Debug, Clone)]
pub struct UpBlock {
    resnets: Vec<ResnetBlock2D>,
    attentions: Vec<Transformer2D>,
    upsample: Option<Conv2d>,
}

impl UpBlock {
    /// `prev` channels come in from below, `skips[i]` join resnet i.
    pub fn new(
        vb: VarBuilder,
        c: &BlockCommon,
        prev: usize,
        c_out: usize,
        skips: &[usize],
        heads: Option<usize>,
        upsample: bool,
    ) -> Result<Self> {
        let mut resnets = Vec::with_capacity(skips.len());
        let mut attentions = Vec::new();
        for (i, &skip) in skips.iter().enumerate() {
            let input = if i == 0 { prev } else { c_out };
            resnets.push(ResnetBlock2D::new(
                vb.pp("resnets").pp(i),
                &c.resnet(input + skip, c_out, 1.0),
            )?);
            if let Some(h) = heads {
                attentions.push(Transformer2D::new(
                    vb.pp("attentions").pp(i),
                    &c.transformer(c_out, h),
                )?);
            }
        }
        let upsample = if upsample {
            Some(conv2d(c_out, c_out, 3, 1, 1, vb.pp("upsamplers.0.conv"))?)
        } else {
            None
        };
        Ok(Self {
            resnets,
            attentions,
            upsample,
        })
    }

    pub fn num_skips(&self) -> usize {
        self.resnets.len()
    }

    /// Layer `i`: the resnet over (`x` ++ `skip`), then its transformer.
    pub fn layer(
        &self,
        i: usize,
        x: &Tensor,
        skip: &Tensor,
        temb: &Tensor,
        ctx: &Tensor,
        merge: Option<&mut TokenMerge>,
    ) -> Result<Tensor> {
        let x = self.resnets[i].forward(&Tensor::cat(&[x, skip], 1)?, Some(temb))?;
        match self.attentions.get(i) {
            Some(a) => a.forward(&x, ctx, merge),
            None => Ok(x),
        }
    }

    /// Upsamples to `size` (the next stage's skip size) when given, else by
    /// 2; the last stage has no upsampler and hands `x` on.
    pub fn upsample(&self, x: Tensor, size: Option<(usize, usize)>) -> Result<Tensor> {
        let Some(u) = &self.upsample else {
            return Ok(x);
        };
        let (_, _, h, w) = x.dims4()?;
        let (th, tw) = size.unwrap_or((2 * h, 2 * w));
        u.forward(&x.upsample_nearest2d(th, tw)?)
    }
}
