//! `report.html`: one self-contained page per run (plots inline, no external
//! resources, no script) for clinicians and researchers.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::html::{base64, escape, table};
use crate::spatiotemporal::StParam;
use gait_eval::CycleTrace;
use gait_eval::normative::Normative;
use gait_eval::plot::{CycleCurve, FailureEntry, Figure, comparison_plot, failure_bars};
use gait_eval::scores::Scores;
use gait_eval::table_markdown;
use gait_eval::{EvalError, Evaluation, Side};

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
    /// Every accepted cycle, for the all-cycles plot (`cycles_all.csv`).
    pub traces: Vec<CycleTrace>,
    /// Mean toe-off of each side (left, right) in % of the cycle.
    pub toe_off: [Option<f64>; 2],
    /// The normative band and reference of the scores.
    pub normative: Option<Normative>,
    /// GVS / sagittal GPS against `normative`.
    pub scores: Option<Scores>,
    /// `spatiotemporal.csv`, shown with norms and symmetry.
    pub spatiotemporal: Vec<StParam>,
    /// Files of the run folder linked from the report (overlay video, exports).
    pub exports: Vec<String>,
    /// overlay.mp4 itself when it is small enough to travel inside the page
    /// ([`EMBED_VIDEO_MAX`]); otherwise the page links the file beside it.
    pub overlay_video: Option<Vec<u8>>,
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
    /// A front or back view's frontal measures.
    pub frontal: Option<crate::frontal::FrontalReport>,
    /// Sections made elsewhere (the gait-deviation checklist), as HTML, shown after the
    /// warnings.
    pub sections: Vec<String>,
}

impl Default for Report {
    fn default() -> Self {
        Self {
            title: "Gait analysis report".into(),
            prosthetic_side: None,
            subject: vec![],
            cycles: vec![],
            traces: vec![],
            toe_off: [None, None],
            normative: None,
            scores: None,
            spatiotemporal: vec![],
            exports: vec![],
            overlay_video: None,
            truth_cycles: vec![],
            method_cycles: vec![],
            evaluations: vec![],
            failure_entries: vec![],
            strip: None,
            tables: vec![],
            manifest: None,
            warnings: vec![],
            frontal: None,
            sections: vec![],
        }
    }
}

const STYLE: &str = "body{font-family:'DejaVu Sans',Arial,sans-serif;margin:24px;color:#222;max-width:1280px}\
h1{font-size:24px}h2{font-size:19px;margin-top:28px;border-bottom:1px solid #ccc}\
figure{margin:12px 0}figure svg,figure img{max-width:100%;height:auto;border:1px solid #ddd}\
table{border-collapse:collapse;margin:8px 0}td,th{border:1px solid #bbb;padding:3px 8px;text-align:left;font-size:13px}\
th{background:#f0f0f0}.warnings li{color:#8a4b00}pre{background:#f6f6f6;padding:8px;overflow:auto;font-size:12px;white-space:pre-wrap;word-break:break-all}\
video{max-width:100%;border:1px solid #ddd}.no-cycles{color:#8a4b00;font-weight:bold}\
table.provenance td{font-family:monospace;overflow-wrap:anywhere}\
@page{size:A4;margin:12mm}\
@media print{body{margin:0;max-width:none}figure{break-inside:avoid}tr{break-inside:avoid}video,details.manifest{display:none}h2{break-after:avoid}\
table{width:100%;table-layout:auto}td,th{font-size:8.5px;padding:2px 3px}\
table.wide td,table.wide th{font-size:7.5px;padding:1px 2px}}";

/// The largest overlay.mp4 embedded in report.html (base64 adds a third): a page that plays
/// its video anywhere, without growing past a few MB.
pub const EMBED_VIDEO_MAX: u64 = 4 << 20;

/// A figure's SVG inlined with its caption.
pub(crate) fn figure(fig: &Figure, caption: &str) -> String {
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
        for section in &self.sections {
            body.push_str(section);
        }
        if let Some(f) = &self.frontal {
            body.push_str(&f.html(self.prosthetic_side)?);
        }
        body.push_str(&self.gait_sections()?);
        body.push_str(&self.score_section()?);
        body.push_str(&self.spatiotemporal_section());
        body.push_str(&self.video_section());
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
                "<figure id=\"fig-skeleton\" class=\"plot\"><img alt=\"skeleton overlay frames\" src=\"data:image/png;base64,{}\"><figcaption>Detected keypoints; left leg red, right leg blue.</figcaption></figure>",
                base64(&strip.png)
            ));
        }
        for t in &self.tables {
            body.push_str(&format!("<h2>{}</h2>", escape(&t.title)));
            body.push_str(&table(&t.header, &t.rows));
        }
        if !self.exports.is_empty() {
            body.push_str("<h2 id=\"files\">Files of this run</h2><ul>");
            for f in &self.exports {
                body.push_str(&format!("<li><a href=\"{0}\">{0}</a></li>", escape(f)));
            }
            body.push_str("</ul>");
        }
        if let Some(m) = &self.manifest {
            body.push_str(&crate::provenance::section(m));
        }
        Ok(format!(
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title><style>{STYLE}</style></head><body>{body}</body></html>\n",
            escape(&self.title)
        ))
    }

    /// The overlay video: embedded when small, else played from the run folder, which the page
    /// says (a copy of report.html alone would show an empty player).
    fn video_section(&self) -> String {
        if !self.exports.iter().any(|f| f == "overlay.mp4") {
            return String::new();
        }
        let (src, where_) = match &self.overlay_video {
            Some(bytes) => (
                format!("data:video/mp4;base64,{}", base64(bytes)),
                "The video is embedded in this page, so it plays wherever the page is opened."
                    .to_string(),
            ),
            None => (
                "overlay.mp4".to_string(),
                format!(
                    "The video is too large to embed (over {} MB): it plays from overlay.mp4 beside report.html, \
                     so open the page in its run folder; a copy of the page alone shows no video.",
                    EMBED_VIDEO_MAX >> 20
                ),
            ),
        };
        format!(
            "<h2 id=\"overlay\">Overlay video</h2><video controls preload=\"metadata\" src=\"{src}\" width=\"960\"></video>\
             <p>overlay.mp4: the skeleton on every analysed frame (left red, right blue), heel strikes and toe-offs as they happen; \
             frames outside walking bouts or in rejected cycles dimmed. {where_}</p>"
        )
    }

    /// Writes `report.html` into `out_dir`; returns its path.
    pub fn write(&self, out_dir: &Path) -> Result<PathBuf, EvalError> {
        gait_eval::fsutil::ensure_dir(out_dir)?;
        let path = out_dir.join("report.html");
        gait_eval::fsutil::write_atomic(&path, self.html()?.as_bytes())?;
        Ok(path)
    }
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
            "parameter,side,mean,sd,n,unit\ncadence,both,104.2,,5,steps/min\n",
        )
        .unwrap();
        let html = Report::from_run_dir(dir.path(), Some(Side::Left), None)
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
            Report::from_run_dir(empty.path(), None, None)
                .unwrap()
                .html()
                .unwrap()
                .contains("<p>None.</p>")
        );
    }
}
