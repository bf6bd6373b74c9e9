//! How the passes of a visit are combined (the curves: curves.rs): the timing pooled over every
//! pass, and each checklist item from the pass that can judge it best, its cycles pooled over
//! the passes that see it alike.

use gait_checklist::{Status, Verdict};
use gait_report::spatiotemporal::StParam;

use crate::pass::Pass;

/// Where a part of the visit comes from, for the report.
#[derive(Debug, Clone)]
pub struct Source {
    pub what: String,
    pub pass: String,
}

const SIDES: [&str; 2] = ["left", "right"];

/// Timing (stride and step time, stance, cadence) pooled over every pass where it was measured:
/// means weighted by their counts, SDs pooled; the symmetry index from the pooled sides.
pub fn spatiotemporal(passes: &[Pass]) -> Vec<StParam> {
    pooled(&passes.iter().collect::<Vec<_>>())
}

/// The timing of the side views alone, pooled: what the checklist's timing items are judged
/// on (they need a side view).
pub fn side_view_timing(passes: &[Pass]) -> Vec<StParam> {
    pooled(
        &passes
            .iter()
            .filter(|p| !p.is_frontal())
            .collect::<Vec<_>>(),
    )
}

fn pooled(passes: &[&Pass]) -> Vec<StParam> {
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
    let groups: Vec<(f64, f64, usize)> = rows.iter().map(|r| (r.mean, r.sd, r.n)).collect();
    let (mean, sd, n) = gait_checklist::pool_groups(&groups)?;
    Some(StParam {
        parameter: rows[0].parameter.clone(),
        side: rows[0].side.clone(),
        mean,
        sd,
        n,
        unit: rows[0].unit.clone(),
    })
}

/// Each item and side from the pass that judges it best: an assessable verdict before a
/// not-assessable one; for a side-view item the side's own view (its limb near the camera)
/// first; then the verdict resting on more cycles. An item that compares the two sides takes
/// both from one judgement: `pooled` (the timing items judged on the side views' pooled timing,
/// and where that comes from) where it judged, else one pass that judges both sides, the view
/// of `preferred` (the prosthetic side; else the left) first, so that visits compare alike.
/// Returns the verdicts with their source.
pub fn checklist(
    per_pass: &[(&Pass, Vec<Verdict>)],
    pooled: (&[Verdict], &str),
    preferred: gait_checklist::Side,
) -> Vec<(Verdict, String)> {
    let mut out: Vec<(Verdict, String)> = Vec::new();
    let Some((_, first)) = per_pass.first() else {
        return out;
    };
    for template in first {
        let (id, side) = (template.item.id, template.side);
        let find = |vs: &[Verdict]| {
            vs.iter()
                .find(|v| v.item.id == id && v.side == side)
                .cloned()
        };
        if let Some(v) = find(pooled.0).filter(|v| v.status != Status::NotAssessable) {
            out.push((v, pooled.1.to_string()));
            continue;
        }
        if let Some((v, from)) = pooled_over_side_views(per_pass, id, side, preferred) {
            out.push((v, from));
            continue;
        }
        let chosen = if template.item.paired {
            per_pass
                .iter()
                .max_by_key(|(p, vs)| both_sides_rank(p, vs, id, preferred))
                .and_then(|(p, vs)| Some((*p, find(vs)?)))
        } else {
            per_pass
                .iter()
                .filter_map(|(p, vs)| Some((*p, find(vs)?)))
                .max_by_key(|(p, v)| {
                    (
                        v.status != Status::NotAssessable,
                        v.item.view == "side" && p.near_camera(side.name()),
                        p.cycles(side.name(), v.item.view != "side"),
                    )
                })
        };
        if let Some((p, v)) = chosen {
            if let Some(pooled) = pooled_over_like_passes(per_pass, p, &v) {
                out.push(pooled);
                continue;
            }
            let from = match (v.status, v.item.paired) {
                (Status::NotAssessable, _) => String::new(),
                (_, true) => format!("{}, both sides", p.label()),
                _ => p.label(),
            };
            out.push((v, from));
        }
    }
    out
}

