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

/// A visit written, or a subject's progress over its visits, for the cohort page.
#[derive(Debug, Clone)]
pub struct Written {
    /// `S01 session 1`, or `S01: progress over 3 visits`.
    pub what: String,
    /// The page, relative to the batch folder.
    pub page: String,
    /// Checklist items present, or changes called.
    pub found: Vec<String>,
}

/// Writes each visit from its rows that ran, then each subject's progress over two or more
/// visits (`progress/SUBJECT`, as `gait progress`).
pub fn write(out: &Path, plan: &Plan, cohort: &[CohortRow]) -> Result<Vec<Written>, BatchError> {
    let mut written = visits(out, plan, cohort)?;
    written.extend(progress(out, &written)?);
    Ok(written)
}

fn fail(what: String, e: gait_visit::VisitError) -> BatchError {
    BatchError::io(what, std::io::Error::other(e.to_string()))
}

/// Each subject's progress over its visits written here.
fn progress(out: &Path, visits: &[Written]) -> Result<Vec<Written>, BatchError> {
    let mut by: BTreeMap<String, Vec<gait_visit::VisitRecord>> = BTreeMap::new();
    for v in visits {
        let dir = out.join(&v.page);
        let dir = dir.parent().unwrap_or(out);
        let record = gait_visit::VisitRecord::read(dir)
            .map_err(|e| fail(format!("the visit {}", v.what), e))?;
        by.entry(record.label.subject.clone())
            .or_default()
            .push(record);
    }
    let mut done = Vec::new();
    for (subject, mut records) in by.into_iter().filter(|(_, r)| r.len() > 1) {
        gait_visit::progress::order(&mut records);
        let dir = out.join("progress").join(&subject);
        let changes = gait_visit::progress::write(&dir, &records)
            .map_err(|e| fail(format!("the progress of {subject}"), e))?;
        done.push(Written {
            what: format!("{subject}: progress over {} visits", records.len()),
            page: format!("progress/{subject}/progress.html"),
            found: changes
                .iter()
                .filter(|c| c.call == "change")
                .map(|c| format!("{} ({}) {:+.1} {}", c.item, c.side, c.difference, c.unit))
                .collect(),
        });
    }
    Ok(done)
}

/// Writes each visit from its rows that ran.
fn visits(out: &Path, plan: &Plan, cohort: &[CohortRow]) -> Result<Vec<Written>, BatchError> {
    let mut written = Vec::new();
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
            .map_err(|e| fail(format!("the visit {subject} {session}"), e))?;
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
                prosthetic: None,
            },
            // Rows that failed are reported by the batch's own summary.
            notes: Vec::new(),
        };
        let summary = gait_visit::write(&visit_dir(out, &subject, &session), &passes, &o)
            .map_err(|e| fail(format!("the visit {subject} {session}"), e))?;
        written.push(Written {
            what: format!("{subject} session {session}"),
            page: format!("visits/{subject}_{session}/report.html"),
            found: summary.present,
        });
    }
    Ok(written)
}
