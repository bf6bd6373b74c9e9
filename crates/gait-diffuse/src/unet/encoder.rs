//! The half of the UNet that ControlNet copies: timestep embedding, down
//! stages and mid block, built from a [`UnetConfig`].

use candle_core::{Result, Tensor};
use candle_nn::VarBuilder;

use super::blocks::{BlockCommon, DownBlock, MidBlock};
use super::deep_cache::CacheBranch;
use super::embeddings::{TimestepEmbedding, Timesteps};
use super::token_merge::TokenMerge;
use crate::model_config::UnetConfig;

/// One down stage of the config: output channels and, for cross-attention
/// stages, the number of heads.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stage {
    pub channels: usize,
    pub heads: Option<usize>,
}

/// The down stages a config describes (diffusers reads SD 1.x's
/// `attention_head_dim` as the head count when `num_attention_heads` is unset).
pub fn stages(cfg: &UnetConfig) -> Result<Vec<Stage>> {
    if cfg.block_out_channels.len() != cfg.down_block_types.len()
        || cfg.block_out_channels.is_empty()
    {
        candle_core::bail!(
            "UNet config: {} block_out_channels for {} down_block_types",
            cfg.block_out_channels.len(),
            cfg.down_block_types.len()
        );
    }
    let heads = cfg
        .num_attention_heads
        .as_ref()
        .unwrap_or(&cfg.attention_head_dim);
    cfg.block_out_channels
        .iter()
        .zip(&cfg.down_block_types)
        .enumerate()
        .map(|(i, (&channels, kind))| match kind.as_str() {
            "CrossAttnDownBlock2D" => Ok(Stage {
                channels,
                heads: Some(heads.get(i)),
            }),
            "DownBlock2D" => Ok(Stage {
                channels,
                heads: None,
            }),
            other => candle_core::bail!("UNet config: unsupported down block type {other}"),
        })
        .collect()
}

/// What every block of the config shares.
pub fn common(cfg: &UnetConfig) -> Result<BlockCommon> {
    let ch0 = cfg.block_out_channels.first().copied().unwrap_or(320);
    Ok(BlockCommon {
        temb: 4 * ch0,
        groups: cfg.norm_num_groups,
        eps: cfg.norm_eps,
        context_dim: cfg.cross_attention_dim,
        transformer_layers: cfg.transformer_layers_per_block,
        linear_projection: cfg.use_linear_projection,
        downsample_padding: cfg.downsample_padding,
    })
}

/// `time_proj`, `time_embedding`, `down_blocks`, `mid_block`.
#[derive(Debug, Clone)]
pub struct Encoder {
    time_proj: Timesteps,
    time_embedding: TimestepEmbedding,
    pub(crate) down: Vec<DownBlock>,
    mid: MidBlock,
}

impl Encoder {
    pub fn new(vb: VarBuilder, cfg: &UnetConfig) -> Result<Self> {
        let stages = stages(cfg)?;
        let c = common(cfg)?;
        let ch0 = stages[0].channels;
        let mut down = Vec::with_capacity(stages.len());
        for (i, s) in stages.iter().enumerate() {
            let c_in = if i == 0 { ch0 } else { stages[i - 1].channels };
            let last = i + 1 == stages.len();
            down.push(DownBlock::new(
                vb.pp("down_blocks").pp(i),
                &c,
                c_in,
                s.channels,
                cfg.layers_per_block,
                s.heads,
                !last,
            )?);
        }
        let top = stages[stages.len() - 1];
        // SD 1.x's mid block takes the last stage's head count.
        let mid_heads = top
            .heads
            .or(stages.iter().rev().find_map(|s| s.heads))
            .unwrap_or(8);
        Ok(Self {
            time_proj: Timesteps::new(ch0, cfg.flip_sin_to_cos, cfg.freq_shift),
            time_embedding: TimestepEmbedding::new(vb.pp("time_embedding"), ch0, c.temb)?,
            mid: MidBlock::new(
                vb.pp("mid_block"),
                &c,
                top.channels,
                mid_heads,
                cfg.mid_block_scale_factor,
            )?,
            down,
        })
    }

    /// SiLU of the time embedding `(batch, temb)`, as every resnet takes it.
    pub fn time(&self, timestep: f64, like: &Tensor) -> Result<Tensor> {
        let t = self
            .time_proj
            .forward(timestep, like.dim(0)?, like.dtype(), like.device())?;
        candle_nn::ops::silu(&self.time_embedding.forward(&t)?)
    }

    /// Runs the down stages from `x` (after `conv_in`); returns the input to
    /// the mid block and the skip states (`x` first).
    pub fn down(
        &self,
        x: Tensor,
        temb: &Tensor,
        ctx: &Tensor,
        mut merge: Option<&mut TokenMerge>,
    ) -> Result<(Tensor, Vec<Tensor>)> {
        let mut states = vec![x.clone()];
        let mut x = x;
        for block in &self.down {
            let (next, s) = block.forward(&x, temb, ctx, merge.as_deref_mut())?;
            states.extend(s);
            x = next;
        }
        Ok((x, states))
    }

    /// The skip states DeepCache's shallow branch (`branch`) recomputes:
    /// `conv_in`'s, every stage's above `branch.block`, and that stage's
    /// first `branch.layer` resnets; the [`Self::shallow_states`] first
    /// states of [`Self::down`].
    pub fn down_shallow(
        &self,
        x: Tensor,
        temb: &Tensor,
        ctx: &Tensor,
        branch: CacheBranch,
        mut merge: Option<&mut TokenMerge>,
    ) -> Result<Vec<Tensor>> {
        let mut states = vec![x.clone()];
        let mut x = x;
        for block in &self.down[..branch.block] {
            let (next, s) = block.forward(&x, temb, ctx, merge.as_deref_mut())?;
            states.extend(s);
            x = next;
        }
        let stage = &self.down[branch.block];
        let layers = branch.layer.min(stage.num_resnets());
        states.extend(stage.resnet_layers(&x, temb, ctx, layers, merge)?.1);
        Ok(states)
    }

    /// How many skip states [`Self::down_shallow`] gives.
    pub fn shallow_states(&self, branch: CacheBranch) -> usize {
        let above: usize = self.down[..branch.block]
            .iter()
            .map(DownBlock::num_states)
            .sum();
        1 + above + branch.layer.min(self.down[branch.block].num_resnets())
    }

    /// Down stages (DeepCache's branch blocks).
    pub fn num_stages(&self) -> usize {
        self.down.len()
    }

    pub fn mid(
        &self,
        x: &Tensor,
        temb: &Tensor,
        ctx: &Tensor,
        merge: Option<&mut TokenMerge>,
    ) -> Result<Tensor> {
        self.mid.forward(x, temb, ctx, merge)
    }

    /// Skip states the down path hands out (`conv_in`'s output included).
    pub fn num_states(&self) -> usize {
        1 + self.down.iter().map(DownBlock::num_states).sum::<usize>()
    }
}
