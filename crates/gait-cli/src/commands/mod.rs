//! One module per subcommand.

pub mod ablate;
pub mod batch;
pub mod edges;
pub mod eval;
pub mod export;
pub mod kin;
pub mod models;
pub mod progress;
pub mod review;
pub mod run;
pub mod visit;

use std::path::{Path, PathBuf};

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

/// `--fps`, else the frame rate of the run the keypoints came from; a `--fps` that contradicts
/// the run's is taken (the user may know better) with a warning.
pub(crate) fn frame_rate(
    given: Option<f64>,
    beside: Option<&gait_pipeline::RunBeside>,
    keypoints: &Path,
) -> Result<f64, CliError> {
    let run = beside.and_then(|b| b.fps);
    let fps = match (given, run) {
        (Some(f), Some(r)) if (f - r).abs() > 1e-9 => {
            eprintln!("warning: --fps {f} differs from the run's frame rate {r} (run.json)");
            f
        }
        (Some(f), _) | (None, Some(f)) => f,
        (None, None) => {
            return Err(CliError::new(format!(
                "{}: no run.json beside it to read the frame rate from; give --fps N",
                keypoints.display()
            )));
        }
    };
    if !(fps.is_finite() && fps > 0.0) {
        return Err(CliError::new(format!(
            "--fps {fps} must be a positive frame rate"
        )));
    }
    Ok(fps)
}
