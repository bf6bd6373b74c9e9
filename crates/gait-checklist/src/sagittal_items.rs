//! The items a side view shows: uneven step time, stance time and step length (from
//! spatiotemporal.csv), and the knee in stance (from cycles_all.csv against the norm).

use gait_eval::normative::Normative;

use crate::judge::{Sample, Threshold, judge};
use crate::run_files::{Param, RunFiles};
use crate::verdict::{Item, Status, Verdict};
use crate::{ChecklistConfig, Side};

pub const STEP_TIME: Item = Item {
    id: "uneven_step_time",
    name: "Uneven step timing",
    measure: "step time of the side (the other foot's heel strike to this one's); present on the longer side when the symmetry index 100 (a - b) / mean(a, b) passes the threshold",
    unit: "s",
    view: "side",
    amputation: "both",
    paired: true,
};
pub const STANCE: Item = Item {
    id: "uneven_stance_time",
    name: "Uneven stance time",
    measure: "stance (% of the stride); judged by (swing / stance) over the other side's, present on the side with the shorter stance",
    unit: "%",
    view: "side",
    amputation: "both",
    paired: true,
};
pub const STEP_LENGTH: Item = Item {
    id: "uneven_step_length",
    name: "Uneven step length",
    measure: "step length of the side; present on the longer side when the symmetry index passes the threshold",
    unit: "",
    view: "side",
    amputation: "both",
    paired: true,
};
pub const KNEE_FLEXION: Item = Item {
    id: "excessive_knee_flexion_stance",
    name: "Excessive knee flexion in stance",
    measure: "largest knee flexion in 0-40 % of the cycle (loading response and mid-stance)",
    unit: "deg",
    view: "side",
    amputation: "transtibial",
    paired: false,
};
pub const KNEE_EXTENSION: Item = Item {
    id: "knee_hyperextension_stance",
    name: "Knee hyperextension in stance",
    measure: "smallest knee flexion in 10-50 % of the cycle (mid-stance)",
    unit: "deg",
    view: "side",
    amputation: "transtibial",
    paired: false,
};

pub const FOOT_SLAP: Item = Item {
    id: "foot_slap",
    name: "Foot slap",
    measure: "largest ankle plantarflexion in 0-15 % of the cycle (loading response)",
    unit: "deg",
    view: "side",
    amputation: "both",
    paired: false,
};
pub const TERMINAL_IMPACT: Item = Item {
    id: "terminal_swing_impact",
    name: "Terminal swing impact",
    measure: "fastest knee extension in 80-100 % of the cycle (deg per 1 %), over the other side's",
    unit: "deg/%",
    view: "side",
    amputation: "transfemoral",
    paired: true,
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
        let source = format!("checklist.symmetry_pct, on the symmetry index (here {si:.1} %)");
        let present = larger && si.abs() > cfg.symmetry_pct;
        of_param(item, side, own, present, (cfg.symmetry_pct, "%"), source)
    })
}

/// A side's verdict on a spatiotemporal row judged against `threshold` (value, unit).
fn of_param(
    item: Item,
    side: Side,
    own: &Param,
    present: bool,
    threshold: (f64, &str),
    source: String,
) -> Verdict {
    let mut v = Verdict::not_assessable(item, side, "");
    v.status = if present {
        Status::Present
    } else {
        Status::Absent
    };
    (v.value, v.spread, v.n) = (own.mean, own.sd, own.n);
    v.unit = own.unit.clone();
    (v.threshold, v.threshold_unit) = (threshold.0, threshold.1.into());
    v.source = source;
    v.reason.clear();
    v
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
        let source = format!(
            "checklist.temporal_ratio (Patterson et al. 2008: 0.9-1.1 healthy), on the swing:stance ratio (here {ratio:.3})"
        );
        let present = ratio > cfg.temporal_ratio;
        let threshold = (cfg.temporal_ratio, "swing:stance ratio");
        of_param(STANCE, side, own, present, threshold, source)
    })
}

/// Per accepted cycle of `side`, the knee's extreme over `range` (% of the cycle).
fn knee(
    run: &RunFiles,
    side: Side,
    range: std::ops::RangeInclusive<usize>,
    largest: bool,
) -> Vec<Sample> {
    extreme(run, side, "knee", range, largest)
}

