//! The frontal measures over the accepted strides: mean curves, per-cycle scalars with the two
//! sides' difference, step width at each heel strike and circumduction in each stride.

use serde::Serialize;

use crate::config::{KinematicsConfig, Side};
use crate::cycles::{CycleCurve, Stride, mean_sd, resample};
use crate::events::{Event, EventKind};
use crate::frontal::measures::{FrontalAngles, MEASURES};
use crate::frontal::scale::Scale;
use crate::spatiotemporal::LEG_PER_HEIGHT;
use crate::tracks::{Tracks, median};
use crate::view::View;

/// One statistic of one measure and side over the accepted cycles (mean and SD over cycles);
/// side `left_minus_right` (or `prosthetic_minus_intact`) holds the difference of the means.
#[derive(Debug, Clone, Serialize)]
pub struct FrontalScalar {
    pub measure: String,
    pub statistic: &'static str,
    pub side: String,
    pub mean: f64,
    pub sd: f64,
    pub n: usize,
    pub unit: String,
}

/// A length measured at one event or over one stride.
#[derive(Debug, Clone, Serialize)]
pub struct FootLength {
    pub side: Side,
    /// `step_width` or `heel_offset` (at a heel strike), or `circumduction` (over a stride).
    pub measure: &'static str,
    pub first_frame: usize,
    pub last_frame: usize,
    /// In `unit`: cm with a known scale, else leg lengths.
    pub value: f64,
    pub unit: &'static str,
}

