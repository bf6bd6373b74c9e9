//! diffusers' `UNet2DConditionModel` (SD 1.x/2.x layout): `conv_in`, the
//! [`Encoder`] (time embedding, down stages, mid block), up stages fed the
//! skip states in reverse, `conv_norm_out` + SiLU + `conv_out`; with a
//! ControlNet's residuals added to the skip states and the mid block output.

use candle_core::{Result, Tensor};
use candle_nn::VarBuilder;

use super::blocks::UpBlock;
use super::conv::{Conv2d, conv2d};
use super::deep_cache::{CacheBranch, CacheStep};
use super::encoder::{Encoder, common, stages};
use super::norm::{GroupNorm, group_norm};
use super::token_merge::TokenMerge;
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
        self.forward_saving(sample, timestep, context, None, UnetSavings::default())
    }

    /// As [`Self::forward`], with a ControlNet's residuals added.
    pub fn forward_with_residuals(
        &self,
        sample: &Tensor,
        timestep: f64,
        context: &Tensor,
        residuals: &ControlResiduals,
    ) -> Result<Tensor> {
        let none = UnetSavings::default();
        self.forward_saving(sample, timestep, context, Some(residuals), none)
    }

    /// The noise prediction with the ControlNet's residuals (if any) and the
    /// training-free savings of `savings`: DeepCache's full or shallow step,
    /// token merging. On a shallow step the residuals need only the first
    /// [`Self::shallow_states`] entries.
    pub fn forward_saving(
        &self,
        sample: &Tensor,
        timestep: f64,
        ctx: &Tensor,
        res: Option<&ControlResiduals>,
        savings: UnetSavings,
    ) -> Result<Tensor> {
        let UnetSavings { cache, mut merge } = savings;
        if let Some(m) = merge.as_deref_mut() {
            let (_, _, h, w) = sample.dims4()?;
            m.set_size(h, w);
        }
        let temb = self.encoder.time(timestep, sample)?;
        let x = self.conv_in.forward(sample)?;
        let x = match cache {
            Some(c) if c.reuse => self.shallow(x, &temb, ctx, res, c, merge)?,
            c => self.full(x, &temb, ctx, res, c, merge)?,
        };
        let x = self.norm_out.forward(&x, true)?;
        self.conv_out.forward(&x)
    }

    /// Every stage; fills the cache with the feature at the branch's entry
    /// (before the mid residual when the branch enters right after the mid block).
    fn full(
        &self,
        x: Tensor,
        temb: &Tensor,
        ctx: &Tensor,
        res: Option<&ControlResiduals>,
        fill: Option<CacheStep>,
        mut merge: Option<&mut TokenMerge>,
    ) -> Result<Tensor> {
        let (x, skips) = self.encoder.down(x, temb, ctx, merge.as_deref_mut())?;
        let mut x = self.encoder.mid(&x, temb, ctx, merge.as_deref_mut())?;
        let mut record = fill.map(|c| (self.entry(c.branch), c.feature));
        if let Some(((0, 0), slot)) = &mut record {
            **slot = Some(x.clone());
            record = None;
        }
        if let Some(r) = res
            && r.down.len() != skips.len()
        {
            candle_core::bail!(
                "ControlNet gives {} residuals, the UNet has {} skip connections",
                r.down.len(),
                skips.len()
            );
        }
        let skips = with_residuals(skips, res)?;
        if let Some(m) = res.and_then(|r| r.mid.as_ref()) {
            x = (x + m)?;
        }
        self.up(x, skips, (0, 0), record, temb, ctx, merge)
    }

    /// DeepCache's shallow branch: the first skip states, then the up layers
    /// from the branch's entry on the cached feature.
    fn shallow(
        &self,
        x: Tensor,
        temb: &Tensor,
        ctx: &Tensor,
        res: Option<&ControlResiduals>,
        cache: CacheStep,
        mut merge: Option<&mut TokenMerge>,
    ) -> Result<Tensor> {
        let b = x.dim(0)?;
        let skips = self
            .encoder
            .down_shallow(x, temb, ctx, cache.branch, merge.as_deref_mut())?;
        let skips = with_residuals(skips, res)?;
        let Some(feature) = cache.feature.as_ref() else {
            candle_core::bail!("DeepCache: a shallow step before any full step");
        };
        // After the guidance cut-off the loop runs the conditional rows only:
        // they are the last rows of a feature cached under guidance.
        let rows = feature.dim(0)?;
        let mut x = if rows > b {
            feature.narrow(0, rows - b, b)?
        } else {
            feature.clone()
        };
        let entry = self.entry(cache.branch);
        if let (Some(m), (0, 0)) = (res.and_then(|r| r.mid.as_ref()), entry) {
            x = (x + m)?;
        }
        self.up(x, skips, entry, None, temb, ctx, merge)
    }

    /// The up path from layer `from.1` of up stage `from.0` (with the skip
    /// states that path consumes), recording the input of layer `record.0`.
    #[allow(clippy::too_many_arguments)]
    fn up(
        &self,
        mut x: Tensor,
        mut skips: Vec<Tensor>,
        from: (usize, usize),
        mut record: Option<((usize, usize), &mut Option<Tensor>)>,
        temb: &Tensor,
        ctx: &Tensor,
        mut merge: Option<&mut TokenMerge>,
    ) -> Result<Tensor> {
        for (i, block) in self.up.iter().enumerate().skip(from.0) {
            let first = if i == from.0 { from.1 } else { 0 };
            for j in first..block.num_skips() {
                if let Some((at, slot)) = record.as_mut()
                    && *at == (i, j)
                {
                    **slot = Some(x.clone());
                }
                let skip = skips.pop().ok_or_else(|| {
                    candle_core::Error::Msg("up block: skip connections exhausted".into())
                })?;
                x = block.layer(j, &x, &skip, temb, ctx, merge.as_deref_mut())?;
            }
            // Upsample to the size of the skip state the next stage starts with.
            let size = skips
                .last()
                .map(|t| t.dims4())
                .transpose()?
                .map(|(_, _, h, w)| (h, w));
            x = block.upsample(x, size)?;
        }
        Ok(x)
    }

    /// The up layer (stage, layer) where `branch`'s shallow path re-enters:
    /// DeepCache recomputes the up layers numbered up to `branch.layer`
    /// (counted from the stage's last) of the stage mirroring `branch.block`.
    fn entry(&self, branch: CacheBranch) -> (usize, usize) {
        let stage = self.up.len() - 1 - branch.block;
        let layers = self.up[stage].num_skips();
        (stage, layers - 1 - branch.layer.min(layers - 1))
    }

    /// Checks that `branch` names a stage of this UNet.
    pub fn check_branch(&self, branch: CacheBranch) -> Result<()> {
        if branch.block >= self.encoder.num_stages() {
            candle_core::bail!(
                "cache branch {} needs a UNet with at least {} down stages; this one has {}",
                branch.block * 3 + branch.layer,
                branch.block + 1,
                self.encoder.num_stages()
            );
        }
        Ok(())
    }

    /// Residuals a shallow step of `branch` uses (its ControlNet call can stop there).
    pub fn shallow_states(&self, branch: CacheBranch) -> usize {
        self.encoder.shallow_states(branch)
    }

    /// Skip connections a ControlNet must supply residuals for.
    pub fn num_skips(&self) -> usize {
        self.encoder.num_states()
    }
}

/// The training-free savings of one UNet call.
#[derive(Debug, Default)]
pub struct UnetSavings<'a> {
    /// DeepCache: fill the cache (a full step) or run the shallow branch on it.
    pub cache: Option<CacheStep<'a>>,
    /// Token merging in the full-resolution transformer blocks.
    pub merge: Option<&'a mut TokenMerge>,
}

/// `skips` with the ControlNet's residuals added; a shallow step's residuals
/// may be longer than its skip states (a full ControlNet call).
fn with_residuals(skips: Vec<Tensor>, res: Option<&ControlResiduals>) -> Result<Vec<Tensor>> {
    let Some(r) = res else {
        return Ok(skips);
    };
    if r.down.len() < skips.len() {
        candle_core::bail!(
            "ControlNet gives {} residuals, the UNet has {} skip connections",
            r.down.len(),
            skips.len()
        );
    }
    skips.iter().zip(&r.down).map(|(s, d)| s + d).collect()
}
