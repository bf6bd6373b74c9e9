//! Exports of a run folder (`[export] formats`, `gait export`): from its
//! keypoints_filtered.csv, angles.csv, events.csv and run.json.

use std::path::{Path, PathBuf};

use gait_core::PoseSequence;
use serde_json::Value;

use crate::EvalError;
use crate::report_config::ExportFormat;

/// What the exports need to know beyond the run folder's files.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunFacts {
    pub fps: f64,
    /// Pixels per cm, when the run had a scale (subject height or known length).
    pub px_per_cm: Option<f64>,
}

impl RunFacts {
    /// From the folder's run.json; `fps` overrides (and is needed without one).
    pub fn of_dir(dir: &Path, fps: Option<f64>) -> Result<RunFacts, EvalError> {
        let run = dir.join("run.json");
        let manifest: Option<Value> = match std::fs::read_to_string(&run) {
            Ok(t) => Some(serde_json::from_str(&t).map_err(|e| EvalError::input(&run, e))?),
            Err(_) => None,
        };
        let kin = manifest
            .as_ref()
            .and_then(|m| m.pointer("/extra/kinematics"));
        let fps = fps
            .or_else(|| kin.and_then(|k| k.get("fps")).and_then(Value::as_f64))
            .or_else(|| {
                manifest
                    .as_ref()
                    .and_then(|m| m.pointer("/input/fps"))
                    .and_then(Value::as_f64)
            })
            .ok_or_else(|| {
                EvalError::input(dir, "no run.json with the frame rate here; give --fps N")
            })?;
        let px_per_cm = kin.and_then(|k| k.get("px_per_cm")).and_then(Value::as_f64);
        Ok(RunFacts { fps, px_per_cm })
    }
}

fn need(dir: &Path, file: &str) -> Result<PathBuf, EvalError> {
    let p = dir.join(file);
    if p.exists() {
        Ok(p)
    } else {
        Err(EvalError::input(
            &p,
            "missing; export needs a folder written by `gait run` or `gait kin`",
        ))
    }
}

fn filtered_keypoints(dir: &Path, fps: f64) -> Result<PoseSequence, EvalError> {
    let p = need(dir, "keypoints_filtered.csv")?;
    let f = std::fs::File::open(&p)
        .map_err(|e| EvalError::io(format!("opening {}", p.display()), e))?;
    gait_core::dlc::read(std::io::BufReader::new(f), None, fps).map_err(|e| EvalError::input(&p, e))
}

/// Writes each format into `dir` (keypoints.c3d, keypoints.trc, angles.mot,
/// openpose/); returns what was written.
pub fn export_run(
    dir: &Path,
    formats: &[ExportFormat],
    facts: &RunFacts,
) -> Result<Vec<PathBuf>, EvalError> {
    let mut written = Vec::new();
    let mut seq: Option<PoseSequence> = None;
    for &f in formats {
        let path = dir.join(f.file_name());
        if f != ExportFormat::Mot && seq.is_none() {
            seq = Some(filtered_keypoints(dir, facts.fps)?);
        }
        let keypoints = seq.as_ref();
        match (f, keypoints) {
            (ExportFormat::Mot, _) => {
                let angles = crate::read_angles_csv(&need(dir, "angles.csv")?)?;
                super::write_mot(&angles, facts.fps, &path)?;
            }
            (_, None) => continue,
            (ExportFormat::Trc, Some(s)) => {
                let opts = super::TrcOptions {
                    metres_per_pixel: facts.px_per_cm.map(|p| 0.01 / p),
                };
                super::write_trc(s, &path, &opts)?;
            }
            (ExportFormat::C3d, Some(s)) => {
                let events = super::c3d::read_events(&need(dir, "events.csv")?)?;
                super::c3d::write(s, &events, facts, &path)?;
            }
            (ExportFormat::Openpose, Some(s)) => {
                crate::openpose::write_dir(s, &path, "frame")?;
            }
        }
        written.push(path);
    }
    Ok(written)
}
