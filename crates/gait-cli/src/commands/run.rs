use std::path::{Path, PathBuf};

use gait_pipeline::{PipelineConfig, RunOptions};

use crate::error::{CliError, one_line};

/// `gait run`: frames -> edges -> regenerated frames -> poses (-> kinematics).
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Pipeline config (TOML), or a previous run's run.json to repeat it [default: configs/default.toml]
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// A video (mp4/avi/mov/webm/mkv), a folder of images, or one image
    #[arg(long, value_name = "PATH")]
    input: PathBuf,
    /// Run folder for keypoints.csv, run.json and the cache
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Override a config value, e.g. --set pose.backend=ort (repeatable)
    #[arg(long = "set", value_name = "TABLE.KEY=VALUE")]
    sets: Vec<String>,
    /// Do not draw a progress bar
    #[arg(long)]
    no_progress: bool,
}

pub fn execute(args: Args, models_dir: &Path) -> Result<(), CliError> {
    let config = PipelineConfig::load(args.config.as_deref(), &args.sets)?;
    let opts = RunOptions {
        input: args.input,
        out: args.out.clone(),
        models_dir: models_dir.to_path_buf(),
        progress: !args.no_progress,
        command: std::env::args().collect(),
    };
    let summary = gait_pipeline::run(&config, &opts)?;
    for w in &summary.manifest.warnings {
        eprintln!("warning: {w}");
    }
    // The report reads what the run wrote, so it shows exactly the files a
    // reader of the run folder gets.
    let side = match config.kinematics.prosthetic_side {
        Some(gait_kin::Side::Left) => gait_eval::Side::Left,
        _ => gait_eval::Side::Right,
    };
    let report = gait_eval::Report::from_run_dir(&args.out, side)
        .and_then(|r| r.write(&args.out))
        .map_err(|e| CliError(format!("writing the report: {}", one_line(&e.to_string()))))?;
    eprintln!(
        "{} frames ({} from cache) -> {}",
        summary.manifest.frames_processed,
        summary.manifest.frames_from_cache,
        report.display()
    );
    Ok(())
}
