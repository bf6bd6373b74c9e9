//! The items a side view shows: uneven step time, stance time and step length (from
//! spatiotemporal.csv), and the knee in stance (from cycles_all.csv against the norm).

use gait_eval::normative::Normative;

use crate::judge::{Sample, Threshold, judge};
use crate::run_files::RunFiles;
use crate::verdict::{Item, Status, Verdict};
use crate::{ChecklistConfig, Side};

pub const STEP_TIME: Item = Item {
    id: "uneven_step_time",
    name: "Uneven step timing",
    measure: "step time of the side (the other foot's heel strike to this one's); present on the longer side when the symmetry index 100 (a - b) / mean(a, b) passes the threshold",
    unit: "s",
    view: "side",
    amputation: "both",
};
pub const STANCE: Item = Item {
    id: "uneven_stance_time",
    name: "Uneven stance time",
    measure: "stance (% of the stride); judged by the temporal symmetry ratio (swing / stance of the side) / (swing / stance of the other side): present on the side with the shorter stance when the ratio passes the threshold",
    unit: "%",
    view: "side",
    amputation: "both",
};
pub const STEP_LENGTH: Item = Item {
    id: "uneven_step_length",
    name: "Uneven step length",
    measure: "step length of the side; present on the longer side when the symmetry index passes the threshold",
    unit: "",
    view: "side",
    amputation: "both",
};
pub const KNEE_FLEXION: Item = Item {
    id: "excessive_knee_flexion_stance",
    name: "Excessive knee flexion in stance",
    measure: "largest knee flexion in 0-40 % of the cycle (loading response and mid-stance)",
    unit: "deg",
    view: "side",
    amputation: "transtibial",
};
pub const KNEE_EXTENSION: Item = Item {
    id: "knee_hyperextension_stance",
    name: "Knee hyperextension in stance",
    measure: "smallest knee flexion in 10-50 % of the cycle (mid-stance)",
    unit: "deg",
    view: "side",
    amputation: "transtibial",
};

/// The symmetry items: each side's mean, present on the larger side when the symmetry index
/// passes `checklist.symmetry_pct`.
fn symmetry(run: &RunFiles, item: Item, parameter: &str, cfg: &ChecklistConfig) -> [Verdict; 2] {
    let row = |s: Side| {
        run.param(parameter, s.name())
            .filter(|p| p.mean.is_finite())
    };
    let (Some(l), Some(r)) = (row(Side::Left), row(Side::Right)) else {
        let why = "needs accepted steps of both sides";
        return Side::BOTH.map(|s| Verdict::not_assessable(item, s, why));
    };
    let si = 100.0 * (l.mean - r.mean) / (0.5 * (l.mean + r.mean));
    Side::BOTH.map(|side| {
        let (own, larger) = match side {
            Side::Left => (l, si > 0.0),
            Side::Right => (r, si < 0.0),
        };
        let mut v = Verdict::not_assessable(item, side, "");
        v.status = if larger && si.abs() > cfg.symmetry_pct {
            Status::Present
        } else {
            Status::Absent
        };
        v.value = own.mean;
        v.spread = own.sd;
        v.n = own.n;
        v.unit = own.unit.clone();
        v.threshold = cfg.symmetry_pct;
        v.threshold_unit = "%".into();
        v.source = format!("checklist.symmetry_pct, on the symmetry index (here {si:.1} %)");
        v.reason.clear();
        v
    })
}

