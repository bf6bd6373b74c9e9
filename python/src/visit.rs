//! `visit`: run folders of one session's passes combined as `gait visit` combines them.

use std::path::PathBuf;

use pyo3::prelude::*;

use crate::errors::input_error;
use crate::run::load;

/// Combines the run folders `passes` (view, video, run folder) into `out` with the config's
/// checklist, norms, prosthetic side and amputation; returns the visit report's path.
#[pyfunction]
#[pyo3(signature = (out, passes, config=None, sets=Vec::new(), subject=String::new(), session=String::new(), date=String::new()))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn visit(
    out: PathBuf,
    passes: Vec<(String, PathBuf, PathBuf)>,
    config: Option<PathBuf>,
    sets: Vec<String>,
    subject: String,
    session: String,
    date: String,
) -> PyResult<PathBuf> {
    let config = load(config, &sets)?;
    let bad = |e: gait_visit::VisitError| input_error(e.to_string());
    let read = passes
        .iter()
        .map(|(view, video, dir)| {
            if !gait_visit::VIEWS.contains(&view.as_str()) {
                return Err(input_error(format!(
                    "view `{view}` is not one of {}",
                    gait_visit::VIEWS.join(", ")
                )));
            }
            gait_visit::Pass::read(view, video, dir).map_err(bad)
        })
        .collect::<PyResult<Vec<_>>>()?;
    let kin = &config.kinematics;
    let o = gait_visit::VisitOptions {
        checklist: &config.checklist,
        normative: config
            .report
            .load_normative()
            .map_err(|e| input_error(e.to_string()))?,
        prosthetic: kin.prosthetic_side,
        amputation: kin.amputation.map(|a| a.name()),
        label: gait_visit::VisitLabel {
            subject,
            session,
            date,
            prosthetic: None,
        },
        // The passes were run by the caller (gait.run); those that failed are not given.
        notes: Vec::new(),
    };
    Ok(gait_visit::write(&out, &read, &o).map_err(bad)?.report)
}
