//! The gait-deviation checklist of the keypoints under review, with the page's corrections.
//! It is judged by the same code as a run's checklist.csv, on the tables `gait kin` writes, so
//! a deviation followed here from a report can be looked at, corrected, and seen to stay or go.

use gait_checklist::{ChecklistConfig, Side, Verdict};
use gait_eval::Normative;
use gait_kin::KinResult;
use gait_pipeline::PipelineConfig;

/// What the checklist is judged with: the run's `[checklist]`, normative set and patient.
#[derive(Debug, Clone)]
pub struct ChecklistSettings {
    cfg: ChecklistConfig,
    norm: Option<Normative>,
    prosthetic: Option<Side>,
    amputation: Option<&'static str>,
}

impl ChecklistSettings {
    /// The settings of `config` (the run's, or the one given to `gait review --keypoints`).
    pub fn of(config: &PipelineConfig) -> Self {
        Self {
            cfg: config.checklist.clone(),
            // A run whose normative file does not load has failed before it had a folder.
            norm: config.report.load_normative().ok().flatten(),
            prosthetic: config.kinematics.prosthetic_side,
            amputation: config.kinematics.amputation.map(|a| a.name()),
        }
    }
}

/// Every item's verdict on the result `r`, or why there is none (the page shows it).
pub fn judge(r: &KinResult, s: &ChecklistSettings) -> Result<Vec<Verdict>, String> {
    let dir = tempfile::tempdir().map_err(|e| format!("the checklist: a scratch folder: {e}"))?;
    gait_kin::write_outputs(r, dir.path()).map_err(|e| format!("the checklist: {e}"))?;
    let list = gait_checklist::assess(
        dir.path(),
        &s.cfg,
        s.norm.as_ref(),
        s.prosthetic,
        s.amputation,
    )
    .map_err(|e| format!("the checklist: {e}"))?;
    Ok(list
        .verdicts
        .into_iter()
        .map(|v| Verdict {
            run: String::new(),
            ..v
        })
        .collect())
}
