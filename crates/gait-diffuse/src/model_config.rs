//! The subset of diffusers' / transformers' `config.json` files our models read.
//! Defaults are Stable Diffusion 1.5's values (runwayml/stable-diffusion-v1-5
//! `unet/config.json`, `vae/config.json`, `text_encoder/config.json`, and
//! lllyasviel/sd-controlnet-canny `config.json`), used when a folder has no config.

use std::path::Path;

use candle_transformers::models::stable_diffusion::vae;
use serde::Deserialize;

use crate::DiffuseError;

/// Input channels of an inpainting UNet: latents (4), mask (1), masked-image latents (4).
pub const INPAINT_UNET_CHANNELS: usize = 9;

/// `attention_head_dim` is a number (SD 1.5) or one per block (SD 2.x).
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum PerBlock {
    One(usize),
    Each(Vec<usize>),
}

impl PerBlock {
    /// The value for down stage `i`.
    pub fn get(&self, i: usize) -> usize {
        match self {
            PerBlock::One(v) => *v,
            PerBlock::Each(v) => v.get(i).or(v.last()).copied().unwrap_or(8),
        }
    }
}

/// UNet2DConditionModel / ControlNetModel configuration (shared keys).
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(default)]
pub struct UnetConfig {
    pub in_channels: usize,
    pub out_channels: usize,
    pub block_out_channels: Vec<usize>,
    pub down_block_types: Vec<String>,
    pub layers_per_block: usize,
    pub cross_attention_dim: usize,
    pub attention_head_dim: PerBlock,
    /// Heads per stage; when unset diffusers takes `attention_head_dim` (SD 1.x's naming).
    pub num_attention_heads: Option<PerBlock>,
    pub norm_num_groups: usize,
    pub norm_eps: f64,
    pub flip_sin_to_cos: bool,
    pub freq_shift: f64,
    pub use_linear_projection: bool,
    pub downsample_padding: usize,
    pub mid_block_scale_factor: f64,
    pub transformer_layers_per_block: usize,
    /// ControlNet only: channels of the condition embedding's convolutions.
    pub conditioning_embedding_out_channels: Vec<usize>,
    /// ControlNet only: channels of the condition image.
    pub conditioning_channels: usize,
}

impl Default for UnetConfig {
    fn default() -> Self {
        Self {
            in_channels: 4,
            out_channels: 4,
            block_out_channels: vec![320, 640, 1280, 1280],
            down_block_types: vec![
                "CrossAttnDownBlock2D".into(),
                "CrossAttnDownBlock2D".into(),
                "CrossAttnDownBlock2D".into(),
                "DownBlock2D".into(),
            ],
            layers_per_block: 2,
            cross_attention_dim: 768,
            attention_head_dim: PerBlock::One(8),
            num_attention_heads: None,
            norm_num_groups: 32,
            norm_eps: 1e-5,
            flip_sin_to_cos: true,
            freq_shift: 0.0,
            use_linear_projection: false,
            downsample_padding: 1,
            mid_block_scale_factor: 1.0,
            transformer_layers_per_block: 1,
            conditioning_embedding_out_channels: vec![16, 32, 96, 256],
            conditioning_channels: 3,
        }
    }
}

/// AutoencoderKL configuration.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(default)]
pub struct VaeConfig {
    pub block_out_channels: Vec<usize>,
    pub layers_per_block: usize,
    pub latent_channels: usize,
    pub norm_num_groups: usize,
    pub scaling_factor: f64,
    pub use_quant_conv: bool,
    pub use_post_quant_conv: bool,
}

impl Default for VaeConfig {
    fn default() -> Self {
        Self {
            block_out_channels: vec![128, 256, 512, 512],
            layers_per_block: 2,
            latent_channels: 4,
            norm_num_groups: 32,
            scaling_factor: 0.18215,
            use_quant_conv: true,
            use_post_quant_conv: true,
        }
    }
}

impl VaeConfig {
    pub fn to_candle(&self) -> vae::AutoEncoderKLConfig {
        vae::AutoEncoderKLConfig {
            block_out_channels: self.block_out_channels.clone(),
            layers_per_block: self.layers_per_block,
            latent_channels: self.latent_channels,
            norm_num_groups: self.norm_num_groups,
            use_quant_conv: self.use_quant_conv,
            use_post_quant_conv: self.use_post_quant_conv,
        }
    }

    /// Pixels per latent cell along each axis.
    pub fn scale_factor(&self) -> usize {
        // Configs from files are checked; a hand-built one must not shift past the word.
        1 << self
            .block_out_channels
            .len()
            .saturating_sub(1)
            .min(MAX_BLOCKS)
    }
}

/// CLIPTextModel configuration (transformers' `CLIPTextConfig`).
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(default)]
pub struct TextConfig {
    pub vocab_size: usize,
    pub hidden_size: usize,
    pub intermediate_size: usize,
    pub num_hidden_layers: usize,
    pub num_attention_heads: usize,
    pub max_position_embeddings: usize,
    pub hidden_act: String,
    pub layer_norm_eps: f64,
}

