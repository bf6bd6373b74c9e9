//! The frontal measures over the accepted strides: mean curves and per-cycle scalars with the
//! two sides' difference (the feet's lengths are in [`super::feet`]).

use serde::Serialize;

use crate::config::Side;
use crate::cycles::{CycleCurve, Stride, mean_sd, resample};
use crate::frontal::measures::{FrontalAngles, MEASURES};

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
