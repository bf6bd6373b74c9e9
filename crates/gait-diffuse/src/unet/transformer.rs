//! diffusers' `Transformer2DModel` (`norm`, `proj_in`, `transformer_blocks`,
//! `proj_out`) and its `BasicTransformerBlock`: self-attention,
//! cross-attention on the text context and a GEGLU feed-forward with the
//! exact (erf) GELU, each pre-normed and residual, on the image's pixels as
//! tokens.

use candle_core::{Module, Result, Tensor};
use candle_nn::{LayerNorm, VarBuilder, layer_norm};

use super::attention::Attention;
use super::conv::{Conv2d, conv2d};
use super::feed_forward::FeedForward;
use super::linear::{Linear, linear};
use super::norm::{GroupNorm, group_norm};
use super::token_merge::TokenMerge;

/// One transformer layer (`transformer_blocks.{i}`).
#[derive(Debug, Clone)]
struct BasicTransformerBlock {
    norm1: LayerNorm,
    attn1: Attention,
    norm2: LayerNorm,
    attn2: Attention,
    norm3: LayerNorm,
    ff: FeedForward,
}

impl BasicTransformerBlock {
    fn new(vb: VarBuilder, dim: usize, context_dim: usize, heads: usize) -> Result<Self> {
        let inner = 4 * dim;
        Ok(Self {
            norm1: layer_norm(dim, 1e-5, vb.pp("norm1"))?,
            attn1: Attention::new(vb.pp("attn1"), dim, dim, heads)?,
            norm2: layer_norm(dim, 1e-5, vb.pp("norm2"))?,
            attn2: Attention::new(vb.pp("attn2"), dim, context_dim, heads)?,
            norm3: layer_norm(dim, 1e-5, vb.pp("norm3"))?,
            ff: FeedForward::new(vb.pp("ff"), dim, inner)?,
        })
    }

    /// `merge` (token merging) applies to self-attention only, as tomesd's default.
    fn forward(
        &self,
        x: &Tensor,
        context: &Tensor,
        merge: Option<&mut TokenMerge>,
    ) -> Result<Tensor> {
        let plan = match merge {
            Some(m) => m.plan(x)?,
            None => None,
        };
        let y = self.norm1.forward(x)?;
        let y = match &plan {
            Some(p) => p.unmerge(&self.attn1.forward(&p.merge(&y)?, None)?)?,
            None => self.attn1.forward(&y, None)?,
        };
        let x = (y + x)?;
        let x = (self
            .attn2
            .forward(&self.norm2.forward(&x)?, Some(context))?
            + x)?;
        self.ff.forward(&self.norm3.forward(&x)?, &x)
    }
}

/// `proj_in` / `proj_out`: 1x1 convolutions (SD 1.x) or linear layers
/// (`use_linear_projection`, SD 2.x).
#[derive(Debug, Clone)]
enum Projection {
    Conv(Conv2d),
    Linear(Linear),
}

/// Transformer layers over the pixels of a `(B, C, H, W)` feature map, added
/// back to it.
#[derive(Debug, Clone)]
pub struct Transformer2D {
    norm: GroupNorm,
    proj_in: Projection,
    blocks: Vec<BasicTransformerBlock>,
    proj_out: Projection,
}

/// Shape of one [`Transformer2D`].
#[derive(Debug, Clone, Copy)]
pub struct TransformerSpec {
    pub channels: usize,
    pub heads: usize,
    pub context_dim: usize,
    pub layers: usize,
    pub groups: usize,
    pub linear_projection: bool,
}

impl Transformer2D {
    pub fn new(vb: VarBuilder, s: &TransformerSpec) -> Result<Self> {
        let c = s.channels;
        let proj = |name: &str| -> Result<Projection> {
            Ok(if s.linear_projection {
                Projection::Linear(linear(c, c, vb.pp(name))?)
            } else {
                Projection::Conv(conv2d(c, c, 1, 1, 0, vb.pp(name))?)
            })
        };
        let blocks = (0..s.layers)
            .map(|i| {
                BasicTransformerBlock::new(
                    vb.pp("transformer_blocks").pp(i),
                    c,
                    s.context_dim,
                    s.heads,
                )
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Self {
            norm: group_norm(s.groups, c, 1e-6, vb.pp("norm"))?,
            proj_in: proj("proj_in")?,
            blocks,
            proj_out: proj("proj_out")?,
        })
    }

    /// The transformer layers over `x`'s pixels; `merge` merges tokens at the
    /// full latent resolution.
    pub fn forward(
        &self,
        x: &Tensor,
        context: &Tensor,
        mut merge: Option<&mut TokenMerge>,
    ) -> Result<Tensor> {
        let (b, c, h, w) = x.dims4()?;
        let y = self.norm.forward(x, false)?;
        let to_tokens = |t: Tensor| t.permute((0, 2, 3, 1))?.reshape((b, h * w, c));
        let mut t = match &self.proj_in {
            Projection::Conv(p) => to_tokens(p.forward(&y)?)?,
            Projection::Linear(p) => p.forward(&to_tokens(y)?)?,
        };
        for block in &self.blocks {
            t = block.forward(&t, context, merge.as_deref_mut())?;
        }
        let to_map = |t: Tensor| t.reshape((b, h, w, c))?.permute((0, 3, 1, 2));
        match &self.proj_out {
            Projection::Conv(p) => p.forward_with(&to_map(t)?, None, Some(x)),
            Projection::Linear(p) => to_map(p.forward(&t)?)? + x,
        }
    }
}
