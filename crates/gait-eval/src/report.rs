//! `report.html`: one self-contained page per run (plots inline, no external
//! resources, no script) for clinicians and researchers.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::html::{base64, escape, table};
use crate::plot::{
    CycleCurve, FailureEntry, Figure, comparison_plot, failure_bars, kinematics_plot,
};
use crate::table::table_markdown;
use crate::{EvalError, Evaluation, Side};

/// A titled table of text cells.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Table {
    pub title: String,
    pub header: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

/// What a report shows; every part is optional.
#[derive(Debug, Clone)]
pub struct Report {
    pub title: String,
    /// The prosthetic leg, when the run names one; otherwise the sides are
    /// shown as left and right only.
    pub prosthetic_side: Option<Side>,
    /// Who was analysed and when they walked (from run.json), as lines.
    pub subject: Vec<String>,
    /// This run's joint angles over the gait cycle (gait-kin's cycles).
    pub cycles: Vec<CycleCurve>,
    /// Ground-truth cycles and other methods' cycles, for the comparison figure.
    pub truth_cycles: Vec<CycleCurve>,
    pub method_cycles: Vec<(String, Vec<CycleCurve>)>,
    /// Evaluations against ground truth (Table 1 and failure modes).
    pub evaluations: Vec<Evaluation>,
    /// Failure modes per camera view; by default one entry per evaluation.
    pub failure_entries: Vec<FailureEntry>,
    /// The skeleton overlay strip (its PNG is embedded).
    pub strip: Option<Figure>,
    /// Further tables (spatiotemporal parameters, events, ...).
    pub tables: Vec<Table>,
    /// The run manifest (`run.json`).
    pub manifest: Option<Value>,
    /// Swapped frames, rejected cycles and anything else to flag.
    pub warnings: Vec<String>,
}

impl Default for Report {
    fn default() -> Self {
        Self {
            title: "Gait analysis report".into(),
            prosthetic_side: None,
            subject: vec![],
            cycles: vec![],
            truth_cycles: vec![],
            method_cycles: vec![],
            evaluations: vec![],
            failure_entries: vec![],
            strip: None,
            tables: vec![],
            manifest: None,
            warnings: vec![],
        }
    }
}

const STYLE: &str = "body{font-family:'DejaVu Sans',Arial,sans-serif;margin:24px;color:#222;max-width:1280px}\
h1{font-size:24px}h2{font-size:19px;margin-top:28px;border-bottom:1px solid #ccc}\
figure{margin:12px 0}figure svg,figure img{max-width:100%;height:auto;border:1px solid #ddd}\
table{border-collapse:collapse;margin:8px 0}td,th{border:1px solid #bbb;padding:3px 8px;text-align:left;font-size:13px}\
th{background:#f0f0f0}.warnings li{color:#8a4b00}pre{background:#f6f6f6;padding:8px;overflow:auto;font-size:12px}";

fn figure(fig: &Figure, caption: &str) -> String {
    // plotters' SVG is self-contained markup; drop any XML prolog before inlining.
    let svg = fig
        .svg
        .find("<svg")
        .map(|i| &fig.svg[i..])
        .unwrap_or(&fig.svg);
    format!(
        "<figure id=\"fig-{}\" class=\"plot\">{svg}<figcaption>{}</figcaption></figure>",
        escape(&fig.name),
        escape(caption)
    )
}

/// Markdown table (as written by [`table_markdown`]) to header and rows.
fn parse_markdown(md: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let split = |l: &str| {
        l.trim()
            .trim_matches('|')
            .split('|')
            .map(|c| c.trim().to_string())
            .collect::<Vec<_>>()
    };
    let mut lines = md.lines().filter(|l| l.starts_with('|'));
    let header = lines.next().map(split).unwrap_or_default();
    let rows = lines
        .filter(|l| !l.starts_with("|---"))
        .map(split)
        .collect();
    (header, rows)
}

