//! The `[regenerator]` table for `kind = "controlnet"`.

use std::path::PathBuf;

use gait_core::Backend;
use serde::{Deserialize, Serialize};

use crate::guidance::Cutoffs;
use crate::leg_mask::LegMaskConfig;
use crate::modes::{RegenMode, begin_step};
use crate::savings::Savings;
use crate::schedule::SchedulerKind;

/// The paper's prompt for regenerating the person with intact limbs.
pub const PAPER_PROMPT: &str =
    "an able-body person walking, intact lower limbs, 2 legs, full-body portrait, realistic";
/// The paper's negative prompt.
pub const PAPER_NEGATIVE_PROMPT: &str = "cyborg, amputee, panfuturism";

/// Floating-point type the models run in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Dtype {
    #[default]
    F32,
    F16,
    Bf16,
}

impl Dtype {
    /// The name used in the TOML.
    pub fn name(self) -> &'static str {
        match self {
            Dtype::F32 => "f32",
            Dtype::F16 => "f16",
            Dtype::Bf16 => "bf16",
        }
    }

    pub fn candle(self) -> candle_core::DType {
        match self {
            Dtype::F32 => candle_core::DType::F32,
            Dtype::F16 => candle_core::DType::F16,
            Dtype::Bf16 => candle_core::DType::BF16,
        }
    }
}

/// SD 1.5 + canny ControlNet regeneration settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ControlnetConfig {
    pub backend: Backend,
    /// SD 1.5 folder in diffusers layout (unet/, vae/, text_encoder/,
    /// tokenizer/), relative to the models folder.
    pub sd_path: PathBuf,
    /// ControlNet folder in diffusers layout, relative to the models folder.
    pub controlnet_path: PathBuf,
    /// `backend = "ort"`: folder of the ONNX exports written by
    /// tools/diffuse/export_onnx.py, relative to the models folder.
    pub onnx_path: PathBuf,
    pub prompt: String,
    pub negative_prompt: String,
    pub steps: usize,
    pub guidance_scale: f64,
    /// Weight of the ControlNet residuals (diffusers' `controlnet_conditioning_scale`).
    pub conditioning_scale: f64,
    /// `ddim`, `unipc` or `dpmpp2m` (DPM-Solver++ 2M).
    pub scheduler: SchedulerKind,
    /// Classifier-free guidance on steps `0..=floor(steps * guidance_end)`,
    /// as diffusers' `SDCFGCutoffCallback`; after it the networks run on one
    /// latent instead of two. 1.0 (default) guides every step.
    pub guidance_end: f64,
    /// The ControlNet runs only on the steps whose fraction of the loop lies
    /// in [control_guidance_start, control_guidance_end] (diffusers' keys);
    /// outside, its call is skipped (diffusers runs it and multiplies by 0).
    pub control_guidance_start: f64,
    pub control_guidance_end: f64,
    /// DeepCache (Ma et al. 2024): the UNet's deep features are computed on
    /// every `cache_interval`-th step and reused between (1: off).
    pub cache_interval: usize,
    /// DeepCache's `cache_branch_id` (0..=11 on SD 1.5): where its shallow
    /// branch leaves the UNet; 0, the shallowest, saves the most.
    pub cache_branch: usize,
    /// Token merging (Bolya & Hoffman 2023): the share of tokens merged
    /// before self-attention at full latent resolution, in [0, 0.9] (0: off).
    pub token_merge_ratio: f64,
    /// Base seed; frame i uses `seed + i` unless `shared_noise` is set.
    pub seed: u64,
    /// Same initial noise for every frame (steadier video).
    pub shared_noise: bool,
    pub dtype: Dtype,
    /// Frames denoised together.
    pub batch: usize,
    /// Short side of the generation canvas (a multiple of 64; long side
    /// follows the frame's aspect, rounded to 64, as ControlNet's annotators do).
    pub resolution: u32,
    /// `text2img` (the paper), `img2img` (from the frame) or `inpaint` (the
    /// leg mask only); the last two need the VAE encoder (on ort:
    /// `vae_encoder/model.onnx` from tools/diffuse/export_onnx.py).
    pub mode: RegenMode,
    /// `img2img` / `inpaint`: noise added to the frame, in (0, 1]; when
    /// unset, diffusers' defaults (0.8 for img2img, 1.0 for inpaint).
    pub strength: Option<f64>,
    /// `inpaint`: how the leg mask is drawn from the original frame's pose.
    pub mask: LegMaskConfig,
    /// `frame` (the whole frame at `resolution`) or `subject`: a crop around
    /// the subject of the subject pass, `crop_size` canvas pixels, pasted back.
    pub region: Region,
    /// `region = "subject"`: the crop's width and height in canvas pixels
    /// (multiples of 64, at most 1024; a walker is about twice as tall as wide).
    pub crop_size: [u32; 2],
    /// `region = "subject"`: extra height around the body box, as a fraction.
    pub crop_margin: f64,
    /// `noise` (every frame from its own noise, or its frame in img2img) or
    /// `previous`: from the previous frame's final latent noised to `strength`
    /// (this project's addition; the first frame of a run and any frame after
    /// a skipped one start as with `noise`).
    pub init: Init,
}

/// What the regenerator redraws (`region = "..."`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Region {
    #[default]
    Frame,
    Subject,
}

/// Where a frame's denoising starts (`init = "..."`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Init {
    #[default]
    Noise,
    Previous,
}

/// Largest crop side, canvas pixels.
pub const MAX_CROP_SIDE: u32 = 1024;
/// The strength of `init = "previous"` when none is set.
pub const PREVIOUS_STRENGTH: f64 = 0.5;

