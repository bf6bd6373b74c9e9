//! A patient's visit: the passes of one session filmed from the left, the right, the front and
//! the back, each analysed as `gait run` analyses a video, combined into one report
//! ([`write`]): each side's sagittal curves from the view where that limb is near the camera,
//! the frontal measures from the front or back views, the timing pooled over every pass, and
//! the gait-deviation checklist with each item from the pass that can judge it.

mod combine;
mod curves;
mod outcomes;
mod pass;
pub mod progress;
mod tables;

use std::path::{Path, PathBuf};

use gait_checklist::{ChecklistConfig, Side};
use gait_eval::normative::Normative;
use gait_report::Report;

pub use combine::Source;
pub use pass::{Pass, VIEWS};
pub use progress::{Change, VisitLabel, VisitRecord};

#[derive(Debug, thiserror::Error)]
pub enum VisitError {
    #[error("{}: {message}", dir.display())]
    Pass { dir: PathBuf, message: String },
    #[error("{0}")]
    Checklist(#[from] gait_checklist::ChecklistError),
    #[error("{0}")]
    Report(#[from] gait_eval::EvalError),
    #[error("writing {}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// What the visit is judged with.
pub struct VisitOptions<'a> {
    pub checklist: &'a ChecklistConfig,
    pub normative: Option<Normative>,
    pub prosthetic: Option<Side>,
    pub amputation: Option<&'a str>,
    /// Who and when (visit.json), for `gait progress`.
    pub label: VisitLabel,
    /// What the caller has to say about the visit (a pass that failed and is left out).
    pub notes: Vec<String>,
}

/// What [`write`] made.
#[derive(Debug)]
pub struct VisitSummary {
    pub report: PathBuf,
    pub sources: Vec<Source>,
    /// Checklist items found present, `item (side)`.
    pub present: Vec<String>,
}

/// Combines the analysed `passes` into `out`: report.html, visit_checklist.csv,
/// visit_cycles.csv and visit_spatiotemporal.csv.
pub fn write(out: &Path, passes: &[Pass], o: &VisitOptions) -> Result<VisitSummary, VisitError> {
    let mut sources = Vec::new();
    let sagittal = curves::sagittal(passes, &mut sources);
    let (frontal, frontal_view) = curves::frontal(passes, &mut sources);
    let spatiotemporal = combine::spatiotemporal(passes);
    let checklist = judge_each(passes, o)?;
    tables::write_all(out, &checklist, &sagittal, &frontal, &spatiotemporal)?;
    let label = VisitLabel {
        prosthetic: o.prosthetic.map(|s| s.name().to_string()),
        ..o.label.clone()
    };
    let label = serde_json::to_string_pretty(&label).unwrap_or_default();
    std::fs::write(out.join("visit.json"), label).map_err(|source| VisitError::Io {
        path: out.join("visit.json"),
        source,
    })?;
    let mut report = Report {
        title: "Visit report".into(),
        prosthetic_side: o.prosthetic.map(|s| match s {
            Side::Left => gait_eval::Side::Left,
            Side::Right => gait_eval::Side::Right,
        }),
        cycles: sagittal,
        spatiotemporal,
        normative: o.normative.clone(),
        ..Default::default()
    };
    report.subject = passes
        .iter()
        .map(|p| {
            let image = p
                .image
                .as_ref()
                .map_or(String::new(), |l| format!(" In the image: {l}"));
            format!(
                "{}: {}; run folder {}.{image}",
                p.label(),
                p.status,
                p.dir.display()
            )
        })
        .chain(sources.iter().map(|s| format!("{}: {}", s.what, s.pass)))
        .collect();
    report.warnings = warnings(passes, o);
    report.sections.push(tables::checklist_html(&checklist, o));
    report.frontal = frontal_view.map(|view| gait_report::frontal::FrontalReport {
        how: "the front or back pass with the most cycles of each side".into(),
        view,
        curves: frontal,
        normative: gait_eval::normative_frontal::for_sagittal(
            o.normative.as_ref().map(|n| n.name.as_str()),
        ),
        ..Default::default()
    });
    let present = checklist
        .iter()
        .filter(|(v, _)| v.status == gait_checklist::Status::Present)
        .map(|(v, _)| format!("{} ({})", v.item.id, v.side.name()))
        .collect();
    let path = report.write(out)?;
    Ok(VisitSummary {
        report: path,
        sources,
        present,
    })
}

/// The visit's warnings: the caller's, frame rates that differ, then each pass's own, named by
/// its view, so the visit report says what each pass's report says (a frame rate resampled, an
/// HDR video converted) without opening it.
fn warnings(passes: &[Pass], o: &VisitOptions) -> Vec<String> {
    let own = passes.iter().flat_map(|p| {
        p.warnings
            .iter()
            .map(move |w| format!("{}: {w}", p.label()))
    });
    o.notes
        .iter()
        .cloned()
        .chain(frame_rate_warning(passes))
        .chain(own)
        .collect()
}

/// Passes filmed at different frame rates are combined in seconds; this says which.
pub fn frame_rate_warning(passes: &[Pass]) -> Option<String> {
    let rates: Vec<(String, f64)> = passes
        .iter()
        .filter_map(|p| Some((p.label(), p.fps?)))
        .collect();
    let (first, f0) = rates.first()?;
    let (other, f) = rates.iter().find(|(_, f)| (f - f0).abs() > 0.01)?;
    Some(format!(
        "{other} was filmed at {f} fps and {first} at {f0} fps; the visit combines them in seconds"
    ))
}

/// Each pass's checklist, then the best verdict per item and side.
fn judge_each(
    passes: &[Pass],
    o: &VisitOptions,
) -> Result<Vec<(gait_checklist::Verdict, String)>, VisitError> {
    let mut per_pass = Vec::new();
    for p in passes {
        let list = gait_checklist::assess(
            &p.dir,
            o.checklist,
            o.normative.as_ref(),
            o.prosthetic,
            o.amputation,
        )?;
        per_pass.push((p, list.verdicts));
    }
    let timing = combine::side_view_timing(passes)
        .into_iter()
        .map(|r| gait_checklist::Param {
            parameter: r.parameter,
            side: r.side,
            mean: r.mean,
            sd: r.sd,
            n: r.n,
            unit: r.unit,
        })
        .collect();
    let pooled = gait_checklist::pooled_timing(timing, o.checklist);
    let sides: Vec<String> = passes
        .iter()
        .filter(|p| !p.is_frontal())
        .map(Pass::label)
        .collect();
    let from = format!("the side views' timing pooled: {}", sides.join(" + "));
    let preferred = o.prosthetic.unwrap_or(Side::Left);
    Ok(combine::checklist(&per_pass, (&pooled, &from), preferred))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pass(view: &str, video: &str, fps: f64, warnings: &[&str]) -> Pass {
        Pass {
            view: view.into(),
            video: video.into(),
            dir: PathBuf::new(),
            sagittal: Vec::new(),
            frontal: Vec::new(),
            spatiotemporal: Vec::new(),
            status: "done".into(),
            fps: Some(fps),
            warnings: warnings.iter().map(|w| w.to_string()).collect(),
            near: Vec::new(),
            image: None,
        }
    }

    /// The visit report says what each pass's own report says, named by its view, after the
    /// caller's notes and the frame rates that differ.
    #[test]
    fn the_visit_carries_each_pass_s_warnings() {
        let checklist = ChecklistConfig::default();
        let o = VisitOptions {
            checklist: &checklist,
            normative: None,
            prosthetic: None,
            amputation: None,
            label: VisitLabel::default(),
            notes: vec!["the anterior pass a.mp4 failed and is left out: no person".into()],
        };
        let passes = [
            pass(
                "left",
                "l.mov",
                30.0,
                &["its frames were resampled to a constant 30.00 fps"],
            ),
            pass("right", "r.mov", 25.0, &["the video is HDR (HLG)"]),
        ];
        let w = warnings(&passes, &o);
        assert_eq!(w.len(), 4, "{w:?}");
        assert!(w[0].contains("anterior pass"));
        assert!(w[1].contains("filmed at 25 fps"));
        assert_eq!(
            w[2],
            "left view (l.mov): its frames were resampled to a constant 30.00 fps"
        );
        assert_eq!(w[3], "right view (r.mov): the video is HDR (HLG)");
    }
}