impl Default for TextConfig {
    fn default() -> Self {
        Self {
            vocab_size: 49408,
            hidden_size: 768,
            intermediate_size: 3072,
            num_hidden_layers: 12,
            num_attention_heads: 12,
            max_position_embeddings: 77,
            hidden_act: "quick_gelu".into(),
            layer_norm_eps: 1e-5,
        }
    }
}

/// The most layers per block (or encoder layers) a config may declare; SD 1.5 has 2 per
/// block and 12 text-encoder layers. Buffers and loops are sized from these before any weight
/// is read, so a hostile file must not name 10^12 of them.
pub const MAX_LAYERS: usize = 64;
/// The most resolution blocks a config may declare (SD 1.5: 4).
pub const MAX_BLOCKS: usize = 16;

/// The sizes a config must keep to before a model is built from it.
pub trait Check {
    fn check(&self) -> Result<(), String>;
}

fn within(what: &str, n: usize, max: usize) -> Result<(), String> {
    match n <= max {
        true => Ok(()),
        false => Err(format!("{what} is {n}, over the limit of {max}")),
    }
}

fn groups(n: usize) -> Result<(), String> {
    match n {
        0 => Err("norm_num_groups is 0".into()),
        _ => Ok(()),
    }
}

impl Check for UnetConfig {
    fn check(&self) -> Result<(), String> {
        within("layers_per_block", self.layers_per_block, MAX_LAYERS)?;
        within(
            "transformer_layers_per_block",
            self.transformer_layers_per_block,
            MAX_LAYERS,
        )?;
        within(
            "block_out_channels' length",
            self.block_out_channels.len(),
            MAX_BLOCKS,
        )?;
        within(
            "conditioning_embedding_out_channels' length",
            self.conditioning_embedding_out_channels.len(),
            MAX_BLOCKS,
        )?;
        // Padding of a 3x3 convolution: more than the kernel overflows candle's size arithmetic.
        within("downsample_padding", self.downsample_padding, 3)?;
        groups(self.norm_num_groups)
    }
}

impl Check for VaeConfig {
    fn check(&self) -> Result<(), String> {
        within("layers_per_block", self.layers_per_block, MAX_LAYERS)?;
        within(
            "block_out_channels' length",
            self.block_out_channels.len(),
            MAX_BLOCKS,
        )?;
        groups(self.norm_num_groups)
    }
}

impl Check for TextConfig {
    fn check(&self) -> Result<(), String> {
        within("num_hidden_layers", self.num_hidden_layers, MAX_LAYERS)
    }
}

/// Reads `config.json` in `dir`, or the SD 1.5 defaults when there is none.
pub fn read_config<T: for<'de> Deserialize<'de> + Default + Check>(
    dir: &Path,
) -> Result<T, DiffuseError> {
    let path = dir.join("config.json");
    if !path.exists() {
        return Ok(T::default());
    }
    let text = std::fs::read_to_string(&path).map_err(|e| DiffuseError::bad_model(&path, e))?;
    let config: T = serde_json::from_str(&text).map_err(|e| DiffuseError::bad_model(&path, e))?;
    config
        .check()
        .map_err(|e| DiffuseError::bad_model(&path, e))?;
    Ok(config)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hostile_sizes_are_refused_when_read() {
        let dir = tempfile::tempdir().unwrap();
        let write = |json: &str| std::fs::write(dir.path().join("config.json"), json).unwrap();
        write(r#"{"layers_per_block": 1000000000000}"#);
        let e = read_config::<UnetConfig>(dir.path())
            .unwrap_err()
            .to_string();
        assert!(e.contains("layers_per_block is 1000000000000"), "{e}");
        write(r#"{"norm_num_groups": 0}"#);
        assert!(read_config::<VaeConfig>(dir.path()).is_err());
        write(r#"{"num_hidden_layers": 12}"#);
        assert!(read_config::<TextConfig>(dir.path()).is_ok());
    }

    #[test]
    fn sd15_defaults_give_the_v1_5_layout() {
        let s = crate::unet::encoder::stages(&UnetConfig::default()).unwrap();
        assert_eq!(s.len(), 4);
        assert_eq!(s[0].heads, Some(8));
        assert_eq!(s[3].heads, None);
        assert_eq!(UnetConfig::default().cross_attention_dim, 768);
        assert_eq!(VaeConfig::default().scale_factor(), 8);
    }

    #[test]
    fn per_block_head_counts_parse() {
        let c: UnetConfig = serde_json::from_str(r#"{"attention_head_dim":[5,10,20,20]}"#).unwrap();
        assert_eq!(crate::unet::encoder::stages(&c).unwrap()[2].heads, Some(20));
        let c: UnetConfig =
            serde_json::from_str(r#"{"attention_head_dim":8,"num_attention_heads":[1,2,3,4]}"#)
                .unwrap();
        assert_eq!(crate::unet::encoder::stages(&c).unwrap()[1].heads, Some(2));
        let c: UnetConfig = serde_json::from_str(r#"{"in_channels":9}"#).unwrap();
        assert_eq!(c.in_channels, 9);
    }
}
