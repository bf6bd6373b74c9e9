use std::path::Path;

use gait_pipeline::{PipelineConfig, RunOptions};

use crate::commands::PipelineArgs;
use crate::error::CliError;

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
        handle: Some(gait_pipeline::RunHandle::default()),
    };
    if let Some(h) = &opts.handle {
        crate::interrupt::install(h);
    }
    let fresh = !opts.out.exists();
    let result = run_and_report(&config, &opts);
    if result.is_err() && fresh && !holds_data(&opts.out) {
        // A folder this run made and left without data only misleads: something ran there.
        let _ = std::fs::remove_dir_all(&opts.out);
    }
    result
}

/// True when `dir` holds a file other than the description a stage cache writes before its
/// first frame (`config.json`): frames in the cache are kept for the rerun.
fn holds_data(dir: &Path) -> bool {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return false;
    };
    entries.flatten().any(|e| {
        if e.file_type().is_ok_and(|t| t.is_dir()) {
            holds_data(&e.path())
        } else {
            e.file_name() != "config.json" || !dir.ancestors().any(|a| a.ends_with("cache"))
        }
    })
}
/// What `gait run` does once the config is resolved: the run, then the report step, with the
/// warnings and the closing line on stderr. `gait batch` runs each row through here.
pub fn run_and_report(config: &PipelineConfig, opts: &RunOptions) -> Result<(), CliError> {
    let (summary, outputs) = gait_pipeline::run_and_write(config, opts)?;
    for w in &summary.manifest.warnings {
        eprintln!("warning: {w}");
    }
    if !config.selection.is_default_flow() {
        eprintln!("{}", summary.manifest.selection.summary());
    }
    for w in &outputs.warnings {
        eprintln!("warning: {w}");
    }
    let report = outputs.report;
    let walked = summary.kinematics.as_ref().map_or(String::new(), |k| {
        let bouts = k.bouts.len();
        let (yes, no) = (&k.cycles_accepted, &k.cycles_rejected);
        if let Some(why) = &summary.manifest.reason {
            // The run completed (exit 0) but has nothing to measure; run.json says "no_result".
            format!("; no result: {why}")
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
