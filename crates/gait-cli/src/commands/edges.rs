use std::path::{Path, PathBuf};

use gait_pipeline::PipelineConfig;

use crate::error::CliError;

/// `gait edges`: write the edge map of every frame as a PNG.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Pipeline config; its [edge] and [input] tables apply [default: configs/default.toml]
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// A video, a folder of images, or one image
    #[arg(long, value_name = "PATH")]
    input: PathBuf,
    /// Folder for the PNGs (named by frame index)
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Override a config value, e.g. --set edge.kind=canny (repeatable)
    #[arg(long = "set", value_name = "TABLE.KEY=VALUE")]
    sets: Vec<String>,
    /// Do not draw a progress bar
    #[arg(long)]
    no_progress: bool,
}

pub fn execute(args: Args, models_dir: &Path) -> Result<(), CliError> {
    let config = PipelineConfig::load(args.config.as_deref(), &args.sets)?;
    let n = gait_pipeline::edges::export_edges(
        &config,
        &args.input,
        &args.out,
        models_dir,
        !args.no_progress,
    )?;
    eprintln!("{n} edge maps -> {}", args.out.display());
    Ok(())
}
