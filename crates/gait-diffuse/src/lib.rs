//! Image regenerators implementing [`gait_core::ImageRegenerator`], chosen in
//! the `[regenerator]` table of a pipeline config by `kind`: `passthrough`
//! (the paper's baseline) and `controlnet` (SD 1.5 + canny ControlNet on candle,
//! or on ONNX Runtime from the exports of tools/diffuse/export_onnx.py).
//! The candle UNet and ControlNet are our own ([`unet`]); VAE from candle-transformers.

mod clip_text;
mod config;
mod controlnet;
mod error;
mod guidance;
mod keep_region;
mod leg_mask;
pub mod model_config;
mod models;
mod modes;
mod noise;
pub mod ort_models;
mod passthrough;
mod pipeline;
mod previous;
mod regenerator;
mod savings;
mod schedule;
mod tokenizer;
pub mod unet;
mod vae_decoder;
mod vae_encoder;
mod warp;
pub mod weights;

use std::path::PathBuf;

pub use clip_text::ClipTextModel;
pub use config::{
    ControlnetConfig, Dtype, Init, MAX_CROP_SIDE, PAPER_NEGATIVE_PROMPT, PAPER_PROMPT, Region,
};
pub use controlnet::{ControlNet, ControlResiduals};
pub use error::DiffuseError;
use gait_core::{ImageRegenerator, StageContext, StageError};
pub use guidance::{Cutoffs, StepPlan};
pub use keep_region::{KeepRegion, latent_mask};
pub use leg_mask::{LegMask, LegMaskConfig};
pub use model_config::INPAINT_UNET_CHANNELS;
pub use models::DiffusionModels;
pub use modes::{RegenMode, begin_step};
pub use noise::NoiseRng;
pub use ort_models::{OrtDenoiser, OrtModels};
pub use passthrough::Passthrough;
pub use pipeline::{ControlnetPipeline, DenoiseParams, Generated};
pub use regenerator::{ControlnetRegenerator, canvas_for};
pub use savings::{MAX_CACHE_BRANCH, MAX_MERGE_RATIO, Savings};
pub use schedule::{Scheduler, SchedulerKind};
use serde::{Deserialize, Serialize};
pub use tokenizer::{ClipTokenizer, MAX_LEN};
pub use vae_decoder::VaeDecoder;
pub use vae_encoder::VaeEncoder;

/// The `[regenerator]` table. `kind` picks the regenerator.
// Built once per run from the TOML; boxing the big variant would only add noise at every use.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum RegeneratorConfig {
    /// Original frames go to the pose model unchanged.
    Passthrough,
    /// SD 1.5 + ControlNet redraws each frame from its edge map.
    Controlnet(ControlnetConfig),
    /// An external regenerator loaded from a shared library (see docs/adding-a-stage.md).
    Plugin(gait_plugin::PluginConfig),
    /// A regenerator written in Python (see docs/adding-a-stage.md).
    #[cfg(feature = "python")]
    Python(gait_python::PythonStageConfig),
}

impl RegeneratorConfig {
    pub fn build(&self, ctx: &StageContext) -> Result<Box<dyn ImageRegenerator>, StageError> {
        match self {
            RegeneratorConfig::Passthrough => Ok(Box::new(Passthrough)),
            RegeneratorConfig::Controlnet(c) => Ok(Box::new(ControlnetRegenerator::new(c, ctx)?)),
            RegeneratorConfig::Plugin(p) => Ok(gait_plugin::load_regenerator(p, ctx)?),
            #[cfg(feature = "python")]
            RegeneratorConfig::Python(p) => gait_python::load_regenerator(p, ctx),
        }
    }

    /// True when the regenerator needs an edge map (an `[edge]` kind other than "none").
    pub fn needs_edges(&self) -> bool {
        match self {
            RegeneratorConfig::Passthrough => false,
            RegeneratorConfig::Controlnet(_) => true,
            // The plugin ABI cannot declare it; plugins get edges when [edge] makes them.
            RegeneratorConfig::Plugin(_) => false,
            #[cfg(feature = "python")]
            RegeneratorConfig::Python(_) => false,
        }
    }

    /// True when the regenerator needs the pose of each original frame
    /// (`mode = "inpaint"`): the pipeline then estimates poses on the
    /// original frames first and calls `ImageRegenerator::regenerate_with_poses`.
    pub fn needs_poses(&self) -> bool {
        matches!(self, RegeneratorConfig::Controlnet(c) if c.mode == RegenMode::Inpaint)
    }