impl Report {
    /// The page as one HTML string.
    pub fn html(&self) -> Result<String, EvalError> {
        let mut body = format!("<h1>{}</h1>", escape(&self.title));
        let sides = match self.prosthetic_side {
            Some(p) => format!(
                "Prosthetic side: <b>{}</b>, intact side: <b>{}</b>.",
                p.as_str(),
                p.other().as_str()
            ),
            None => "Sides: left and right (no prosthetic side set; <code>--set kinematics.prosthetic_side=\"left\"</code> names it).".into(),
        };
        body.push_str(&format!(
            "<p>{sides} Joint angles in degrees; hip and knee flexion and ankle dorsiflexion positive.</p>"
        ));
        if !self.subject.is_empty() {
            body.push_str("<h2>Subject and walking bouts</h2><ul>");
            for line in &self.subject {
                body.push_str(&format!("<li>{}</li>", escape(line)));
            }
            body.push_str("</ul>");
        }
        body.push_str("<h2>Warnings</h2>");
        if self.warnings.is_empty() {
            body.push_str("<p>None.</p>");
        } else {
            body.push_str("<ul class=\"warnings\">");
            for w in &self.warnings {
                body.push_str(&format!("<li>{}</li>", escape(w)));
            }
            body.push_str("</ul>");
        }
        if !self.cycles.is_empty() {
            body.push_str("<h2>Kinematics over the gait cycle</h2>");
            let fig = kinematics_plot(&self.cycles, self.prosthetic_side)?;
            let colours = match self.prosthetic_side {
                Some(_) => "prosthetic red, intact blue",
                None => "left blue, right red",
            };
            body.push_str(&figure(
                &fig,
                &format!("Mean (line) and SD (band) over the accepted cycles; {colours}."),
            ));
        }
        if !self.truth_cycles.is_empty() && !self.method_cycles.is_empty() {
            body.push_str("<h2>Methods against ground truth</h2>");
            let fig = comparison_plot(
                &self.truth_cycles,
                &self.method_cycles,
                self.prosthetic_side.unwrap_or(Side::Right),
            )?;
            body.push_str(&figure(
                &fig,
                "Ground truth green with its SD band; one colour per method.",
            ));
        }
        if !self.evaluations.is_empty() {
            body.push_str("<h2>Errors against ground truth</h2>");
            let (h, rows) = parse_markdown(&table_markdown(&self.evaluations));
            body.push_str(&table(&h, &rows));
            let mut rows = Vec::new();
            for e in &self.evaluations {
                let f = &e.failures;
                rows.push(vec![
                    e.options.method.clone(),
                    e.options.view.clone().unwrap_or_default(),
                    f.frames.to_string(),
                    format!("{:.1}", f.not_identified.percent),
                    format!("{:.1}", f.misidentified.percent),
                    format!("{:.1}", f.swapped.percent),
                    format!("{:.1} px", f.misid_threshold_px),
                ]);
            }
            let header = [
                "Method",
                "View",
                "Frames",
                "Not identified %",
                "Misidentified %",
                "Swapped %",
                "Misidentified above",
            ];
            body.push_str(&table(&header.map(String::from), &rows));
            let entries: Vec<FailureEntry> = if self.failure_entries.is_empty() {
                self.evaluations
                    .iter()
                    .map(|e| FailureEntry {
                        view: e.options.view.clone().unwrap_or_else(|| "video".into()),
                        method: e.options.method.clone(),
                        failures: e.failures.clone(),
                    })
                    .collect()
            } else {
                self.failure_entries.clone()
            };
            let fig = failure_bars(&entries)?;
            body.push_str(&figure(
                &fig,
                "Failure modes as percentages of frames, per camera view.",
            ));
        }
        if let Some(strip) = &self.strip {
            body.push_str("<h2>Skeleton overlay</h2>");
            body.push_str(&format!(
                "<figure id=\"fig-skeleton\" class=\"plot\"><img alt=\"skeleton overlay frames\" src=\"data:image/png;base64,{}\"><figcaption>Detected keypoints; left leg blue, right leg red.</figcaption></figure>",
                base64(&strip.png)
            ));
        }
        for t in &self.tables {
            body.push_str(&format!("<h2>{}</h2>", escape(&t.title)));
            body.push_str(&table(&t.header, &t.rows));
        }
        if let Some(m) = &self.manifest {
            body.push_str("<h2>Run manifest (run.json)</h2>");
            let text = serde_json::to_string_pretty(m)
                .map_err(|e| EvalError::io("formatting run.json", e.into()))?;
            body.push_str(&format!("<pre>{}</pre>", escape(&text)));
        }
        Ok(format!(
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title><style>{STYLE}</style></head><body>{body}</body></html>\n",
            escape(&self.title)
        ))
    }

    /// Writes `report.html` into `out_dir`; returns its path.
    pub fn write(&self, out_dir: &Path) -> Result<PathBuf, EvalError> {
        crate::fsutil::ensure_dir(out_dir)?;
        let path = out_dir.join("report.html");
        crate::fsutil::write_atomic(&path, self.html()?.as_bytes())?;
        Ok(path)
    }

