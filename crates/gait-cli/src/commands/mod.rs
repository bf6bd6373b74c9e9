//! One module per subcommand.

pub mod ablate;
pub mod batch;
pub mod edges;
pub mod eval;
pub mod export;
pub mod kin;
pub mod models;
pub mod review;
pub mod run;

use std::path::PathBuf;

use gait_pipeline::PipelineConfig;

use crate::error::CliError;

/// The models folder: the flag, else `$GAIT_MODELS_DIR`, else the user cache.
pub fn models_dir(flag: Option<PathBuf>) -> PathBuf {
    flag.unwrap_or_else(gait_pipeline::default_models_dir)
}

/// The options every command that runs stages over an input shares.
#[derive(Debug, clap::Args)]
pub struct PipelineArgs {
    /// Pipeline config (TOML), or a previous run's run.json to repeat it [default: configs/default.toml]
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// A video (mp4/avi/mov/webm/mkv), a folder of images, or one image
    #[arg(long, value_name = "PATH")]
    pub input: PathBuf,
    /// Output folder
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Override a config value, e.g. --set pose.backend=ort (repeatable)
    #[arg(long = "set", value_name = "TABLE.KEY=VALUE")]
    pub sets: Vec<String>,
    /// Do not draw a progress bar
    #[arg(long)]
    pub no_progress: bool,
}

impl PipelineArgs {
    /// The resolved configuration: the file (or default) plus the overrides.
    pub fn config(&self) -> Result<PipelineConfig, CliError> {
        Ok(PipelineConfig::load(self.config.as_deref(), &self.sets)?)
    }
}