/// Item `id` of `side` pooled over the side views that judge it on both sides (the best ranked
/// first), for the items of [`gait_checklist::POOLED_OVER_VIEWS`]: a left and a right view see
/// each leg once near and once far (pool.rs).
fn pooled_over_side_views(
    per_pass: &[(&Pass, Vec<Verdict>)],
    id: &str,
    side: gait_checklist::Side,
    preferred: gait_checklist::Side,
) -> Option<(Verdict, String)> {
    if !gait_checklist::POOLED_OVER_VIEWS.contains(&id) {
        return None;
    }
    let mut views: Vec<&(&Pass, Vec<Verdict>)> = per_pass
        .iter()
        .filter(|(p, vs)| !p.is_frontal() && both_sides_rank(p, vs, id, preferred).0)
        .collect();
    views.sort_by_key(|(p, vs)| std::cmp::Reverse(both_sides_rank(p, vs, id, preferred)));
    let verdicts: Vec<&Verdict> = views
        .iter()
        .filter_map(|(_, vs)| vs.iter().find(|v| v.item.id == id && v.side == side))
        .collect();
    let v = gait_checklist::pooled(&verdicts)?;
    let labels: Vec<String> = views.iter().map(|(p, _)| p.label()).collect();
    Some((
        v,
        format!("{}, both sides, cycles pooled", labels.join(" + ")),
    ))
}

/// The judged verdict `v` of pass `p` pooled with the same item's verdicts from the passes that
/// see that side as `p` does: the side views with the limb as near the camera, or the passes of
/// the same front or back view. A clinic films several short passes of one view, each with a
/// stride or two a side, and one stride's foot items are not reliable under the pose model's
/// jitter (BENCHMARKS.md, "Visit and checklist"). Items that weigh one side against the other
/// keep one judgement; `None` where no other pass judges it alike.
fn pooled_over_like_passes(
    per_pass: &[(&Pass, Vec<Verdict>)],
    p: &Pass,
    v: &Verdict,
) -> Option<(Verdict, String)> {
    if v.item.paired || v.status == Status::NotAssessable {
        return None;
    }
    let side = v.side.name();
    let alike = |q: &Pass| {
        if v.item.view == "side" {
            !q.is_frontal() && q.near_camera(side) == p.near_camera(side)
        } else {
            q.view == p.view
        }
    };
    // In the passes' order, `v` itself among them.
    let like: Vec<(&Pass, &Verdict)> = (per_pass.iter())
        .filter(|(q, _)| alike(q))
        .filter_map(|(q, vs)| {
            let w = vs
                .iter()
                .find(|w| w.item.id == v.item.id && w.side == v.side)?;
            let same_scale = w.unit == v.unit && w.threshold == v.threshold;
            (w.status != Status::NotAssessable && same_scale).then_some((*q, w))
        })
        .collect();
    let verdicts: Vec<&Verdict> = like.iter().map(|(_, w)| *w).collect();
    let pooled = gait_checklist::pooled(&verdicts)?;
    let labels: Vec<String> = like.iter().map(|(q, _)| q.label()).collect();
    Some((pooled, format!("{}, cycles pooled", labels.join(" + "))))
}