    /// A report of a `gait run` / `gait kin` output folder: `run.json` (its
    /// `warnings` arrays, anywhere, are listed), `cycles.csv`,
    /// `spatiotemporal.csv` and `events.csv` when present, and a skeleton strip
    /// from `keypoints.csv`. Files that are absent are left out.
    pub fn from_run_dir(dir: &Path, prosthetic_side: Option<Side>) -> Result<Report, EvalError> {
        let mut r = Report {
            prosthetic_side,
            title: format!("Gait analysis report: {}", dir.display()),
            ..Default::default()
        };
        let run = dir.join("run.json");
        if run.exists() {
            let text = std::fs::read_to_string(&run)
                .map_err(|e| EvalError::io(format!("reading {}", run.display()), e))?;
            let v: Value = serde_json::from_str(&text).map_err(|e| EvalError::input(&run, e))?;
            collect_warnings(&v, &mut r.warnings);
            r.subject = crate::subject_lines::describe(&v);
            r.manifest = Some(v);
        }
        let cycles = dir.join("cycles.csv");
        if cycles.exists() {
            r.cycles = crate::plot::read_cycles_csv(&cycles)?;
        }
        for (file, title) in [
            (
                "spatiotemporal.csv",
                "Spatiotemporal parameters (accepted cycles)",
            ),
            (
                "cycle_quality.csv",
                "Cycle quality: every cycle found, kept or rejected",
            ),
            ("bouts.csv", "Walking bouts"),
            ("events.csv", "Gait events"),
        ] {
            let p = dir.join(file);
            if p.exists() {
                r.tables.push(read_table(&p, title)?);
            }
        }
        let kp = dir.join("keypoints.csv");
        if kp.exists() {
            let fps = r
                .manifest
                .as_ref()
                .and_then(|m| m.get("fps"))
                .and_then(Value::as_f64)
                .unwrap_or(30.0);
            let seq = crate::read_poses(&kp, fps, None)?;
            if !seq.is_empty() {
                r.strip = Some(crate::plot::skeleton_strip(
                    &seq,
                    &[],
                    &crate::plot::StripOptions::default(),
                )?);
            }
        }
        Ok(r)
    }
}

/// Every string in arrays under a key named `warnings`, at any depth.
fn collect_warnings(v: &Value, out: &mut Vec<String>) {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                if k == "warnings"
                    && let Value::Array(items) = x
                {
                    // run.json repeats a step's warnings in its summary; list each once.
                    for w in items.iter().filter_map(Value::as_str) {
                        if !out.iter().any(|o| o == w) {
                            out.push(w.to_string());
                        }
                    }
                } else {
                    collect_warnings(x, out);
                }
            }
        }
        Value::Array(items) => items.iter().for_each(|x| collect_warnings(x, out)),
        _ => {}
    }
}

fn read_table(path: &Path, title: &str) -> Result<Table, EvalError> {
    let mut r = csv::Reader::from_path(path).map_err(|e| EvalError::input(path, e))?;
    let header = r
        .headers()
        .map_err(|e| EvalError::input(path, e))?
        .iter()
        .map(str::to_string)
        .collect();
    let mut rows = Vec::new();
    for rec in r.records() {
        rows.push(
            rec.map_err(|e| EvalError::input(path, e))?
                .iter()
                .map(str::to_string)
                .collect(),
        );
    }
    Ok(Table {
        title: title.into(),
        header,
        rows,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_dir_report_lists_warnings_and_tables() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("run.json"),
            r#"{"tool":"gait 0.1.0","kinematics":{"warnings":["left/right leg labels corrected in 3 frames","<cycle 2 rejected>"]}}"#,
        )
        .unwrap();
        std::fs::write(
            dir.path().join("spatiotemporal.csv"),
            "parameter,side,value,unit\ncadence,,104.2,steps/min\n",
        )
        .unwrap();
        let html = Report::from_run_dir(dir.path(), Some(Side::Left))
            .unwrap()
            .html()
            .unwrap();
        assert!(html.contains("<li>left/right leg labels corrected in 3 frames</li>"));
        assert!(
            html.contains("&lt;cycle 2 rejected&gt;"),
            "warnings are escaped"
        );
        assert!(
            html.contains("<td>cadence</td>")
                && html.contains("&quot;tool&quot;: &quot;gait 0.1.0&quot;")
        );
        assert!(!html.contains("<script"), "no script in the report");
        let empty = tempfile::tempdir().unwrap();
        assert!(
            Report::from_run_dir(empty.path(), None)
                .unwrap()
                .html()
                .unwrap()
                .contains("<p>None.</p>")
        );
    }
}
