//! `cohort.html`: per subject and view, the mean curves of all their videos together; per view,
//! the group mean ± SD across subjects (each subject weighted once: the mean of their videos).

use std::collections::BTreeMap;
use std::fmt::Write as _;

use gait_eval::Side;
use gait_eval::plot::{CycleCurve, GraphContext, gait_graphs};

use crate::cohort::CohortRow;

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Mean and SD over `curves` (same side and joint, same percent grid) point by point.
fn spread(curves: &[&CycleCurve], side: Side, joint: &str) -> Option<CycleCurve> {
    let first = curves.first()?;
    let n = first.mean.len();
    let mut mean = vec![f64::NAN; n];
    let mut sd = vec![f64::NAN; n];
    for i in 0..n {
        let v: Vec<f64> = curves
            .iter()
            .filter_map(|c| c.mean.get(i).copied())
            .filter(|v| v.is_finite())
            .collect();
        if v.is_empty() {
            continue;
        }
        let m = v.iter().sum::<f64>() / v.len() as f64;
        mean[i] = m;
        sd[i] = if v.len() > 1 {
            (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
        } else {
            0.0
        };
    }
    Some(CycleCurve {
        side,
        joint: joint.to_string(),
        percent: first.percent.clone(),
        mean,
        sd,
        n_cycles: curves.len(),
    })
}

/// The mean over groups of curves, per side and joint.
fn mean_curves<'a>(groups: impl Iterator<Item = &'a [CycleCurve]> + Clone) -> Vec<CycleCurve> {
    let mut out = Vec::new();
    for side in Side::BOTH {
        for joint in ["hip", "knee", "ankle"] {
            let of: Vec<&CycleCurve> = groups
                .clone()
                .flat_map(|g| g.iter())
                .filter(|c| c.side == side && c.joint == joint)
                .collect();
            out.extend(spread(&of, side, joint));
        }
    }
    out
}

fn figure(curves: &[CycleCurve], normative: Option<&gait_eval::Normative>) -> String {
    let ctx = GraphContext {
        prosthetic: None,
        normative,
        toe_off: [None, None],
    };
    match gait_graphs(curves, ctx) {
        Ok(f) => f.svg,
        Err(e) => format!("<p>figure not drawn: {}</p>", escape(&e.to_string())),
    }
}

/// The page.
pub fn html(
    rows: &[CohortRow],
    normative: Option<&gait_eval::Normative>,
    visits: &[crate::visits::Written],
) -> String {
    // subject -> view -> each video's curves (both sides).
    let mut by: BTreeMap<(String, String), BTreeMap<String, Vec<CycleCurve>>> = BTreeMap::new();
    for r in rows.iter().filter(|r| !r.curves.is_empty()) {
        by.entry((r.row.view.clone(), r.row.subject.clone()))
            .or_default()
            .entry(r.row.name.clone())
            .or_default()
            .extend(r.curves.iter().cloned());
    }
    let mut s = String::from(
        "<!doctype html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>Cohort</title>\
         <style>body{font:14px/1.4 sans-serif;margin:1.5em;max-width:1250px}svg{max-width:100%;height:auto}\
         td,th{padding:.15em .5em;border-bottom:1px solid #ddd;text-align:left}table{border-collapse:collapse}\
         .failed{color:#a33}</style></head><body><h1>Cohort</h1>",
    );
    let failed: Vec<&CohortRow> = rows.iter().filter(|r| r.status != "done").collect();
    let _ = write!(
        s,
        "<p>{} videos, {} without results. Curves: mean over each video's accepted cycles; the \
         grey band is the normative data. The full table is cohort.csv.</p>",
        rows.iter()
            .map(|r| &r.row.name)
            .collect::<std::collections::BTreeSet<_>>()
            .len(),
        failed.len()
    );
    if !visits.is_empty() {
        s.push_str("<h2>Visits and progress</h2><table><tr><th>visit</th><th>deviations present / changes</th></tr>");
        for v in visits {
            let found = if v.found.is_empty() {
                "none".to_string()
            } else {
                v.found.join(", ")
            };
            let _ = write!(
                s,
                "<tr><td><a href=\"{}\">{}</a></td><td>{}</td></tr>",
                v.page,
                escape(&v.what),
                escape(&found)
            );
        }
        s.push_str("</table>");
    }
    if !failed.is_empty() {
        s.push_str("<h2>Videos without results</h2><table><tr><th>run</th><th>status</th><th>why</th></tr>");
        for r in &failed {
            let _ = write!(
                s,
                "<tr class=\"failed\"><td>{}</td><td>{}</td><td>{}</td></tr>",
                escape(&r.row.name),
                escape(&r.status),
                escape(&r.error)
            );
        }
        s.push_str("</table>");
    }
    let views: std::collections::BTreeSet<&String> = by.keys().map(|(v, _)| v).collect();
    for view in views {
        let label = if view.is_empty() {
            "(no view given)"
        } else {
            view
        };
        let subjects: Vec<(&String, Vec<CycleCurve>)> = by
            .iter()
            .filter(|((v, _), _)| v == view)
            .map(|((_, subj), videos)| (subj, mean_curves(videos.values().map(Vec::as_slice))))
            .collect();
        let _ = write!(
            s,
            "<h2>View: {}</h2><h3>Group: mean ± SD across {} subject(s)</h3>",
            escape(label),
            subjects.len()
        );
        let group = mean_curves(subjects.iter().map(|(_, c)| c.as_slice()));
        s.push_str(&figure(&group, normative));
        for ((v, subject), videos) in by.iter().filter(|((v, _), _)| v == view) {
            let _ = v;
            let _ = write!(
                s,
                "<h3>Subject {}: {} video(s) ({})</h3>",
                escape(if subject.is_empty() {
                    "(none)"
                } else {
                    subject
                }),
                videos.len(),
                escape(&videos.keys().cloned().collect::<Vec<_>>().join(", "))
            );
            let all: Vec<CycleCurve> = videos.values().flatten().cloned().collect();
            s.push_str(&figure(&all, normative));
        }
    }
    s.push_str("</body></html>\n");
    s
}
