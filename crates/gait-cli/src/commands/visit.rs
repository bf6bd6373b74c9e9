//! `gait visit`: the passes of one session (side, front and back views), each run as `gait run`
//! runs a video, then combined into one visit report (gait-visit).

use std::path::{Path, PathBuf};

use gait_pipeline::{PipelineConfig, RunOptions};
use gait_visit::{Pass, VisitOptions};

use crate::error::CliError;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Output folder: the visit report, and each pass's run under passes/
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// A pass filmed from the subject's left side (repeatable: the passes of a view are pooled)
    #[arg(long, value_name = "VIDEO")]
    left: Vec<PathBuf>,
    /// A pass filmed from the subject's right side (repeatable)
    #[arg(long, value_name = "VIDEO")]
    right: Vec<PathBuf>,
    /// A pass walking toward the camera (repeatable)
    #[arg(long, value_name = "VIDEO")]
    anterior: Vec<PathBuf>,
    /// A pass walking away from the camera (repeatable)
    #[arg(long, value_name = "VIDEO")]
    posterior: Vec<PathBuf>,
    /// Pipeline config (TOML) every pass runs with [default: configs/default.toml]
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Override a config value for every pass (repeatable)
    #[arg(long = "set", value_name = "TABLE.KEY=VALUE")]
    sets: Vec<String>,
    /// Who the visit is (visit.json, for `gait progress`)
    #[arg(long, default_value = "")]
    subject: String,
    /// Which session
    #[arg(long, default_value = "")]
    session: String,
    /// The visit's date, ISO 8601 (YYYY-MM-DD)
    #[arg(long, default_value = "")]
    date: String,
    /// Do not draw progress bars
    #[arg(long)]
    no_progress: bool,
}

impl Args {
    /// (view, video) of every pass, in the order left, right, anterior, posterior.
    fn passes(&self) -> Vec<(&'static str, &Path)> {
        [
            ("left", &self.left),
            ("right", &self.right),
            ("anterior", &self.anterior),
            ("posterior", &self.posterior),
        ]
        .iter()
        .flat_map(|(view, videos)| videos.iter().map(move |v| (*view, v.as_path())))
        .collect()
    }
}

pub fn execute(args: Args, models_dir: &Path) -> Result<(), CliError> {
    if !args.date.is_empty() && !gait_batch::study::is_iso_date(&args.date) {
        return Err(CliError::new(format!(
            "--date {}: not ISO 8601; write it as YYYY-MM-DD (e.g. 2026-12-04)",
            args.date
        )));
    }
    let passes = args.passes();
    if passes.is_empty() {
        return Err(CliError::new(
            "a visit needs at least one pass: --left, --right, --anterior or --posterior VIDEO",
        ));
    }
    let base = PipelineConfig::load(args.config.as_deref(), &args.sets)?;
    let (mut done, mut notes) = (Vec::new(), Vec::new());
    for (k, (view, video)) in passes.iter().enumerate() {
        let dir = args.out.join("passes").join(format!("{}-{view}", k + 1));
        match run_pass(&args, view, video, &dir, models_dir) {
            Ok(()) => {
                done.push(Pass::read(view, video, &dir).map_err(|e| CliError::new(e.to_string()))?)
            }
            // The visit goes on with the passes that ran.
            Err(e) => {
                let note = format!(
                    "the {view} pass {} failed and is left out: {}",
                    video.display(),
                    crate::error::one_line(&e.message)
                );
                eprintln!("warning: {note}");
                notes.push(note);
            }
        }
    }
    if done.is_empty() {
        return Err(CliError::new(
            "no pass of the visit ran; see the errors above",
        ));
    }
    if let Some(w) = gait_visit::frame_rate_warning(&done) {
        eprintln!("warning: {w}");
    }
    let kin = &base.kinematics;
    let o = VisitOptions {
        checklist: &base.checklist,
        normative: base
            .report
            .load_normative()
            .map_err(|e| CliError::new(e.to_string()))?,
        prosthetic: kin.prosthetic_side,
        amputation: kin.amputation.map(|a| a.name()),
        label: gait_visit::VisitLabel {
            subject: args.subject.clone(),
            session: args.session.clone(),
            date: args.date.clone(),
            prosthetic: None,
        },
        notes,
    };
    let t = std::time::Instant::now();
    let summary =
        gait_visit::write(&args.out, &done, &o).map_err(|e| CliError::new(e.to_string()))?;
    let combined_s = t.elapsed().as_secs_f64();
    print_pdf(&base, &summary.report, &args.out);
    let present = if summary.present.is_empty() {
        "none".to_string()
    } else {
        summary.present.join(", ")
    };
    eprintln!(
        "visit of {} pass(es) combined in {combined_s:.2} s -> {} (deviations present: {present})",
        done.len(),
        summary.report.display()
    );
    Ok(())
}

/// One pass, as `gait run` with `kinematics.view` set to the pass's view.
fn run_pass(
    args: &Args,
    view: &str,
    video: &Path,
    dir: &Path,
    models_dir: &Path,
) -> Result<(), CliError> {
    let mut sets = args.sets.clone();
    sets.push(format!("kinematics.view=\"{view}\""));
    let config = PipelineConfig::load(args.config.as_deref(), &sets)?;
    let opts = RunOptions {
        input: video.to_path_buf(),
        out: dir.to_path_buf(),
        models_dir: models_dir.to_path_buf(),
        progress: !args.no_progress,
        command: std::env::args().collect(),
        handle: Some(gait_pipeline::RunHandle::default()),
    };
    if let Some(h) = &opts.handle {
        crate::interrupt::install(h);
    }
    eprintln!("{view} pass: {}", video.display());
    crate::commands::run::run_and_report(&config, &opts)
}

/// report.pdf beside the visit's report.html, as a run prints its own.
fn print_pdf(config: &PipelineConfig, html: &Path, out: &Path) {
    if config.report.pdf == Some(false) {
        return;
    }
    match gait_report::pdf::find_chromium() {
        Some(browser) => {
            if let Err(e) = gait_report::pdf::print_pdf(&browser, html, &out.join("report.pdf")) {
                eprintln!("warning: the visit's report.pdf not written: {e}");
            }
        }
        None if config.report.pdf == Some(true) => {
            eprintln!("warning: report.pdf = true but no Chromium is on the PATH");
        }
        None => {}
    }
}