/// Per accepted cycle of `side`, `joint`'s extreme over `range` (% of the cycle).
fn extreme(
    run: &RunFiles,
    side: Side,
    joint: &str,
    range: std::ops::RangeInclusive<usize>,
    largest: bool,
) -> Vec<Sample> {
    run.sagittal
        .iter()
        .filter(|((s, j, _), _)| *s == side && j == joint)
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

/// Uneven step time and uneven stance time judged once on `params`, spatiotemporal rows of
/// several side-view runs pooled (a visit's), so both sides rest on the same comparison.
pub fn pooled_timing(params: Vec<Param>, cfg: &ChecklistConfig) -> Vec<Verdict> {
    let run = RunFiles {
        view: "sagittal".into(),
        spatiotemporal: params,
        ..RunFiles::default()
    };
    let mut out = symmetry(&run, STEP_TIME, "step_time", cfg).to_vec();
    out.extend(stance_ratio(&run, cfg));
    out
}

/// The five side-view items for both sides.
pub fn assess(run: &RunFiles, cfg: &ChecklistConfig, norm: Option<&Normative>) -> Vec<Verdict> {
    let all = [
        STEP_TIME,
        STANCE,
        STEP_LENGTH,
        KNEE_FLEXION,
        KNEE_EXTENSION,
        FOOT_SLAP,
        TERMINAL_IMPACT,
    ];
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
    out.extend(foot_slap(run, norm, k));
    out.extend(terminal_impact(run, cfg));
    out
}

/// Foot slap: the ankle's most plantarflexed point in loading response against the normative
/// ankle's mean - k SD there, less the MDC95 of the ankle's peak plantarflexion on video: the
/// pose model's foot points move that peak by 7-11 deg between encodings of one walk, and the
/// sample's healthy walker has one such cycle (-27 deg).
fn foot_slap(run: &RunFiles, norm: Option<&Normative>, k: f64) -> [Verdict; 2] {
    let curve = norm.and_then(|n| n.curve("ankle"));
    let noise = gait_eval::reliability::angle_mdc("ankle", "peak extension").unwrap_or(0.0);
    let limit = curve.map(|c| {
        (0..=15)
            .map(|p| c.mean[p] - k * c.sd[p])
            .fold(f64::MAX, f64::min)
            - noise
    });
    Side::BOTH.map(|side| {
        let t = Threshold {
            value: limit.unwrap_or(f64::NAN),
            beyond: "below",
            source: format!(
                "the normative ankle, mean - {k} SD in 0-15 %, less its video MDC95 ({noise:.1} deg)"
            ),
        };
        let why = if curve.is_some() {
            "no accepted cycle of this side"
        } else {
            "no normative band (report.normative = \"none\")"
        };
        judge(FOOT_SLAP, side, &extreme(run, side, "ankle", 0..=15, false), t, "deg", why)
    })
}

/// Per accepted cycle of `side`, the knee's fastest extension over 80-100 % (degrees per 1 %).
fn extension_speed(run: &RunFiles, side: Side) -> Vec<Sample> {
    run.sagittal
        .iter()
        .filter(|((s, j, _), _)| *s == side && j == "knee")
        .filter_map(|((_, _, first), c)| {
            let stride = run.strides_of(side).find(|s| s.first == *first)?;
            let (p, v) = (81..=100)
                .map(|p| (p, c[p - 1] - c[p]))
                .filter(|(_, v)| v.is_finite())
                .max_by(|a, b| a.1.total_cmp(&b.1))?;
            Some(Sample {
                value: v,
                first: stride.first,
                frame: stride.first + ((stride.last - stride.first) * p) / 100,
            })
        })
        .collect()
}

/// Terminal swing impact: each side's fastest terminal knee extension over the other side's
/// mean; one-sided, as a prosthetic knee swinging into its stop is.
fn terminal_impact(run: &RunFiles, cfg: &ChecklistConfig) -> [Verdict; 2] {
    let both = Side::BOTH.map(|s| extension_speed(run, s));
    let mean = |v: &[Sample]| v.iter().map(|s| s.value).sum::<f64>() / v.len() as f64;
    Side::BOTH.map(|side| {
        let (own, other) = match side {
            Side::Left => (&both[0], &both[1]),
            Side::Right => (&both[1], &both[0]),
        };
        let base = mean(other);
        if other.is_empty() || base <= 0.0 {
            let why = "needs accepted cycles of both sides";
            return Verdict::not_assessable(TERMINAL_IMPACT, side, why);
        }
        let t = Threshold {
            value: cfg.impact_ratio,
            beyond: "above",
            source:
                "checklist.impact_ratio: no published value (healthy walks 0.8-1.3, BENCHMARKS.md)"
                    .into(),
        };
        let ratios: Vec<Sample> = own
            .iter()
            .map(|s| Sample {
                value: s.value / base,
                ..*s
            })
            .collect();
        let mut v = judge(
            TERMINAL_IMPACT,
            side,
            &ratios,
            t,
            "x",
            "no accepted cycle of this side",
        );
        v.threshold_unit = "x the other side's".into();
        v
    })
}
