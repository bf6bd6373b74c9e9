//! The walker's size in the image per frame, in a front or back view. Walking toward or away
//! from the camera the body grows or shrinks by a factor of 2 or more within a few metres, so
//! every length is measured in body sizes of its own frame, never in fixed pixels.

use crate::config::Side;
use crate::tracks::{Tracks, dist, median};
use crate::view::body_size;

/// Per frame, the smoothed body size and the leg length it implies, in pixels.
#[derive(Debug, Clone, Default)]
pub struct Scale {
    /// Mid-hip to mid-shoulder (else hip to ankle), moving median then mean over 0.5 s.
    pub size: Vec<f64>,
    /// Thigh + shank of a straight leg over the body size (see [`leg_per_size`]).
    pub leg_per_size: f64,
}

impl Scale {
    pub fn measure(t: &Tracks) -> Self {
        let raw: Vec<f64> = (0..t.len()).map(|i| body_size(t, i)).collect();
        let half = ((0.25 * t.fps).round() as usize).max(1);
        let size = moving_mean(&moving_median(&raw, half), half);
        let leg_per_size = leg_per_size(t, &size);
        Self { size, leg_per_size }
    }

    /// A leg's length in pixels at timeline frame `i` (NaN where the body is not seen).
    pub fn leg_px(&self, i: usize) -> f64 {
        self.size.get(i).map_or(f64::NAN, |s| s * self.leg_per_size)
    }
}

/// The longer leg's thigh + shank over the body size, at its 90th percentile over the frames:
/// in mid-stance the leg is straight and upright, and a front view then shows its whole
/// length; flexed in swing (or tilted forward at heel strike) it looks shorter.
fn leg_per_size(t: &Tracks, size: &[f64]) -> f64 {
    let mut ratios = Vec::new();
    for (i, &s) in size.iter().enumerate() {
        let longest = Side::BOTH
            .iter()
            .filter_map(|&side| {
                let [h, k, a] = ["hip", "knee", "ankle"].map(|p| t.leg_index(side, p));
                let (h, k, a) = (t.at(h?, i)?, t.at(k?, i)?, t.at(a?, i)?);
                Some(dist(h, k) + dist(k, a))
            })
            .fold(f64::NAN, f64::max);
        if longest.is_finite() && s.is_finite() && s > 0.0 {
            ratios.push(longest / s);
        }
    }
    ratios.sort_by(f64::total_cmp);
    match ratios.len() {
        0 => f64::NAN,
        n => ratios[((n - 1) as f64 * 0.9).round() as usize],
    }
}

/// Median of the finite values within +-`half` samples.
fn moving_median(x: &[f64], half: usize) -> Vec<f64> {
    (0..x.len())
        .map(|i| {
            if !x[i].is_finite() {
                return f64::NAN;
            }
            let lo = i.saturating_sub(half);
            let hi = (i + half + 1).min(x.len());
            median(&mut x[lo..hi].to_vec())
        })
        .collect()
}

/// Mean of the finite values within +-`half` samples (NaN stays NaN).
fn moving_mean(x: &[f64], half: usize) -> Vec<f64> {
    (0..x.len())
        .map(|i| {
            if !x[i].is_finite() {
                return f64::NAN;
            }
            let lo = i.saturating_sub(half);
            let hi = (i + half + 1).min(x.len());
            let v: Vec<f64> = x[lo..hi]
                .iter()
                .copied()
                .filter(|v| v.is_finite())
                .collect();
            v.iter().sum::<f64>() / v.len() as f64
        })
        .collect()
}