/// One accepted stride's cycle of each measure of [`MEASURES`], or why it has none.
pub type StrideCycles = (Stride, [Result<Vec<f64>, &'static str>; 4]);

/// A per-cycle statistic and its name.
type Statistic = (&'static str, fn(&[f64]) -> f64);

/// Per accepted stride and measure: the resampled cycle, or why there is none.
pub fn per_cycle(a: &FrontalAngles, first_frame: usize, accepted: &[Stride]) -> Vec<StrideCycles> {
    accepted
        .iter()
        .map(|s| {
            let series = a.side(s.side);
            let cycles =
                std::array::from_fn(|k| resample(&series[k], first_frame, s).ok_or(MISSING[k]));
            (*s, cycles)
        })
        .collect()
}

/// Why a measure has no value in a cycle: the keypoints it needs were not all seen.
const MISSING: [&str; 4] = [
    "trunk_lean: a shoulder or hip not seen",
    "pelvic_obliquity: a hip not seen",
    "hip_adduction: a hip or the knee not seen",
    "knee_varus: the hip, knee or ankle not seen",
];

/// Mean and SD curves per side and measure over the cycles that have them.
pub fn curves(cycles: &[StrideCycles], min_cycles: usize) -> Vec<CycleCurve> {
    let mut out = Vec::new();
    for side in Side::BOTH {
        for (k, measure) in MEASURES.iter().enumerate() {
            let have: Vec<Vec<f64>> = cycles
                .iter()
                .filter(|(s, _)| s.side == side)
                .filter_map(|(_, c)| c[k].clone().ok())
                .collect();
            if have.len() < min_cycles.max(1) {
                continue;
            }
            let (mean, sd) = mean_sd(&have);
            out.push(CycleCurve {
                side,
                joint: measure,
                mean,
                sd,
                n_cycles: have.len(),
            });
        }
    }
    out
}

/// Peak, trough and range of each measure per cycle, as mean and SD over cycles, per side;
/// then the difference between the sides' means.
pub fn scalars(cycles: &[StrideCycles], prosthetic: Option<Side>) -> Vec<FrontalScalar> {
    let stats: [Statistic; 3] = [
        ("max", |c| {
            c.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        }),
        ("min", |c| c.iter().copied().fold(f64::INFINITY, f64::min)),
        ("range", |c| {
            c.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                - c.iter().copied().fold(f64::INFINITY, f64::min)
        }),
    ];
    let mut out = Vec::new();
    for (k, measure) in MEASURES.iter().enumerate() {
        for (name, f) in stats {
            let mut means = [f64::NAN; 2];
            for (m, side) in means.iter_mut().zip(Side::BOTH) {
                let v: Vec<f64> = cycles
                    .iter()
                    .filter(|(s, _)| s.side == side)
                    .filter_map(|(_, c)| c[k].as_ref().ok().map(|c| f(c)))
                    .collect();
                let (mean, sd) = mean_and_sd(&v);
                *m = mean;
                out.push(row(measure, name, side.name(), mean, sd, v.len()));
            }
            let (a, b, label) = match prosthetic {
                Some(p) => (p, p.other(), "prosthetic_minus_intact"),
                None => (Side::Left, Side::Right, "left_minus_right"),
            };
            let idx = |s: Side| usize::from(s == Side::Right);
            let diff = means[idx(a)] - means[idx(b)];
            out.push(row(
                measure,
                name,
                label,
                diff,
                f64::NAN,
                usize::from(diff.is_finite()),
            ));
        }
    }
    out
}

fn row(
    measure: &str,
    statistic: &'static str,
    side: &str,
    mean: f64,
    sd: f64,
    n: usize,
) -> FrontalScalar {
    FrontalScalar {
        measure: measure.into(),
        statistic,
        side: side.into(),
        mean,
        sd,
        n,
        unit: "deg".into(),
    }
}

/// Mean and sample SD of the finite values.
pub fn mean_and_sd(v: &[f64]) -> (f64, f64) {
    let v: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    let n = v.len() as f64;
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let mean = v.iter().sum::<f64>() / n;
    let sd = if v.len() < 2 {
        f64::NAN
    } else {
        (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
    };
    (mean, sd)
}

/// Leg lengths in cm (from the subject's height) or leg lengths as the unit.
fn unit(kin: &KinematicsConfig) -> (f64, &'static str) {
    match kin.subject_height_m {
        Some(h) => (LEG_PER_HEIGHT * h * 100.0, "cm"),
        None => (1.0, "leg"),
    }
}

/// What the foot measures need besides the keypoints.
pub struct Feet<'a> {
    pub t: &'a Tracks,
    pub view: View,
    pub scale: &'a Scale,
    /// Image x of the camera's axis: the frame's middle, else the pelvis' median x.
    pub axis_x: f64,
}

impl Feet<'_> {
    fn point(&self, side: Side, parts: &[&str], frame: usize) -> Option<(f64, f64)> {
        let i = frame.checked_sub(self.t.first_frame)?;
        let j = parts.iter().find_map(|p| self.t.seen_leg_index(side, p))?;
        self.t.at(j, i)
    }

    /// Lateral position of a point toward `side`, in leg lengths at its frame's scale.
    fn lateral(&self, side: Side, x: f64, frame: usize) -> f64 {
        let leg = self.scale.leg_px(frame - self.t.first_frame);
        self.view.toward(side) * (x - self.axis_x) / leg
    }

    /// `measure` at each heel strike `keep` admits: `px` gives its lateral length in pixels
    /// from the striking side and its heel, scaled here to cm or leg lengths.
    fn at_heel_strikes(
        &self,
        events: &[Event],
        keep: &dyn Fn(usize) -> bool,
        kin: &KinematicsConfig,
        measure: &'static str,
        px: &dyn Fn(Side, (f64, f64), usize) -> Option<f64>,
    ) -> Vec<FootLength> {
        let (per_leg, unit) = unit(kin);
        events
            .iter()
            .filter(|e| e.event == EventKind::HeelStrike && keep(e.frame))
            .filter_map(|e| {
                let heel = self.point(e.side, &["heel", "ankle"], e.frame)?;
                let leg = self.scale.leg_px(e.frame.checked_sub(self.t.first_frame)?);
                let value = px(e.side, heel, e.frame)? / leg * per_leg;
                value.is_finite().then_some(FootLength {
                    side: e.side,
                    measure,
                    first_frame: e.frame,
                    last_frame: e.frame,
                    value,
                    unit,
                })
            })
            .collect()
    }

    /// Step width at each heel strike `keep` admits: the heels' lateral distance.
    pub fn step_widths(
        &self,
        events: &[Event],
        keep: &dyn Fn(usize) -> bool,
        kin: &KinematicsConfig,
    ) -> Vec<FootLength> {
        let other = |side: Side, heel: (f64, f64), frame: usize| {
            let b = self.point(side.other(), &["heel", "ankle"], frame)?;
            Some((heel.0 - b.0).abs())
        };
        self.at_heel_strikes(events, keep, kin, "step_width", &other)
    }

    /// At each heel strike `keep` admits, the striking heel's lateral distance from the
    /// pelvis' midpoint (half the walking base, the side's own share of it: a step width
    /// grows at both feet's heel strikes when one foot is placed wide).
    pub fn heel_offsets(
        &self,
        events: &[Event],
        keep: &dyn Fn(usize) -> bool,
        kin: &KinematicsConfig,
    ) -> Vec<FootLength> {
        let pelvis = |side: Side, heel: (f64, f64), frame: usize| {
            let p = self.t.pelvis(frame.checked_sub(self.t.first_frame)?)?;
            Some(self.view.toward(side) * (heel.0 - p.0))
        };
        self.at_heel_strikes(events, keep, kin, "heel_offset", &pelvis)
    }

    /// Circumduction of each stride: the swing ankle's largest lateral excursion from the
    /// chord joining where the foot stood before and after the swing.
    ///
    /// Both ends are the planted foot's lateral position in the middle of its stance, where it
    /// is beside the pelvis and so at the depth the body's scale is taken at (at the heel
    /// strike itself the foot is 0.3-0.4 m ahead of the pelvis, and a walker off the camera's
    /// axis seems to drift sideways by 10 % of that offset); the chord is followed over the
    /// swing only, from toe-off to heel strike (over the whole stride a standing foot moved
    /// against a chord that had already begun to move). On the projected motion capture of
    /// tests/data/frontal the largest error against the 3-D excursion fell from 3.7 to 1.3 cm.
    pub fn circumduction(
        &self,
        strides: &[Stride],
        events: &[Event],
        kin: &KinematicsConfig,
    ) -> Vec<FootLength> {
        let (per_leg, unit) = unit(kin);
        strides
            .iter()
            .filter_map(|s| {
                let lat = |f: usize| {
                    let p = self.point(s.side, &["ankle"], f)?;
                    Some(self.lateral(s.side, p.0, f))
                };
                let toe_off = |after: usize| {
                    (events.iter())
                        .filter(|e| e.side == s.side && e.event == EventKind::ToeOff)
                        .map(|e| e.frame)
                        .filter(|&f| f > after)
                        .min()
                };
                let stood = |hs: usize| {
                    let mid = toe_off(hs).and_then(|to| {
                        let third = (to - hs) / 3;
                        let mut mid: Vec<f64> = (hs + third..=to - third).filter_map(lat).collect();
                        Some(median(&mut mid)).filter(|m| m.is_finite())
                    });
                    mid.or_else(|| lat(hs))
                };
                let lift = toe_off(s.start).filter(|&to| to < s.end)?;
                let (a, b) = (stood(s.start)?, stood(s.end)?);
                let span = (s.end - lift) as f64;
                let mut most = 0.0f64;
                for f in lift..=s.end {
                    let chord = a + (b - a) * (f - lift) as f64 / span;
                    most = most.max(lat(f)? - chord);
                }
                let v = most * per_leg;
                v.is_finite().then_some(FootLength {
                    side: s.side,
                    measure: "circumduction",
                    first_frame: s.start,
                    last_frame: s.end,
                    value: v,
                    unit,
                })
            })
            .collect()
    }
}