/// How well a pass judges the paired item `id`: on both sides, from the `preferred` side's
/// view, then on the fewer cycles of its two sides.
fn both_sides_rank(
    p: &Pass,
    vs: &[Verdict],
    id: &str,
    preferred: gait_checklist::Side,
) -> (bool, bool, usize) {
    let mine = vs.iter().filter(|v| v.item.id == id);
    let judged = mine
        .clone()
        .filter(|v| v.status != Status::NotAssessable)
        .count();
    let frontal = mine.clone().any(|v| v.item.view != "side");
    let fewer = p.cycles("left", frontal).min(p.cycles("right", frontal));
    (judged == 2, p.near_camera(preferred.name()), fewer)
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use gait_checklist::{ChecklistConfig, Item, Param, Side};
    use gait_eval::plot::CycleCurve;

    use super::*;

    const STEP_LENGTH: Item = Item {
        id: "uneven_step_length",
        name: "Uneven step length",
        measure: "",
        unit: "px",
        view: "side",
        amputation: "both",
        paired: true,
    };

    fn pass(view: &str, left: usize, right: usize) -> Pass {
        let curve = |side: &str, n| CycleCurve {
            side: side.parse().unwrap(),
            joint: "knee".into(),
            percent: vec![0.0],
            mean: vec![0.0],
            sd: vec![0.0],
            n_cycles: n,
        };
        Pass::with_curves(
            view,
            &format!("{view}.mp4"),
            vec![curve("left", left), curve("right", right)],
        )
    }

    /// (side, status, source) of each verdict.
    fn verdicts(got: &[(Verdict, String)]) -> Vec<(Side, Status, &str)> {
        got.iter()
            .map(|(v, from)| (v.side, v.status, from.as_str()))
            .collect()
    }

    /// A pass's step-length verdicts: `present` names the side that pass finds longer.
    fn step_length(present: Side, value: f64) -> Vec<Verdict> {
        Side::BOTH
            .map(|side| {
                let mut v = Verdict::not_assessable(STEP_LENGTH, side, "");
                v.status = if side == present {
                    Status::Present
                } else {
                    Status::Absent
                };
                v.value = value;
                v
            })
            .to_vec()
    }

    /// Two side views that disagree on which step is longer (the sample and its mirror, each
    /// finding the far limb's step longer): the visit once took each side from its own view and
    /// so dropped both findings; both sides now come from one pass, the prosthetic side's view.
    #[test]
    fn a_paired_item_takes_both_sides_from_one_pass() {
        let (left, right) = (pass("left", 2, 3), pass("right", 3, 3));
        let per_pass = vec![
            (&left, step_length(Side::Right, 1.0)),
            (&right, step_length(Side::Left, 2.0)),
        ];
        let got = checklist(&per_pass, (&[], ""), Side::Right);
        let status = verdicts(&got);
        assert_eq!(
            status,
            [
                (
                    Side::Left,
                    Status::Present,
                    "right view (right.mp4), both sides"
                ),
                (
                    Side::Right,
                    Status::Absent,
                    "right view (right.mp4), both sides"
                ),
            ]
        );
    }

    const WHIP: Item = Item {
        id: "medial_lateral_whip",
        name: "Medial or lateral whip",
        measure: "",
        unit: "% leg",
        view: "back",
        amputation: "both",
        paired: false,
    };

    /// A pass's right whip from one stride of `signed` % leg (judged on its size, 5 % leg).
    fn whip(signed: f64) -> Vec<Verdict> {
        let mut v = Verdict::not_assessable(WHIP, Side::Right, "");
        v.status = if signed.abs() > 5.0 {
            Status::Present
        } else {
            Status::Absent
        };
        (v.value, v.judged, v.n, v.threshold) = (signed, Some(signed.abs()), 1, 5.0);
        vec![v]
    }

    /// Three passes from behind, one stride each: the one whose stride read past the threshold
    /// no longer decides alone; the strides are judged together (a side view cannot judge it).
    #[test]
    fn the_passes_of_one_view_pool_their_strides() {
        let back = [1, 2, 3].map(|k| {
            let mut p = pass("posterior", 1, 1);
            p.video = PathBuf::from(format!("back{k}.mp4"));
            p
        });
        let side = pass("left", 2, 2);
        let per_pass = vec![
            (&back[0], whip(6.5)),
            (&back[1], whip(-2.0)),
            (&back[2], whip(3.0)),
            (
                &side,
                vec![Verdict::not_assessable(
                    WHIP,
                    Side::Right,
                    "needs a back view",
                )],
            ),
        ];
        let got = checklist(&per_pass, (&[], ""), Side::Right);
        let (v, from) = &got[0];
        assert_eq!(v.status, Status::Absent, "{v:?}");
        assert_eq!(v.n, 3);
        assert!((v.value - 2.5).abs() < 1e-12, "{v:?}");
        assert!((v.judged.unwrap() - 11.5 / 3.0).abs() < 1e-12, "{v:?}");
        assert_eq!(
            from,
            "posterior view (back1.mp4) + posterior view (back2.mp4) + posterior view (back3.mp4), cycles pooled"
        );
        // A whip in every stride is found, with its sign.
        let per_pass = vec![(&back[0], whip(-9.0)), (&back[1], whip(-7.0))];
        let (v, _) = &checklist(&per_pass, (&[], ""), Side::Right)[0];
        assert_eq!((v.status, v.value, v.n), (Status::Present, -8.0, 2));
    }

    /// The timing items are judged on the side views' pooled timing when it judges them.
    #[test]
    fn the_timing_items_come_from_the_pooled_side_views() {
        let param = |side: &str, mean| Param {
            parameter: "step_time".into(),
            side: side.into(),
            mean,
            sd: 0.01,
            n: 4,
            unit: "s".into(),
        };
        let cfg = ChecklistConfig::default();
        let pooled =
            gait_checklist::pooled_timing(vec![param("left", 0.70), param("right", 0.55)], &cfg);
        let step_time = |side| {
            let mut v = pooled
                .iter()
                .find(|v| v.item.id == "uneven_step_time" && v.side == side)
                .unwrap()
                .clone();
            v.status = Status::Absent;
            v
        };
        let (left, right) = (pass("left", 2, 2), pass("right", 2, 2));
        let per_pass = vec![
            (&left, vec![step_time(Side::Left), step_time(Side::Right)]),
            (&right, vec![step_time(Side::Left), step_time(Side::Right)]),
        ];
        let got = checklist(&per_pass, (&pooled, "pooled"), Side::Left);
        let status = verdicts(&got);
        assert_eq!(
            status,
            [
                (Side::Left, Status::Present, "pooled"),
                (Side::Right, Status::Absent, "pooled")
            ]
        );
    }
}