    /// The crop around the subject the regenerator redraws, when its region
    /// is the subject (the runner cuts and pastes it).
    pub fn subject_crop(&self) -> Option<gait_core::CropSpec> {
        match self {
            RegeneratorConfig::Controlnet(c) => c.subject_crop(),
            _ => None,
        }
    }

    /// True when each frame starts from the one before (`init = "previous"`).
    pub fn chains_frames(&self) -> bool {
        matches!(self, RegeneratorConfig::Controlnet(c) if c.init == Init::Previous)
    }

    /// True when the regenerator hands frames on unchanged, so the runner need
    /// not cache its output.
    pub fn is_identity(&self) -> bool {
        matches!(self, RegeneratorConfig::Passthrough)
    }

    /// Model files the regenerator reads (checksummed into `run.json`).
    pub fn model_files(&self, ctx: &StageContext) -> Vec<PathBuf> {
        match self {
            RegeneratorConfig::Passthrough => Vec::new(),
            RegeneratorConfig::Controlnet(c) => match c.backend {
                gait_core::Backend::Candle | gait_core::Backend::Auto => weights::required_files(
                    &ctx.model_path(&c.sd_path),
                    &ctx.model_path(&c.controlnet_path),
                ),
                gait_core::Backend::Ort => {
                    let dir = ctx.model_path(&c.onnx_path);
                    let mut files = ort_models::onnx_files(&dir);
                    if c.mode.uses_frame() {
                        files.push(dir.join(ort_models::ONNX_VAE_ENCODER));
                    }
                    files
                }
            },
            RegeneratorConfig::Plugin(p) => vec![p.resolved_path()],
            #[cfg(feature = "python")]
            RegeneratorConfig::Python(p) => p.module_file().into_iter().collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn controlnet_table_defaults_to_the_paper() {
        let c: RegeneratorConfig = toml::from_str("kind = \"controlnet\"").unwrap();
        let RegeneratorConfig::Controlnet(c) = c else {
            panic!("wrong kind")
        };
        assert_eq!(c.prompt, PAPER_PROMPT);
        assert_eq!(c.negative_prompt, PAPER_NEGATIVE_PROMPT);
        assert_eq!(c.resolution, 512);
    }

    #[test]
    fn every_knob_parses_and_unknown_keys_are_named() {
        let c: RegeneratorConfig = toml::from_str(
            "kind = \"controlnet\"\nbackend = \"candle\"\nsteps = 2\nguidance_scale = 5.0\n\
             conditioning_scale = 0.5\nscheduler = \"ddim\"\nseed = 9\nshared_noise = true\n\
             dtype = \"bf16\"\nbatch = 4\nresolution = 256\nprompt = \"a\"\nnegative_prompt = \"b\"\n\
             sd_path = \"x\"\ncontrolnet_path = \"y\"\nonnx_path = \"z\"",
        )
        .unwrap();
        let RegeneratorConfig::Controlnet(c) = c else {
            panic!("wrong kind")
        };
        assert_eq!((c.steps, c.batch, c.seed), (2, 4, 9));
        assert_eq!(c.scheduler, SchedulerKind::Ddim);
        assert_eq!(c.dtype, Dtype::Bf16);
        let err = toml::from_str::<RegeneratorConfig>("kind = \"controlnet\"\nstep = 3")
            .unwrap_err()
            .to_string();
        assert!(err.contains("step") && err.contains("steps"), "{err}");
    }

    #[test]
    fn missing_weights_list_every_file() {
        let dir = std::env::temp_dir().join("gait-diffuse-no-models");
        let ctx = StageContext::new(&dir);
        let cfg: RegeneratorConfig = toml::from_str("kind = \"controlnet\"").unwrap();
        assert_eq!(cfg.model_files(&ctx).len(), 5);
        let Err(err) = cfg.build(&ctx) else {
            panic!("built without weights")
        };
        let msg = err.to_string();
        for f in [
            "unet/diffusion_pytorch_model.safetensors",
            "text_encoder/model.safetensors",
            "sd-controlnet-canny",
        ] {
            assert!(msg.contains(f), "{msg}");
        }
    }
}
