//! What a run folder gets after the kinematics: the exports of `[export]`,
//! overlay.mp4, report.html with its scores, and report.pdf. `gait run`,
//! `gait kin` and `gait export` all end here, so a folder looks the same
//! whichever command wrote it.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use gait_eval::Side;
use gait_eval::export::{RunFacts, export_run};
use gait_eval::report_config::ExportFormat;
use gait_report::Report;

use crate::{PipelineConfig, PipelineError};

/// Where and what to write.
pub struct OutputOptions<'a> {
    pub dir: &'a Path,
    /// The input video, for overlay.mp4 (None: no overlay).
    pub input: Option<&'a Path>,
    pub config: &'a PipelineConfig,
    /// Frame rate, when the folder has no run.json (`gait kin`).
    pub fps: Option<f64>,
    pub progress: bool,
    /// Stops the overlay between frames, and the PDF before it starts (a signal, Ctrl-C).
    pub handle: Option<&'a crate::RunHandle>,
}

/// What was written, and what the user should know.
#[derive(Debug, Default)]
pub struct Outputs {
    pub report: PathBuf,
    pub files: Vec<PathBuf>,
    pub warnings: Vec<String>,
    /// Wall-clock seconds of each step (exports, overlay, report, pdf), as run.json records them.
    pub seconds: BTreeMap<&'static str, f64>,
}

fn failed(what: &str, e: impl ToString) -> PipelineError {
    PipelineError::Output {
        what: what.into(),
        message: e.to_string(),
    }
}

/// Exports, overlay, report and PDF, in that order (the report links the files).
pub fn write_outputs(o: &OutputOptions) -> Result<Outputs, PipelineError> {
    let mut out = Outputs::default();
    let t = Instant::now();
    let facts = RunFacts::of_dir(o.dir, o.fps).map_err(|e| failed("the exports", e))?;
    out.files = export_run(o.dir, &o.config.export.formats, &facts)
        .map_err(|e| failed("the exports", e))?;
    out.seconds.insert("exports", t.elapsed().as_secs_f64());
    if o.config.report.overlay
        && let Some(input) = o.input
    {
        let t = Instant::now();
        let (path, warnings) =
            crate::overlay::write_overlay(o.dir, input, o.config, o.progress, o.handle)?;
        out.seconds.insert("overlay", t.elapsed().as_secs_f64());
        out.files.push(path);
        out.warnings.extend(warnings);
    }
    let t = Instant::now();
    let chromium = pdf_browser(o.config, &mut out.warnings)?;
    let report = build_report(o, chromium.is_some())?;
    out.report = report.write(o.dir).map_err(|e| failed("report.html", e))?;
    out.seconds.insert("report", t.elapsed().as_secs_f64());
    if let Some(browser) = chromium {
        stop_point(o.handle, "report.pdf")?;
        let t = Instant::now();
        let pdf = o.dir.join("report.pdf");
        gait_report::pdf::print_pdf(&browser, &out.report, &pdf)
            .map_err(|e| failed("report.pdf", e))?;
        out.seconds.insert("pdf", t.elapsed().as_secs_f64());
        out.files.push(pdf);
    }
    record(o.dir, &report, &out.seconds)?;
    Ok(out)
}

/// The error that ends a run its handle stopped, before `step`.
pub(crate) fn stop_point(
    handle: Option<&crate::RunHandle>,
    step: &str,
) -> Result<(), PipelineError> {
    match handle {
        Some(h) if h.is_stopped() => Err(PipelineError::Interrupted { step: step.into() }),
        _ => Ok(()),
    }
}

