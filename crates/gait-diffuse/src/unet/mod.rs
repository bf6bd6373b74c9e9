//! Our SD UNet and its building blocks, with diffusers' structure and tensor
//! names so the real checkpoints load unchanged, numerically as diffusers
//! (exact erf GELU in the feed-forward), and with fused CPU kernels for the
//! hot spots (convolutions by Winograd or im2col products, attention without a
//! score tensor, GroupNorm + SiLU in one pass).

mod attention;
mod blocks;
mod conv;
mod cpu;
pub mod deep_cache;
mod embeddings;
pub(crate) mod encoder;
mod feed_forward;
mod im2col;
mod linear;
mod model;
mod norm;
mod resnet;
mod sgemm;
#[cfg(target_arch = "x86_64")]
mod tile_avx2;
#[cfg(target_arch = "aarch64")]
mod tile_neon;
#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
mod tile_quarters;
pub mod token_merge;
mod transformer;
mod winograd;

pub use attention::Attention;
pub use conv::{Conv2d, conv2d};
pub use deep_cache::{CacheBranch, CacheStep, DeepCache};
pub use embeddings::{TimestepEmbedding, Timesteps};
pub use linear::{Linear, linear, linear_no_bias};
pub use model::{UNet2DConditionModel, UnetSavings};
pub use norm::{GroupNorm, group_norm};
pub use resnet::{ResnetBlock2D, ResnetSpec};
pub use token_merge::TokenMerge;
