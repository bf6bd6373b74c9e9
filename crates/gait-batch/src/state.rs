//! Where each row stands, read from its run folder: complete (run.json for the planned config,
//! with the report step done), failed (the task left its error), or not run.

use std::path::Path;

use gait_pipeline::PipelineConfig;
use serde::Serialize;

use crate::plan::{PlannedRow, run_dir};

/// The file a failed task leaves in its run folder: the error, one line.
pub const ERROR_FILE: &str = "batch-error.txt";

/// A row's state.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RowState {
    Done,
    /// Complete, but with nothing to measure (run.json's `"status": "no_result"`).
    NoResult,
    Failed,
    /// Queued or running on Slurm.
    Running,
    NotRun,
}

impl RowState {
    pub fn name(&self) -> &'static str {
        match self {
            RowState::Done => "done",
            RowState::NoResult => "no result",
            RowState::Failed => "failed",
            RowState::Running => "running",
            RowState::NotRun => "not run",
        }
    }
}

/// True when the run folder holds a finished run of `config`: run.json with that config and
/// the report step's record (written last).
pub fn is_complete(out: &Path, row: &PlannedRow, config: &PipelineConfig) -> bool {
    let Ok(text) = std::fs::read_to_string(run_dir(out, row).join("run.json")) else {
        return false;
    };
    let Ok(v) = serde_json::from_str::<serde_json::Value>(&text) else {
        return false;
    };
    let want = serde_json::to_value(config).unwrap_or_default();
    v.get("config") == Some(&want) && v.get("report").is_some()
}

impl RowState {
    /// Done or with no result: the run completed and is not run again.
    pub fn finished(&self) -> bool {
        matches!(self, RowState::Done | RowState::NoResult)
    }
}

/// Why a complete run has no result (run.json's `reason` when its status is "no_result").
pub fn no_result(out: &Path, row: &PlannedRow) -> Option<String> {
    let text = std::fs::read_to_string(run_dir(out, row).join("run.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    (v.get("status")?.as_str()? == "no_result").then(|| {
        v.get("reason")
            .and_then(|r| r.as_str())
            .unwrap_or("nothing to measure")
            .to_string()
    })
}

/// The error a failed task left, if any.
pub fn failure(out: &Path, row: &PlannedRow) -> Option<String> {
    std::fs::read_to_string(run_dir(out, row).join(ERROR_FILE))
        .ok()
        .map(|s| s.trim().to_string())
}

/// Records why the row failed (one line), for `gait batch status` and the cohort table.
pub fn record_failure(out: &Path, row: &PlannedRow, message: &str) -> std::io::Result<()> {
    let dir = run_dir(out, row);
    std::fs::create_dir_all(&dir)?;
    let line = message.split_whitespace().collect::<Vec<_>>().join(" ");
    gait_pipeline::atomic::write(&dir.join(ERROR_FILE), format!("{line}\n").as_bytes())
}

/// Forgets an earlier failure before the row runs again.
pub fn clear_failure(out: &Path, row: &PlannedRow) {
    let _ = std::fs::remove_file(run_dir(out, row).join(ERROR_FILE));
}

/// The row's state from its folder alone (Slurm's queue is asked elsewhere).
pub fn row_state(out: &Path, row: &PlannedRow, config: Option<&PipelineConfig>) -> RowState {
    if config.is_some_and(|c| is_complete(out, row, c)) {
        if no_result(out, row).is_some() {
            RowState::NoResult
        } else {
            RowState::Done
        }
    } else if failure(out, row).is_some() {
        RowState::Failed
    } else {
        RowState::NotRun
    }
}
