//! How close each decision came to its threshold (run.json's `kinematics.margins`): a decision
//! taken far from its threshold survives re-encoding and keypoint noise, one taken at the
//! threshold may not. The matrix of tools/robustness measures what tips; these figures tell a
//! reader of one run where to look.

use serde::Serialize;

use crate::config::{KinematicsConfig, Side};
use crate::event::EventKind;
use crate::peaks::GaitPeaks;
use crate::quality::CycleQuality;

/// The stride decision of one foot's events: prominences over the threshold they needed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EventMargin {
    pub side: Side,
    pub event: EventKind,
    /// Prominence (pixels) an excursion needed to count as a stride.
    pub threshold_px: f64,
    /// The least prominent excursion taken, over the threshold (1: on it).
    pub weakest_kept: Option<f64>,
    /// The most prominent excursion left out, over the threshold (below 1).
    pub strongest_dropped: Option<f64>,
}

impl EventMargin {
    pub(crate) fn of(side: Side, event: EventKind, peaks: &GaitPeaks) -> Self {
        let over = |p: f64| p / peaks.threshold;
        Self {
            side,
            event,
            threshold_px: peaks.threshold,
            weakest_kept: peaks
                .kept
                .iter()
                .map(|p| over(p.prominence))
                .reduce(f64::min),
            strongest_dropped: peaks.strongest_dropped.map(over),
        }
    }
}

/// The cycle check that came closest to deciding the other way for one stride.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CycleMargin {
    pub side: Side,
    pub first_frame: usize,
    pub accepted: bool,
    /// The check (a [`crate::quality::Reason`] name).
    pub closest: &'static str,
    /// Its value over its limit, oriented so that above 1 rejects.
    pub ratio: f64,
}

/// Per stride, the check whose value lies nearest its limit (ratio nearest 1).
pub fn cycles(q: &[CycleQuality], kin: &KinematicsConfig) -> Vec<CycleMargin> {
    q.iter()
        .filter_map(|c| {
            let tol = kin.cycle_segment_tolerance;
            let segment = (c.thigh_ratio - 1.0).abs().max((c.shank_ratio - 1.0).abs());
            let frames = (c.last_frame - c.first_frame + 1) as f64;
            let checks = [
                (
                    "stride_time",
                    c.stride_deviation / kin.cycle_max_stride_deviation,
                ),
                ("filled_gap", c.max_filled_s / kin.cycle_max_filled_s),
                (
                    "low_likelihood",
                    kin.cycle_min_likelihood / c.mean_likelihood,
                ),
                ("segment_length", segment / tol),
                (
                    "swap",
                    c.unsure_frames as f64 / (kin.cycle_max_swapped_share * frames),
                ),
                ("small_subject", kin.cycle_min_leg_px / c.leg_px),
                ("blurred", c.blur_px / (kin.cycle_max_blur_share * c.leg_px)),
                (
                    "motion_blurred",
                    kin.cycle_min_swing_contrast / c.swing_contrast,
                ),
            ];
            checks
                .into_iter()
                .filter(|(_, r)| r.is_finite() && *r > 0.0)
                .min_by(|a, b| (a.1.ln().abs()).total_cmp(&b.1.ln().abs()))
                .map(|(closest, ratio)| CycleMargin {
                    side: c.side,
                    first_frame: c.first_frame,
                    accepted: c.accepted,
                    closest,
                    ratio,
                })
        })
        .collect()
}

/// What run.json reports.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Margins {
    pub events: Vec<EventMargin>,
    pub cycles: Vec<CycleMargin>,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stride 19 % off the median stride time (limit 20 %) is named as nearly rejected for
    /// it, whatever the other checks say from afar.
    #[test]
    fn the_check_nearest_its_limit_is_named() {
        let kin = KinematicsConfig::default();
        let q = CycleQuality {
            side: Side::Left,
            first_frame: 10,
            last_frame: 46,
            accepted: true,
            reasons: Vec::new(),
            stride_s: 1.2,
            stride_deviation: 0.19,
            max_filled_s: 0.0,
            mean_likelihood: 0.99,
            thigh_ratio: 1.02,
            shank_ratio: 0.97,
            leg_px: 190.0,
            swapped_frames: 0,
            unsure_frames: 0,
            blur_px: f64::NAN,
            swing_contrast: f64::NAN,
            bout: Some(0),
            at: None,
        };
        let m = cycles(&[q], &kin);
        assert_eq!(m.len(), 1);
        assert_eq!(m[0].closest, "stride_time");
        assert!((m[0].ratio - 0.95).abs() < 1e-9, "{}", m[0].ratio);
    }
}
