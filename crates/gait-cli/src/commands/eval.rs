use std::path::{Path, PathBuf};

use gait_eval::{EvalOptions, Side};
use gait_pipeline::PipelineConfig;

use crate::error::{CliError, one_line};

/// `gait eval`: score predicted keypoints (and the angles from them) against ground truth.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Ground truth: DeepLabCut CSV or a folder of OpenPose per-frame JSON files
    #[arg(long, value_name = "FILE")]
    truth: PathBuf,
    /// Prediction: DeepLabCut CSV (e.g. a run's keypoints.csv) or an OpenPose JSON folder
    #[arg(long, value_name = "FILE")]
    pred: PathBuf,
    /// The leg with the prosthesis; the other one is reported as intact
    #[arg(long, value_name = "SIDE", default_value = "right")]
    prosthetic_side: SideArg,
    /// Folder for metrics.csv, metrics.json and table.md
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Frame rate of the video (for the angles' filters and events)
    #[arg(long, value_name = "N", default_value_t = 30.0)]
    fps: f64,
    /// Method name for the table's column
    #[arg(long, value_name = "NAME", default_value = "prediction")]
    method: String,
    /// Pipeline config whose [postprocess] and [kinematics] tables apply to both files
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum SideArg {
    Left,
    Right,
}

pub fn execute(args: Args, _models_dir: &Path) -> Result<(), CliError> {
    if !(args.fps.is_finite() && args.fps > 0.0) {
        return Err(CliError::new(format!(
            "--fps {} must be a positive frame rate",
            args.fps
        )));
    }
    let config = PipelineConfig::load(args.config.as_deref(), &[])?;
    let read = |p: &Path| {
        gait_eval::read_poses(p, args.fps, None)
            .map_err(|e| CliError::new(format!("{}: {}", p.display(), one_line(&e.to_string()))))
    };
    let (truth, pred) = (read(&args.truth)?, read(&args.pred)?);
    let opts = EvalOptions {
        prosthetic_side: match args.prosthetic_side {
            SideArg::Left => Side::Left,
            SideArg::Right => Side::Right,
        },
        method: args.method,
        ..EvalOptions::default()
    };
    let eval = gait_eval::evaluate(
        &truth,
        &pred,
        &config.postprocess,
        &config.kinematics,
        &opts,
    )
    .map_err(|e| CliError::new(one_line(&e.to_string())))?;
    for w in &eval.warnings {
        eprintln!("warning: {w}");
    }
    let files = gait_eval::write_eval(&[eval], &args.out)
        .map_err(|e| CliError::new(one_line(&e.to_string())))?;
    for f in files {
        eprintln!("{}", f.display());
    }
    Ok(())
}
