//! The visits of a study: rows with the same subject and session that name their view are the
//! passes of one visit, combined into `visits/SUBJECT_SESSION/` as `gait visit` combines its
//! passes (gait-visit), once the rows have run.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::BatchError;
use crate::cohort::CohortRow;
use crate::plan::{Plan, PlannedRow, run_dir};

/// The folder of a visit.
pub fn visit_dir(out: &Path, subject: &str, session: &str) -> PathBuf {
    out.join("visits").join(format!("{subject}_{session}"))
}

/// Rows grouped by (subject, session), for those with a subject and a view.
pub fn groups(rows: &[PlannedRow]) -> BTreeMap<(String, String), Vec<&PlannedRow>> {
    let mut g: BTreeMap<(String, String), Vec<&PlannedRow>> = BTreeMap::new();
    for r in rows
        .iter()
        .filter(|r| !r.subject.is_empty() && !r.view.is_empty())
    {
        g.entry((r.subject.clone(), r.session.clone()))
            .or_default()
            .push(r);
    }
    g
}

/// Writes each visit from its rows that ran; returns the visits written.
pub fn write(out: &Path, plan: &Plan, cohort: &[CohortRow]) -> Result<usize, BatchError> {
    let mut written = 0;
    for ((subject, session), rows) in groups(&plan.rows) {
        let ran: Vec<&PlannedRow> = rows
            .into_iter()
            .filter(|r| {
                cohort
                    .iter()
                    .any(|c| c.row.name == r.name && c.status == "done")
            })
            .collect();
        let Some(first) = ran.first() else { continue };
        let config = Plan::config(out, first)?;
        let passes = ran
            .iter()
            .map(|r| gait_visit::Pass::read(&r.view, &r.video, &run_dir(out, r)))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| {
                BatchError::io(
                    format!("the visit {subject} {session}"),
                    std::io::Error::other(e.to_string()),
                )
            })?;
        let kin = &config.kinematics;
        let o = gait_visit::VisitOptions {
            checklist: &config.checklist,
            normative: config.report.load_normative().ok().flatten(),
            prosthetic: kin.prosthetic_side,
            amputation: kin.amputation.map(|a| a.name()),
            label: gait_visit::VisitLabel {
                subject: subject.clone(),
                session: session.clone(),
                date: first.date.clone(),
            },
        };
        gait_visit::write(&visit_dir(out, &subject, &session), &passes, &o).map_err(|e| {
            BatchError::io(
                format!("the visit {subject} {session}"),
                std::io::Error::other(e.to_string()),
            )
        })?;
        written += 1;
    }
    Ok(written)
}