/// The Chromium to print with, per `[report] pdf`: required when true, used
/// when found when unset (with a warning when not).
fn pdf_browser(
    config: &PipelineConfig,
    warnings: &mut Vec<String>,
) -> Result<Option<PathBuf>, PipelineError> {
    let found = gait_report::pdf::find_chromium();
    match (config.report.pdf, found) {
        (Some(false), _) => Ok(None),
        (_, Some(b)) => Ok(Some(b)),
        (Some(true), None) => Err(failed(
            "report.pdf",
            "report.pdf = true but no Chromium is on the PATH; install the Debian package chromium (or set CHROMIUM=/path/to/chromium), or set report.pdf=false",
        )),
        (None, None) => {
            warnings.push(
                "report.pdf not written: no Chromium on the PATH (install the Debian package chromium, or set CHROMIUM=/path/to/chromium; report.pdf=false silences this)".into(),
            );
            Ok(None)
        }
    }
}

fn build_report(o: &OutputOptions, with_pdf: bool) -> Result<Report, PipelineError> {
    let side = o.config.kinematics.prosthetic_side.map(|s| match s {
        gait_kin::Side::Left => Side::Left,
        gait_kin::Side::Right => Side::Right,
    });
    let normative = o
        .config
        .report
        .load_normative()
        .map_err(|e| failed("the report", e))?;
    let mut report =
        Report::from_run_dir(o.dir, side, normative).map_err(|e| failed("the report", e))?;
    if with_pdf && !report.exports.iter().any(|f| f == "report.pdf") {
        report.exports.push("report.pdf".into());
    }
    if let Some(s) = &report.scores {
        let path = o.dir.join("scores.csv");
        crate::atomic::write(&path, s.csv().as_bytes())
            .map_err(|e| PipelineError::io(format!("writing {}", path.display()), e))?;
    }
    report
        .sections
        .push(checklist(o, report.normative.as_ref())?);
    Ok(report)
}

/// The gait-deviation checklist of the run folder: checklist.csv, and its report section.
fn checklist(
    o: &OutputOptions,
    norm: Option<&gait_eval::normative::Normative>,
) -> Result<String, PipelineError> {
    let kin = &o.config.kinematics;
    let side = kin.prosthetic_side;
    let list = gait_checklist::assess(
        o.dir,
        &o.config.checklist,
        norm,
        side,
        kin.amputation.map(|a| a.name()),
    )
    .map_err(|e| failed("the checklist", e))?;
    let path = o.dir.join("checklist.csv");
    crate::atomic::write(&path, list.csv().as_bytes())
        .map_err(|e| PipelineError::io(format!("writing {}", path.display()), e))?;
    Ok(list.html())
}

/// The steps of [`write_outputs`] in the order they run (the keys of [`Outputs::seconds`]).
pub(crate) const STEPS: &[&str] = &["exports", "overlay", "report", "pdf"];

/// Adds the report's scores and files to run.json (when there is one).
fn record(
    dir: &Path,
    report: &Report,
    seconds: &BTreeMap<&'static str, f64>,
) -> Result<(), PipelineError> {
    let formats: Vec<&str> = ExportFormat::ALL
        .iter()
        .filter(|f| dir.join(f.file_name()).exists())
        .map(|f| f.as_str())
        .collect();
    let report = serde_json::json!({
        "normative": report.normative.as_ref().map(|n| n.name.clone()),
        "scores": report.scores,
        "exports": formats,
        "files": report.exports,
        "seconds": seconds,
    });
    record_in_manifest(dir, "report", &report)
}

/// Sets `key` of the run.json in `dir` to `value` (nothing when there is no run.json).
pub(crate) fn record_in_manifest(
    dir: &Path,
    key: &str,
    value: &impl serde::Serialize,
) -> Result<(), PipelineError> {
    let path = dir.join("run.json");
    let Ok(text) = std::fs::read_to_string(&path) else {
        return Ok(());
    };
    let mut v: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| failed("run.json", e))?;
    if let Some(m) = v.as_object_mut() {
        m.insert(key.into(), serde_json::to_value(value).unwrap_or_default());
    }
    let text = serde_json::to_string_pretty(&v).map_err(|e| failed("run.json", e))?;
    crate::atomic::write(&path, text.as_bytes())
        .map_err(|e| PipelineError::io(format!("writing {}", path.display()), e))
}
