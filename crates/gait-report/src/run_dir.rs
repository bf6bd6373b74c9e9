//! A report of a `gait run` / `gait kin` output folder: it reads exactly the
//! files a reader of the folder gets.

use std::path::Path;

use serde_json::Value;

use crate::report::{Report, Table};
use crate::spatiotemporal::read_spatiotemporal;
use gait_eval::normative::Normative;
use gait_eval::scores::Scores;
use gait_eval::{EvalError, Side};

/// Files of the run folder shown as tables, with their titles.
const TABLES: [(&str, &str); 3] = [
    (
        "cycle_quality.csv",
        "Cycle quality: every cycle found, kept or rejected",
    ),
    ("bouts.csv", "Walking bouts"),
    ("events.csv", "Gait events"),
];

/// Files that, when present, are listed as downloads of the run.
const EXPORTS: [&str; 6] = [
    "overlay.mp4",
    "keypoints.c3d",
    "keypoints.trc",
    "angles.mot",
    "openpose",
    "report.pdf",
];

impl Report {
    /// The report of `dir`: `run.json` (its `warnings` arrays, anywhere, are
    /// listed), `cycles.csv`, `cycles_all.csv`, `spatiotemporal.csv`, the
    /// quality, bout and event tables, a skeleton strip from `keypoints.csv`,
    /// and scores against `normative`. Absent files are left out.
    pub fn from_run_dir(
        dir: &Path,
        prosthetic_side: Option<Side>,
        normative: Option<Normative>,
    ) -> Result<Report, EvalError> {
        let mut r = Report {
            prosthetic_side,
            title: format!("Gait analysis report: {}", dir.display()),
            ..Default::default()
        };
        let run = dir.join("run.json");
        let kin = dir.join("kin.json");
        if run.exists() {
            let v = read_json(&run)?;
            collect_warnings(&v, &mut r.warnings);
            r.subject = crate::subject_lines::describe(&v);
            r.manifest = Some(v);
        } else if kin.exists() {
            // A `gait kin` folder: its analysis' warnings.
            collect_warnings(&read_json(&kin)?, &mut r.warnings);
        }
        let sagittal_norm = normative.as_ref().map(|n| n.name.as_str());
        r.frontal = crate::frontal::FrontalReport::read(dir, r.manifest.as_ref(), sagittal_norm)?;
        let cycles = dir.join("cycles.csv");
        if cycles.exists() {
            r.cycles = gait_eval::plot::read_cycles_csv(&cycles)?;
        }
        let all = dir.join("cycles_all.csv");
        if all.exists() {
            r.traces = gait_eval::read_cycles_all_csv(&all)?;
        }
        let st = dir.join("spatiotemporal.csv");
        if st.exists() {
            r.spatiotemporal = read_spatiotemporal(&st)?;
        }
        r.toe_off = Side::BOTH.map(|s| {
            r.spatiotemporal
                .iter()
                .find(|p| p.parameter == "stance" && p.side == s.as_str())
                .map(|p| p.mean)
                .filter(|v| v.is_finite())
        });
        if let Some(t) = r.manifest.as_ref().and_then(corrections_table) {
            r.tables.push(t);
        }
        for (file, title) in TABLES {
            let p = dir.join(file);
            if p.exists() {
                r.tables.push(read_table(&p, title)?);
            }
        }
        r.exports = EXPORTS
            .iter()
            .filter(|f| dir.join(f).exists())
            .map(|f| f.to_string())
            .collect();
        let video = dir.join("overlay.mp4");
        if std::fs::metadata(&video).is_ok_and(|m| m.len() <= crate::report::EMBED_VIDEO_MAX) {
            r.overlay_video = std::fs::read(&video).ok();
        }
        r.strip = strip(dir, &r)?;
        if let Some(n) = &normative {
            r.scores = Some(Scores::compute(&r.cycles, n));
        }
        r.normative = normative;
        Ok(r)
    }
}