impl Default for ControlnetConfig {
    fn default() -> Self {
        Self {
            backend: Backend::Candle,
            sd_path: "stable-diffusion-v1-5".into(),
            controlnet_path: "sd-controlnet-canny".into(),
            onnx_path: "onnx/sd15-controlnet-canny".into(),
            prompt: PAPER_PROMPT.into(),
            negative_prompt: PAPER_NEGATIVE_PROMPT.into(),
            steps: 20,
            guidance_scale: 7.5,
            conditioning_scale: 1.0,
            scheduler: SchedulerKind::Unipc,
            guidance_end: 1.0,
            control_guidance_start: 0.0,
            control_guidance_end: 1.0,
            cache_interval: 1,
            cache_branch: 0,
            token_merge_ratio: 0.0,
            seed: 0,
            shared_noise: false,
            dtype: Dtype::F32,
            batch: 1,
            resolution: 512,
            mode: RegenMode::Text2img,
            strength: None,
            mask: LegMaskConfig::default(),
            region: Region::Frame,
            crop_size: [256, 512],
            crop_margin: 0.15,
            init: Init::Noise,
        }
    }
}

impl ControlnetConfig {
    /// Checks value ranges that serde cannot.
    pub fn validate(&self) -> Result<(), String> {
        if self.steps == 0 || self.steps > 1000 {
            return Err(format!(
                "regenerator.steps = {} must be in 1..=1000",
                self.steps
            ));
        }
        self.cutoffs().validate()?;
        self.savings(0).validate(self.steps)?;
        if self.backend == Backend::Ort && self.savings(0).any() {
            return Err(format!(
                "regenerator.cache_interval = {} and regenerator.token_merge_ratio = {} need \
                 backend = \"candle\": the ONNX export is one UNet graph, which cannot stop at \
                 DeepCache's branch or merge tokens inside its attention; set them to 1 and 0 for \"ort\"",
                self.cache_interval, self.token_merge_ratio
            ));
        }
        if self.batch == 0 {
            return Err("regenerator.batch must be at least 1".into());
        }
        if self.resolution < 64 || !self.resolution.is_multiple_of(64) {
            return Err(format!(
                "regenerator.resolution = {} must be a positive multiple of 64",
                self.resolution
            ));
        }
        if let Some(s) = self.strength
            && !self.mode.uses_frame()
            && self.init == Init::Noise
        {
            return Err(format!(
                "regenerator.strength = {s} needs mode = \"img2img\" or \"inpaint\", or init = \"previous\" (mode is \"{}\")",
                self.mode.name()
            ));
        }
        self.validate_crop()?;
        self.validate_init()?;
        if self.mode.uses_frame() {
            begin_step(self.steps, self.strength()).map_err(|e| e.to_string())?;
        }
        if self.mode == RegenMode::Inpaint {
            self.mask.validate()?;
        }
        Ok(())
    }

    /// `crop_size` and `crop_margin`, when the region is the subject.
    fn validate_crop(&self) -> Result<(), String> {
        if self.region != Region::Subject {
            return Ok(());
        }
        if self.mode == RegenMode::Inpaint {
            return Err(
                "regenerator.region = \"subject\" cannot be used with mode = \"inpaint\" (the leg \
                 mask is drawn on the whole frame); use region = \"frame\""
                    .into(),
            );
        }
        for side in self.crop_size {
            if side == 0 || !side.is_multiple_of(64) || side > MAX_CROP_SIDE {
                return Err(format!(
                    "regenerator.crop_size = {:?}: each side must be a multiple of 64 from 64 to {MAX_CROP_SIDE}",
                    self.crop_size
                ));
            }
        }
        if !(0.0..=2.0).contains(&self.crop_margin) {
            return Err(format!(
                "regenerator.crop_margin = {} must be in [0, 2]",
                self.crop_margin
            ));
        }
        Ok(())
    }

    /// `init = "previous"`: its strength leaves a step to run, and no inpainting.
    fn validate_init(&self) -> Result<(), String> {
        if self.init != Init::Previous {
            return Ok(());
        }
        if self.mode == RegenMode::Inpaint {
            return Err(
                "regenerator.init = \"previous\" cannot be used with mode = \"inpaint\" \
                 (the leg mask is redrawn from noise); use mode = \"text2img\" or \"img2img\""
                    .into(),
            );
        }
        begin_step(self.steps, self.strength()).map_err(|e| e.to_string())?;
        Ok(())
    }

    /// The subject crop, when the region is the subject.
    pub fn subject_crop(&self) -> Option<gait_core::CropSpec> {
        (self.region == Region::Subject).then_some(gait_core::CropSpec {
            size: self.crop_size,
            margin: self.crop_margin,
        })
    }

    /// The guidance and ControlNet cut-offs.
    pub fn cutoffs(&self) -> Cutoffs {
        Cutoffs {
            guidance_end: self.guidance_end,
            control_start: self.control_guidance_start,
            control_end: self.control_guidance_end,
        }
    }

    /// DeepCache and token merging, token merging's picks seeded by `merge_seed`.
    pub fn savings(&self, merge_seed: u64) -> Savings {
        Savings {
            cache_interval: self.cache_interval,
            cache_branch: self.cache_branch,
            token_merge_ratio: self.token_merge_ratio,
            merge_seed,
        }
    }

    /// The strength in use: the configured one or the mode's default.
    pub fn strength(&self) -> f64 {
        self.strength
            .unwrap_or_else(|| match (self.init, self.mode) {
                (Init::Previous, RegenMode::Text2img) => PREVIOUS_STRENGTH,
                _ => self.mode.default_strength(),
            })
    }
}
