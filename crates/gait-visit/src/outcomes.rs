//! What `gait progress` shows beside the checklist: each visit's GPS and GVS per
//! side, its symmetry indices, and each side's mean sagittal curves of every
//! visit over the normative band. Read from the visit folders' tables.

use std::path::Path;

use gait_eval::normative::Normative;
use gait_eval::plot::{CycleCurve, read_curves_csv, visits_plot};
use gait_eval::{Scores, Side};
use gait_report::html::{base64, escape, table};

use crate::VisitError;
use crate::progress::VisitRecord;

/// One visit's outcomes (empty where its folder lacks a table).
struct Outcomes {
    curves: Vec<CycleCurve>,
    /// (parameter, value in %) of visit_spatiotemporal.csv's symmetry rows.
    symmetry: Vec<(String, f64)>,
}

fn read(dir: &Path) -> Outcomes {
    let curves = read_curves_csv(&dir.join("visit_cycles.csv"), "curve")
        .unwrap_or_default()
        .into_iter()
        .filter(|c| ["hip", "knee", "ankle"].contains(&c.joint.as_str()))
        .collect();
    let mut symmetry = Vec::new();
    if let Ok(mut r) = csv::Reader::from_path(dir.join("visit_spatiotemporal.csv")) {
        for rec in r.records().flatten() {
            let (p, v) = (rec.get(0).unwrap_or(""), rec.get(2).unwrap_or(""));
            if let (Some(name), Ok(v)) = (p.strip_prefix("symmetry_index_"), v.parse::<f64>()) {
                symmetry.push((name.replace('_', " "), v));
            }
        }
    }
    Outcomes { curves, symmetry }
}

fn cell(v: Option<f64>) -> String {
    v.filter(|x| x.is_finite())
        .map_or("–".into(), |x| format!("{x:.1}"))
}

/// The scores table, the symmetry table and the curve figure, as HTML sections.
pub(crate) fn html(
    visits: &[VisitRecord],
    norm: Option<&Normative>,
    prosthetic: Option<Side>,
) -> Result<String, VisitError> {
    let all: Vec<Outcomes> = visits.iter().map(|v| read(&v.dir)).collect();
    let header: Vec<String> = std::iter::once("Measure".to_string())
        .chain(visits.iter().map(|v| v.name()))
        .collect();
    let mut out = String::new();
    if let Some(norm) = norm {
        let scores: Vec<Scores> = all
            .iter()
            .map(|o| Scores::compute(&o.curves, norm))
            .collect();
        let mut rows = Vec::new();
        for side in [Some(Side::Left), Some(Side::Right), None] {
            let name = side.map_or("both sides".into(), |s| s.as_str().to_string());
            let mut row = vec![format!("GPS, {name} (deg)")];
            row.extend(scores.iter().map(|s| cell(s.gps_of(side))));
            rows.push(row);
        }
        for side in [Side::Left, Side::Right] {
            for joint in ["hip", "knee", "ankle"] {
                let mut row = vec![format!("GVS {joint}, {} (deg)", side.as_str())];
                row.extend(scores.iter().map(|s| cell(s.gvs_of(side, joint))));
                rows.push(row);
            }
        }
        out.push_str(&format!(
            "<h2>Gait Profile Score</h2><p>Sagittal GPS and GVS of each visit's mean curves against {} (RMS difference over the cycle; lower is nearer the norm). Shown, not judged: a GPS has no spread over cycles to test a difference against.</p>{}",
            escape(&norm.name),
            table(&header, &rows)
        ));
    }
    let mut names: Vec<&String> = all
        .iter()
        .flat_map(|o| o.symmetry.iter().map(|s| &s.0))
        .collect();
    names.sort();
    names.dedup();
    if !names.is_empty() {
        let rows: Vec<Vec<String>> = names
            .iter()
            .map(|n| {
                let mut row = vec![format!("{n} (%)")];
                row.extend(
                    all.iter()
                        .map(|o| cell(o.symmetry.iter().find(|s| &&s.0 == n).map(|s| s.1))),
                );
                row
            })
            .collect();
        out.push_str(&format!(
            "<h2>Symmetry indices</h2><p>100 × (left − right) / mean of the two, pooled over the visit's passes; 0 is symmetric.</p>{}",
            table(&header, &rows)
        ));
    }
    let curves: Vec<(String, Vec<CycleCurve>)> = visits
        .iter()
        .zip(all)
        .filter(|(_, o)| !o.curves.is_empty())
        .map(|(v, o)| (v.name(), o.curves))
        .collect();
    if !curves.is_empty() {
        let fig = visits_plot(&curves, norm, prosthetic)?;
        out.push_str(&format!(
            "<h2>Mean curves, visit by visit</h2><figure><img alt=\"each side's mean sagittal curves of every visit over the normative band\" src=\"data:image/png;base64,{}\" style=\"max-width:100%\"><figcaption>Each visit's mean curve per side and joint (one colour per visit, in order) over the normative mean ± 1 SD (grey).</figcaption></figure>",
            base64(&fig.png)
        ));
    }
    Ok(out)
}
