//! How the passes of a visit are combined: each side's sagittal curves from the side view where
//! that limb is near the camera, the frontal curves from the front or back view with the most
//! cycles, the timing pooled over every pass, and each checklist item from the pass that can
//! judge it best.

use gait_checklist::{Status, Verdict};
use gait_eval::plot::CycleCurve;
use gait_report::spatiotemporal::StParam;

use crate::pass::Pass;

/// Where a part of the visit comes from, for the report.
#[derive(Debug, Clone)]
pub struct Source {
    pub what: String,
    pub pass: String,
}

const SIDES: [&str; 2] = ["left", "right"];

/// Each side's sagittal curves: from its own side view (the limb near the camera), else from
/// the other side view (the far limb, half hidden), said so.
pub fn sagittal(passes: &[Pass], sources: &mut Vec<Source>) -> Vec<CycleCurve> {
    let mut out = Vec::new();
    for side in SIDES {
        let best = |near: bool| {
            passes
                .iter()
                .filter(|p| {
                    !p.is_frontal() && (p.view == side) == near && p.cycles(side, false) > 0
                })
                .max_by_key(|p| p.cycles(side, false))
        };
        let (pass, how) = match (best(true), best(false)) {
            (Some(p), _) => (p, "near the camera"),
            (None, Some(p)) => (p, "far from the camera: no pass from its own side"),
            (None, None) => {
                sources.push(Source {
                    what: format!("{side} sagittal curves"),
                    pass: "none: no side view with an accepted cycle of this limb".into(),
                });
                continue;
            }
        };
        out.extend(
            pass.sagittal
                .iter()
                .filter(|c| c.side.as_str() == side)
                .cloned(),
        );
        sources.push(Source {
            what: format!("{side} sagittal curves"),
            pass: format!(
                "{} ({how}), {} cycles",
                pass.label(),
                pass.cycles(side, false)
            ),
        });
    }
    out
}

/// Each side's frontal curves from the front or back pass with the most of its cycles.
pub fn frontal(passes: &[Pass], sources: &mut Vec<Source>) -> (Vec<CycleCurve>, Option<String>) {
    let mut out = Vec::new();
    let mut view = None;
    for side in SIDES {
        let best = passes
            .iter()
            .filter(|p| p.is_frontal() && p.cycles(side, true) > 0)
            .max_by_key(|p| p.cycles(side, true));
        let Some(p) = best else {
            sources.push(Source {
                what: format!("{side} frontal curves"),
                pass: "none: no front or back view with an accepted cycle of this side".into(),
            });
            continue;
        };
        view.get_or_insert_with(|| p.view.clone());
        out.extend(
            p.frontal
                .iter()
                .filter(|c| c.side.as_str() == side)
                .cloned(),
        );
        sources.push(Source {
            what: format!("{side} frontal curves"),
            pass: format!("{}, {} cycles", p.label(), p.cycles(side, true)),
        });
    }
    (out, view)
}

/// Timing (stride and step time, stance, cadence) pooled over every pass where it was measured:
/// means weighted by their counts, SDs pooled; the symmetry index from the pooled sides.
pub fn spatiotemporal(passes: &[Pass]) -> Vec<StParam> {
    let mut out = Vec::new();
    for (parameter, sides) in [
        ("stride_time", &SIDES[..]),
        ("step_time", &SIDES[..]),
        ("stance", &SIDES[..]),
        ("cadence", &["both"][..]),
    ] {
        for &side in sides {
            let rows: Vec<&StParam> = passes
                .iter()
                .flat_map(|p| &p.spatiotemporal)
                .filter(|r| {
                    r.parameter == parameter && r.side == side && r.n > 0 && r.mean.is_finite()
                })
                .collect();
            if let Some(p) = pool(&rows) {
                out.push(p);
            }
        }
    }
    for parameter in ["stride_time", "step_time", "stance"] {
        let mean = |s: &str| {
            out.iter()
                .find(|r| r.parameter == parameter && r.side == s)
                .map(|r| (r.mean, r.n))
        };
        if let (Some((l, nl)), Some((r, nr))) = (mean("left"), mean("right")) {
            out.push(StParam {
                parameter: format!("symmetry_index_{parameter}"),
                side: "left_vs_right".into(),
                mean: 100.0 * (l - r) / (0.5 * (l + r)),
                sd: f64::NAN,
                n: nl.min(nr),
                unit: "%".into(),
            });
        }
    }
    out
}

fn pool(rows: &[&StParam]) -> Option<StParam> {
    let n: usize = rows.iter().map(|r| r.n).sum();
    if n == 0 {
        return None;
    }
    let mean = rows.iter().map(|r| r.mean * r.n as f64).sum::<f64>() / n as f64;
    // Within-pass variance plus the passes' spread about the pooled mean.
    let ss: f64 = rows
        .iter()
        .map(|r| {
            let within = if r.sd.is_finite() {
                r.sd * r.sd * (r.n as f64 - 1.0)
            } else {
                0.0
            };
            within + r.n as f64 * (r.mean - mean).powi(2)
        })
        .sum();
    Some(StParam {
        parameter: rows[0].parameter.clone(),
        side: rows[0].side.clone(),
        mean,
        sd: if n > 1 {
            (ss / (n as f64 - 1.0)).sqrt()
        } else {
            f64::NAN
        },
        n,
        unit: rows[0].unit.clone(),
    })
}

/// Each item and side from the pass that judges it best: an assessable verdict before a
/// not-assessable one; for a side-view item the side's own view (its limb near the camera)
/// first; then the verdict resting on more cycles. Returns the verdicts with their pass.
pub fn checklist(per_pass: &[(&Pass, Vec<Verdict>)]) -> Vec<(Verdict, String)> {
    let mut out: Vec<(Verdict, String)> = Vec::new();
    let Some((_, first)) = per_pass.first() else {
        return out;
    };
    for template in first {
        let (id, side) = (template.item.id, template.side);
        let candidates = per_pass.iter().filter_map(|(p, vs)| {
            vs.iter()
                .find(|v| v.item.id == id && v.side == side)
                .map(|v| (*p, v))
        });
        let rank = |(p, v): &(&Pass, &Verdict)| {
            (
                v.status != Status::NotAssessable,
                v.item.view == "side" && p.view == side.name(),
                p.cycles(side.name(), v.item.view != "side"),
            )
        };
        if let Some((p, v)) = candidates.max_by_key(rank) {
            let from = if v.status == Status::NotAssessable {
                String::new()
            } else {
                p.label()
            };
            out.push((v.clone(), from));
        }
    }
    out
}
