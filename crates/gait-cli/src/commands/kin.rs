use std::path::{Path, PathBuf};

use gait_pipeline::PipelineConfig;

use crate::error::{CliError, one_line};

/// `gait kin`: keypoints CSV -> filtered keypoints, angles, events, cycles,
/// exports and report.html.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Keypoints in DeepLabCut's CSV layout (e.g. a run's keypoints.csv: its run.json beside
    /// it gives the frame rate, the frame size and the run's settings)
    #[arg(long, value_name = "FILE")]
    keypoints: PathBuf,
    /// Frame rate of the video the keypoints come from [default: the run.json beside the keypoints]
    #[arg(long, value_name = "N")]
    fps: Option<f64>,
    /// Folder for angles.csv, events.csv, cycles.csv, spatiotemporal.csv
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Pipeline config whose [postprocess] and [kinematics] tables apply [default: the run.json
    /// beside the keypoints, else configs/default.toml]
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Override a config value, e.g. --set kinematics.prosthetic_side=\"right\" (repeatable)
    #[arg(long = "set", value_name = "TABLE.KEY=VALUE")]
    sets: Vec<String>,
    /// For multi-animal DeepLabCut files: the individual to analyse [default: the first]
    #[arg(long, value_name = "NAME")]
    individual: Option<String>,
    /// Apply a corrections.toml (swaps, events, excluded frames, keypoints; README, Corrections)
    #[arg(long, value_name = "FILE")]
    corrections: Option<PathBuf>,
}

pub fn execute(args: Args, _models_dir: &Path) -> Result<(), CliError> {
    let beside = gait_pipeline::RunBeside::find(&args.keypoints)?;
    let fps = super::frame_rate(args.fps, beside.as_ref(), &args.keypoints)?;
    let config_path = args
        .config
        .clone()
        .or_else(|| beside.as_ref().map(|b| b.manifest.clone()));
    let mut config = PipelineConfig::load(config_path.as_deref(), &args.sets)?;
    if config.kinematics.frame_size.is_none() {
        config.kinematics.frame_size = beside.as_ref().and_then(|b| b.frame_size);
    }
    config.kinematics.image_blur_px = beside.as_ref().and_then(|b| b.blur_px.clone());
    config.kinematics.image_feet_contrast = beside.as_ref().and_then(|b| b.feet_contrast.clone());
    if let Some(c) = &args.corrections {
        config.kinematics.corrections = Some(c.clone());
    }
    let file = std::fs::File::open(&args.keypoints).map_err(|e| {
        CliError::new(format!(
            "{}: cannot open ({e}); check the --keypoints path",
            args.keypoints.display()
        ))
    })?;
    let seq = gait_core::dlc::read(
        std::io::BufReader::new(file),
        args.individual.as_deref(),
        fps,
    )
    .map_err(|e| {
        CliError::new(format!(
            "{}: {}",
            args.keypoints.display(),
            one_line(&e.to_string())
        ))
    })?;
    let tool = format!("gait kin {}", env!("CARGO_PKG_VERSION"));
    let source = gait_pipeline::KinSource {
        keypoints: &args.keypoints,
        fps,
        individual: args.individual.as_deref(),
        tool: &tool,
    };
    let (result, outputs) = gait_pipeline::kin_and_write(&seq, &config, &args.out, &source)?;
    for w in &result.warnings {
        eprintln!("warning: {w}");
    }
    for w in &outputs.warnings {
        eprintln!("warning: {w}");
    }
    eprintln!(
        "{} frames, {} events, {} strides -> {}",
        result.n_frames,
        result.events.len(),
        result.strides.len(),
        args.out.display()
    );
    Ok(())
}
