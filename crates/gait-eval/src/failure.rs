//! Failure modes of the paper (Fig. 2, Supplementary Table 1), counted per frame.
//!
//! Over the aligned frames in which the ground truth has at least one
//! lower-limb keypoint (hip, knee, ankle, heel, toe of either side) and with
//! `L` = the reference length ([`EvalOptions::reference_length_px`], by default
//! the median ground-truth hip-knee distance), each frame falls in at most one
//! category, checked in this order:
//! 1. **not identified**: a lower-limb keypoint the truth has is missing from
//!    the prediction (or below `min_likelihood`);
//! 2. **swapped**: over the left/right pairs of a part that the truth has on
//!    both sides, the cross-side error sum `|pL-tR| + |pR-tL|` is smaller than
//!    the same-side sum `|pL-tL| + |pR-tR|` by more than `swap_fraction * L`
//!    per pair;
//! 3. **misidentified**: a lower-limb keypoint's error exceeds `misid_fraction * L`.
//!
//! Percentages are of the evaluated frames. Per side, "not identified" and
//! "misidentified" are also counted with the same rules applied to one leg's
//! keypoints (a side is misidentified only in frames that are not swapped).

use serde::{Deserialize, Serialize};

use crate::EvalError;
use crate::align::Aligned;
use crate::keypoint_error::{distance, identified};
use crate::names::{LEG_PARTS, Side, leg_name};
use crate::options::{EvalOptions, Role};
use crate::stats::median;

/// Frame counts and percentages of one failure mode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Count {
    pub frames: usize,
    pub percent: f64,
}

/// Failure modes of one leg.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SideFailures {
    pub side: Side,
    pub role: Role,
    pub not_identified: Count,
    pub misidentified: Count,
}

/// Failure-mode counts over a sequence, with the thresholds used and the frames affected.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Failures {
    /// Frames evaluated (the denominator of the percentages).
    pub frames: usize,
    pub not_identified: Count,
    pub swapped: Count,
    pub misidentified: Count,
    /// Frames with any of the three.
    pub any: Count,
    pub by_side: Vec<SideFailures>,
    pub reference_length_px: f64,
    pub misid_threshold_px: f64,
    pub swap_margin_px: f64,
    pub not_identified_frames: Vec<usize>,
    pub swapped_frames: Vec<usize>,
    pub misidentified_frames: Vec<usize>,
}

/// Column of `side`'s `part` in the aligned names.
fn col(a: &Aligned, side: Side, part: &str) -> Option<usize> {
    let name = leg_name(side, part);
    a.names.iter().position(|n| *n == name)
}

/// The reference length: the option, or the median truth thigh length.
fn reference_length(a: &Aligned, opts: &EvalOptions) -> Result<f64, EvalError> {
    if let Some(l) = opts.reference_length_px {
        return Ok(l);
    }
    let mut per_frame = Vec::new();
    for t in &a.truth {
        let thighs: Vec<f64> = Side::BOTH
            .iter()
            .filter_map(|&s| {
                let (h, k) = (col(a, s, "hip")?, col(a, s, "knee")?);
                (t[h].is_found() && t[k].is_found()).then(|| distance(&t[h], &t[k]))
            })
            .collect();
        if !thighs.is_empty() {
            per_frame.push(thighs.iter().sum::<f64>() / thighs.len() as f64);
        }
    }
    match median(&mut per_frame) {
        Some(l) if l > 0.0 => Ok(l),
        _ => Err(EvalError::Option {
            key: "reference_length_px",
            reason: "the ground truth has no hip and knee in any frame to measure a thigh; give a length in pixels".into(),
        }),
    }
}

fn count(frames: usize, total: usize) -> Count {
    Count {
        frames,
        percent: if total == 0 {
            0.0
        } else {
            100.0 * frames as f64 / total as f64
        },
    }
}

pub(crate) fn failures(a: &Aligned, opts: &EvalOptions) -> Result<Failures, EvalError> {
    let l = reference_length(a, opts)?;
    let misid = opts.misid_fraction * l;
    let margin = opts.swap_fraction * l;
    let legs: Vec<(Side, Vec<usize>)> = Side::BOTH
        .iter()
        .map(|&s| (s, LEG_PARTS.iter().filter_map(|p| col(a, s, p)).collect()))
        .collect();
    let pairs: Vec<(usize, usize)> = LEG_PARTS
        .iter()
        .filter_map(|p| Some((col(a, Side::Left, p)?, col(a, Side::Right, p)?)))
        .collect();
    let (mut total, mut ni, mut sw, mut mi, mut any) = (0, Vec::new(), Vec::new(), Vec::new(), 0);
    let mut side_ni = [0usize; 2];
    let mut side_mi = [0usize; 2];
    for ((frame, t), p) in a.frames.iter().zip(&a.truth).zip(&a.pred) {
        let expected = |cols: &Vec<usize>| {
            cols.iter()
                .copied()
                .filter(|&k| t[k].is_found())
                .collect::<Vec<_>>()
        };
        let per_side: Vec<Vec<usize>> = legs.iter().map(|(_, c)| expected(c)).collect();
        if per_side.iter().all(Vec::is_empty) {
            continue;
        }
        total += 1;
        let missing: Vec<bool> = per_side
            .iter()
            .map(|ks| ks.iter().any(|&k| !identified(&p[k], opts.min_likelihood)))
            .collect();
        for (s, &m) in missing.iter().enumerate() {
            side_ni[s] += usize::from(m);
        }
        if missing.iter().any(|&m| m) {
            ni.push(*frame);
            any += 1;
            continue;
        }
        let both: Vec<&(usize, usize)> = pairs
            .iter()
            .filter(|(kl, kr)| t[*kl].is_found() && t[*kr].is_found())
            .collect();
        if !both.is_empty() {
            let same: f64 = both
                .iter()
                .map(|&&(kl, kr)| distance(&p[kl], &t[kl]) + distance(&p[kr], &t[kr]))
                .sum();
            let cross: f64 = both
                .iter()
                .map(|&&(kl, kr)| distance(&p[kl], &t[kr]) + distance(&p[kr], &t[kl]))
                .sum();
            if (same - cross) > margin * both.len() as f64 {
                sw.push(*frame);
                any += 1;
                continue;
            }
        }
        let wrong: Vec<bool> = per_side
            .iter()
            .map(|ks| ks.iter().any(|&k| distance(&p[k], &t[k]) > misid))
            .collect();
        for (s, &w) in wrong.iter().enumerate() {
            side_mi[s] += usize::from(w);
        }
        if wrong.iter().any(|&w| w) {
            mi.push(*frame);
            any += 1;
        }
    }
    Ok(Failures {
        frames: total,
        not_identified: count(ni.len(), total),
        swapped: count(sw.len(), total),
        misidentified: count(mi.len(), total),
        any: count(any, total),
        by_side: legs
            .iter()
            .enumerate()
            .map(|(s, (side, _))| SideFailures {
                side: *side,
                role: opts.role(*side),
                not_identified: count(side_ni[s], total),
                misidentified: count(side_mi[s], total),
            })
            .collect(),
        reference_length_px: l,
        misid_threshold_px: misid,
        swap_margin_px: margin,
        not_identified_frames: ni,
        swapped_frames: sw,
        misidentified_frames: mi,
    })
}
