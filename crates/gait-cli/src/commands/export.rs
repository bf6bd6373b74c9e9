use std::path::PathBuf;

use gait_eval::export::{RunFacts, export_run};
use gait_eval::report_config::ExportFormat;

use crate::error::{CliError, one_line};

/// `gait export`: an earlier run's keypoints, angles and events as c3d,
/// OpenSim .trc/.mot or OpenPose JSON, written into its folder.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// A folder written by `gait run` or `gait kin`
    #[arg(value_name = "RUN_DIR")]
    run_dir: PathBuf,
    /// c3d | trc | mot | openpose (repeatable or comma-separated) [default: the run's [export] formats]
    #[arg(long = "format", value_name = "F", value_delimiter = ',')]
    formats: Vec<String>,
    /// Frame rate, for a folder without run.json (`gait kin` output)
    #[arg(long, value_name = "N")]
    fps: Option<f64>,
}

pub fn execute(args: Args) -> Result<(), CliError> {
    if !args.run_dir.is_dir() {
        return Err(CliError::new(format!(
            "{}: not a folder; give the output folder of `gait run` or `gait kin`",
            args.run_dir.display()
        )));
    }
    let formats: Vec<ExportFormat> = if args.formats.is_empty() {
        let run = args.run_dir.join("run.json");
        let config = if run.exists() {
            gait_pipeline::PipelineConfig::load(Some(&run), &[])?
        } else {
            gait_pipeline::PipelineConfig::load(None, &[])?
        };
        config.export.formats
    } else {
        args.formats
            .iter()
            .map(|f| {
                f.trim()
                    .parse()
                    .map_err(|e: String| CliError::new(format!("--format: {e}")))
            })
            .collect::<Result<_, _>>()?
    };
    if let Some(f) = args.fps
        && !(f.is_finite() && f > 0.0)
    {
        return Err(CliError::new(format!(
            "--fps {f} must be a positive frame rate"
        )));
    }
    let facts = RunFacts::of_dir(&args.run_dir, args.fps)
        .map_err(|e| CliError::new(one_line(&e.to_string())))?;
    let written = export_run(&args.run_dir, &formats, &facts)
        .map_err(|e| CliError::new(one_line(&e.to_string())))?;
    for p in written {
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}
