//! `gait batch`: a study (many videos, one row each) analysed as a set of `gait run` folders,
//! on this machine or as Slurm job arrays, then gathered into a cohort table.
//!
//! [`Study`] reads the study file; [`Plan`] checks every row and writes the batch folder's plan,
//! which each task reads; [`local::run_local`] and [`slurm::submit`] run the tasks (the `gait`
//! binary again, through [`Launcher`]); [`state`] reads where each row stands from its run
//! folder; [`aggregate`] writes cohort.csv and cohort.html.

pub mod cohort;
mod cohort_html;
mod error;
pub mod launch;
pub mod local;
pub mod plan;
pub mod slurm;
pub mod state;
pub mod study;
pub mod visits;

use std::path::Path;

pub use error::BatchError;
pub use launch::{Launcher, Task};
pub use plan::{Plan, PlannedRow, run_dir};
pub use state::RowState;
pub use study::{Study, StudyRow};

/// Writes cohort.csv and cohort.html into `out` from the run folders (failed rows included);
/// returns the number of rows that have no results.
pub fn aggregate(out: &Path, plan: &Plan) -> Result<usize, BatchError> {
    let rows = cohort::collect(out, plan);
    let write = |name: &str, bytes: &[u8]| {
        let path = out.join(name);
        gait_pipeline::atomic::write(&path, bytes)
            .map_err(|e| BatchError::io(format!("writing {}", path.display()), e))
    };
    write("cohort.csv", cohort::csv(&rows).as_bytes())?;
    // Rows of one subject and session with their views make a visit; two visits, progress.
    let visits = visits::write(out, plan, &rows)?;
    let normative = gait_eval::report_config::ReportConfig::default()
        .load_normative()
        .ok()
        .flatten();
    write(
        "cohort.html",
        cohort_html::html(&rows, normative.as_ref(), &visits).as_bytes(),
    )?;
    let mut failed: Vec<&str> = rows
        .iter()
        .filter(|r| r.status != "done")
        .map(|r| r.row.name.as_str())
        .collect();
    failed.dedup();
    Ok(failed.len())
}