fn strip(dir: &Path, r: &Report) -> Result<Option<gait_eval::Figure>, EvalError> {
    let kp = dir.join("keypoints.csv");
    if !kp.exists() {
        return Ok(None);
    }
    let fps = r
        .manifest
        .as_ref()
        .and_then(|m| m.get("fps"))
        .and_then(Value::as_f64)
        .unwrap_or(30.0);
    let seq = gait_eval::read_poses(&kp, fps, None)?;
    if seq.is_empty() {
        return Ok(None);
    }
    gait_eval::plot::skeleton_strip(&seq, &[], &gait_eval::plot::StripOptions::default()).map(Some)
}

/// The corrections a person applied (run.json's kinematics summary), as a table.
fn corrections_table(manifest: &Value) -> Option<Table> {
    // `"corrections": null` is a run without a corrections file: no table.
    let c = manifest
        .pointer("/extra/kinematics/corrections")
        .filter(|c| !c.is_null())?;
    let n = |k: &str| c.get(k).and_then(Value::as_u64).unwrap_or(0).to_string();
    let sha = c.get("sha256").and_then(Value::as_str).unwrap_or("");
    let path = c.get("path").and_then(Value::as_str).unwrap_or("");
    Some(Table {
        title: format!(
            "Corrections applied ({path}, sha256 {})",
            sha.get(..12).unwrap_or(sha)
        ),
        header: ["correction", "entries", "frames"]
            .map(String::from)
            .to_vec(),
        rows: vec![
            vec!["swap left/right".into(), n("swaps"), n("swapped_frames")],
            vec!["event added".into(), n("events_added"), String::new()],
            vec!["event removed".into(), n("events_removed"), String::new()],
            vec![
                "frames excluded".into(),
                n("excludes"),
                n("excluded_frames"),
            ],
            vec!["keypoint set".into(), n("keypoints"), String::new()],
        ],
    })
}

fn read_json(path: &Path) -> Result<Value, EvalError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| EvalError::io(format!("reading {}", path.display()), e))?;
    serde_json::from_str(&text).map_err(|e| EvalError::input(path, e))
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

/// A CSV cell as the report shows it: numbers to 3 decimals (the CSV keeps them all), so a
/// table of many columns fits a printed page.
fn shown(cell: &str) -> String {
    match cell.split_once('.') {
        Some((_, decimals)) if decimals.len() > 3 && cell.parse::<f64>().is_ok() => {
            format!("{:.3}", cell.parse::<f64>().unwrap_or(f64::NAN))
        }
        _ => cell.to_string(),
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
                .map(shown)
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
    fn overlay_video_is_embedded_when_small_and_explained_when_not() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("overlay.mp4"), b"not really a video").unwrap();
        let html = Report::from_run_dir(dir.path(), None, None)
            .unwrap()
            .html()
            .unwrap();
        assert!(html.contains("src=\"data:video/mp4;base64,"), "embedded");
        assert!(html.contains("plays wherever the page is opened"));
        let mut r = Report::from_run_dir(dir.path(), None, None).unwrap();
        r.overlay_video = None;
        let html = r.html().unwrap();
        assert!(
            html.contains("src=\"overlay.mp4\"")
                && html.contains("a copy of the page alone shows no video")
        );
    }

    #[test]
    fn table_numbers_are_shown_to_three_decimals() {
        assert_eq!(shown("1.266667"), "1.267");
        assert_eq!(shown("0.5"), "0.5");
        assert_eq!(shown("117"), "117");
        assert_eq!(shown("left"), "left");
        assert_eq!(shown("a.bcdef"), "a.bcdef");
    }

    #[test]
    fn corrections_null_is_no_corrections_table() {
        let none = serde_json::json!({"extra": {"kinematics": {"corrections": null}}});
        assert_eq!(corrections_table(&none), None);
        let some = serde_json::json!({"extra": {"kinematics": {"corrections":
            {"path": "corrections.toml", "sha256": "abcdef0123456789", "swaps": 2}}}});
        let t = corrections_table(&some).unwrap();
        assert!(t.title.contains("corrections.toml"), "{}", t.title);
        assert_eq!(t.rows[0][1], "2");
    }
}
