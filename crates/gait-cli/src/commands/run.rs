use std::path::Path;

use gait_pipeline::RunOptions;

use crate::commands::PipelineArgs;
use crate::error::{CliError, one_line};

/// `gait run`: frames -> edges -> regenerated frames -> poses -> kinematics,
/// into a run folder (keypoints.csv, angles.csv, ..., report.html, run.json, cache/).
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pipeline: PipelineArgs,
}

pub fn execute(args: Args, models_dir: &Path) -> Result<(), CliError> {
    let p = args.pipeline;
    let config = p.config()?;
    let opts = RunOptions {
        input: p.input,
        out: p.out.clone(),
        models_dir: models_dir.to_path_buf(),
        progress: !p.no_progress,
        command: std::env::args().collect(),
    };
    let summary = gait_pipeline::run(&config, &opts)?;
    for w in &summary.manifest.warnings {
        eprintln!("warning: {w}");
    }
    if !config.selection.is_default_flow() {
        eprintln!("{}", summary.manifest.selection.summary());
    }
    // The report reads what the run wrote, so it shows exactly the files a
    // reader of the run folder gets.
    let side = config.kinematics.prosthetic_side.map(|s| match s {
        gait_kin::Side::Left => gait_eval::Side::Left,
        gait_kin::Side::Right => gait_eval::Side::Right,
    });
    let report = gait_eval::Report::from_run_dir(&p.out, side)
        .and_then(|r| r.write(&p.out))
        .map_err(|e| CliError(format!("writing the report: {}", one_line(&e.to_string()))))?;
    let walked = summary.kinematics.as_ref().map_or(String::new(), |k| {
        let bouts = k.bouts.len();
        let (yes, no) = (&k.cycles_accepted, &k.cycles_rejected);
        if bouts == 0 {
            "; no walking bout found, so no cycles".into()
        } else {
            format!(
                "; {bouts} walking bout(s), cycles accepted left {} right {} (rejected {})",
                yes.left,
                yes.right,
                no.left + no.right
            )
        }
    });
    eprintln!(
        "{} frames ({} from cache){walked} -> {}",
        summary.manifest.frames_processed,
        summary.manifest.frames_from_cache,
        report.display()
    );
    Ok(())
}