/// Uneven stance time: Patterson et al.'s temporal symmetry ratio, the side's swing:stance over
/// the other side's. It is judged instead of a symmetry index of stance itself because a shorter
/// stance lengthens the same side's swing: the ratio sees both, so a stance 10 % shorter passes
/// 1.1 where the stance's own index stays near 5 % (tools/visit, BENCHMARKS.md).
fn stance_ratio(run: &RunFiles, cfg: &ChecklistConfig) -> [Verdict; 2] {
    let row = |s: Side| {
        run.param("stance", s.name())
            .filter(|p| p.mean.is_finite() && p.mean > 0.0 && p.mean < 100.0)
    };
    let (Some(l), Some(r)) = (row(Side::Left), row(Side::Right)) else {
        let why = "needs accepted cycles of both sides";
        return Side::BOTH.map(|s| Verdict::not_assessable(STANCE, s, why));
    };
    let swing_over_stance = |stance: f64| (100.0 - stance) / stance;
    let (wl, wr) = (swing_over_stance(l.mean), swing_over_stance(r.mean));
    Side::BOTH.map(|side| {
        let (own, ratio) = match side {
            Side::Left => (l, wl / wr),
            Side::Right => (r, wr / wl),
        };
        let mut v = Verdict::not_assessable(STANCE, side, "");
        v.status = if ratio > cfg.temporal_ratio {
            Status::Present
        } else {
            Status::Absent
        };
        v.value = own.mean;
        v.spread = own.sd;
        v.n = own.n;
        v.unit = own.unit.clone();
        v.threshold = cfg.temporal_ratio;
        v.threshold_unit = "swing:stance ratio".into();
        v.source = format!(
            "checklist.temporal_ratio (Patterson et al. 2008: 0.9-1.1 in 24 healthy adults), on the swing:stance ratio over the other side's (here {ratio:.3})"
        );
        v.reason.clear();
        v
    })
}

/// Per accepted cycle of `side`, the knee's extreme over `range` (% of the cycle).
fn knee(
    run: &RunFiles,
    side: Side,
    range: std::ops::RangeInclusive<usize>,
    largest: bool,
) -> Vec<Sample> {
    run.sagittal
        .iter()
        .filter(|((s, joint, _), _)| *s == side && joint == "knee")
        .filter_map(|((_, _, first), curve)| {
            let stride = run.strides_of(side).find(|s| s.first == *first)?;
            let pick = range.clone().filter(|&p| curve[p].is_finite());
            let p = if largest {
                pick.max_by(|&a, &b| curve[a].total_cmp(&curve[b]))
            } else {
                pick.min_by(|&a, &b| curve[a].total_cmp(&curve[b]))
            }?;
            let frame = stride.first + ((stride.last - stride.first) * p) / 100;
            Some(Sample {
                value: curve[p],
                first: stride.first,
                frame,
            })
        })
        .collect()
}

/// The five side-view items for both sides.
pub fn assess(run: &RunFiles, cfg: &ChecklistConfig, norm: Option<&Normative>) -> Vec<Verdict> {
    let all = [STEP_TIME, STANCE, STEP_LENGTH, KNEE_FLEXION, KNEE_EXTENSION];
    if run.view != "sagittal" {
        return Side::BOTH
            .iter()
            .flat_map(|&s| all.map(|i| Verdict::not_assessable(i, s, "needs a side view")))
            .collect();
    }
    let mut out = Vec::new();
    out.extend(symmetry(run, STEP_TIME, "step_time", cfg));
    out.extend(stance_ratio(run, cfg));
    out.extend(symmetry(run, STEP_LENGTH, "step_length", cfg));
    let curve = norm.and_then(|n| n.curve("knee"));
    let k = cfg.norm_sd;
    for side in Side::BOTH {
        let few = "no accepted cycle of this side";
        let no_norm = "no normative band (report.normative = \"none\")";
        let flex = curve.map(|c| {
            (0..=40)
                .map(|p| c.mean[p] + k * c.sd[p])
                .fold(f64::MIN, f64::max)
        });
        let t = Threshold {
            value: flex.unwrap_or(f64::NAN),
            beyond: "above",
            source: format!("the normative knee flexion, mean + {k} SD, its largest in 0-40 %"),
        };
        out.push(judge(
            KNEE_FLEXION,
            side,
            &knee(run, side, 0..=40, true),
            t,
            "deg",
            if curve.is_some() { few } else { no_norm },
        ));
        let ext = curve.map(|c| {
            (10..=50)
                .map(|p| c.mean[p] - k * c.sd[p])
                .fold(f64::MAX, f64::min)
        });
        let t = Threshold {
            value: ext.unwrap_or(f64::NAN),
            beyond: "below",
            source: format!("the normative knee flexion, mean - {k} SD, its smallest in 10-50 %"),
        };
        out.push(judge(
            KNEE_EXTENSION,
            side,
            &knee(run, side, 10..=50, false),
            t,
            "deg",
            if curve.is_some() { few } else { no_norm },
        ));
    }
    out
}
