//! Where a front or back view's heel strikes are placed, from the starts of the heel's still runs
//! ([`super::events`]) and the feet's vertical image distance ([`lead`]).
//!
//! A still run's start is right on average but moved by a pose model's jitter, by 2-3 video
//! frames either way. The distance has features that jitter hardly moves, each at its own lag
//! after the heel strike: walking toward the camera a trough (the landing foot nearest the
//! camera), walking away the steep fall after the landing peak (the other foot leaving the
//! floor). Those lags depend on the walker's double support (0.11-0.24 s on the two trials of
//! tests/data/frontal), so each is calibrated on the walk itself: a heel strike is the feature
//! less the median, over the walk's heel strikes, of the feature's lag after an estimate that
//! is right on average (walking toward: the still run's start; away: the landing peak).

use crate::events::{Event, EventKind};
use crate::frontal::lead;
use crate::tracks::{self, Tracks};
use crate::view::View;

/// Fewest heel strikes whose lags calibrate a feature: with fewer, the estimates stay. Both
/// feet's lags are pooled: per foot (3 each on the Parkinson's walk toward the camera) the
/// median of so few noisy lags moved more heel strikes than it corrected (held in 6 seeds of
/// 10 instead of 9). A walker whose lags differ by d between the legs gets each foot's heel
/// strikes d/2 off, in opposite directions.
const MIN_CALIBRATION: usize = 3;

/// A heel strike without the feature that lies within this share of the walk's stride of one
/// placed from it (same foot) is dropped: on the projected trials under the limbs' jitter
/// (tests/frontal_mocap.rs) 49 of 59 heel strikes without a feature were spurious, most where
/// a shuffling foot's heel rose in terminal stance or the other foot landed (0.4-0.6 of a
/// stride from a real one), and they split a stride into two rejected halves. A real one
/// without its feature lies about a stride from its neighbours. Two heel strikes placed on
/// the same feature (two still runs before one landing) are one: within [`SAME_SHARE`] of a
/// stride; two placed from features further apart both stay, as nothing tells which is right.
const CONFLICT_SHARE: f64 = 0.7;
const SAME_SHARE: f64 = 0.25;

/// The heel strikes of `events` (each on its still run's start) placed for `view`; those that
/// conflict with better-placed ones ([`CONFLICT_SHARE`]) dropped. Strides shorter than
/// `min_stride_s` are not strides.
pub fn place(t: &Tracks, view: View, min_stride_s: f64, events: &mut Vec<Event>) {
    let frames = |s: f64| (s * t.fps).round() as usize;
    let (before, after) = match view {
        View::Anterior => (lead::TROUGH_SEARCH_BEFORE_S, lead::TROUGH_SEARCH_AFTER_S),
        View::Posterior => (lead::SEARCH_BEFORE_S, lead::SEARCH_AFTER_S),
        _ => return,
    };
    // (event index, estimate right on average, jitter-robust feature), in track frames.
    let mut found: Vec<(usize, f64, Option<f64>)> = Vec::new();
    for (k, e) in events.iter().enumerate() {
        if e.event != EventKind::HeelStrike {
            continue;
        }
        let start = e.frame - t.first_frame;
        let (lo, hi) = (start.saturating_sub(frames(before)), start + frames(after));
        match view {
            View::Anterior => found.push((k, start as f64, lead::trough_near(t, e.side, lo, hi))),
            _ => {
                if let Some(landing) = lead::landing_near(t, e.side, lo, hi) {
                    found.push((k, landing.peak, landing.fall));
                }
            }
        }
    }
    let mut lags: Vec<f64> = found
        .iter()
        .filter_map(|&(_, estimate, feature)| Some(feature? - estimate))
        .collect();
    let lag = (lags.len() >= MIN_CALIBRATION).then(|| tracks::median(&mut lags));
    let mut supported = vec![false; events.len()];
    for (k, estimate, feature) in found {
        let at = match (feature, lag) {
            (Some(feature), Some(lag)) => {
                supported[k] = true;
                feature - lag
            }
            _ => estimate,
        };
        let at = t.first_frame as f64 + at.max(0.0);
        events[k] = Event::between_frames(events[k].side, EventKind::HeelStrike, at);
    }
    if let Some(stride) = walk_stride(events, &supported, min_stride_s * t.fps) {
        drop_conflicting(events, &supported, stride);
    }
}

/// The median interval (frames) between consecutive heel strikes of one foot placed from a
/// feature, both feet pooled, of those at least `shortest` long; `None` without any.
fn walk_stride(events: &[Event], supported: &[bool], shortest: f64) -> Option<f64> {
    let mut gaps = Vec::new();
    for side in crate::config::Side::BOTH {
        let mut times: Vec<f64> = events
            .iter()
            .zip(supported)
            .filter(|(e, s)| **s && e.side == side && e.event == EventKind::HeelStrike)
            .map(|(e, _)| e.time())
            .collect();
        times.sort_by(f64::total_cmp);
        gaps.extend(
            times
                .windows(2)
                .map(|w| w[1] - w[0])
                .filter(|&g| g >= shortest),
        );
    }
    (!gaps.is_empty()).then(|| tracks::median(&mut gaps))
}

/// Drops each heel strike of a foot that conflicts with a supported one of the same foot, given
/// the walk's `stride` (frames): an unsupported one within [`CONFLICT_SHARE`] of it, a later
/// supported one within [`SAME_SHARE`].
fn drop_conflicting(events: &mut Vec<Event>, supported: &[bool], stride: f64) {
    let conflicts = |k: usize| {
        let e = &events[k];
        let share = if supported[k] {
            SAME_SHARE
        } else {
            CONFLICT_SHARE
        };
        let within = share * stride;
        e.event == EventKind::HeelStrike
            && (0..events.len()).any(|j| {
                let o = &events[j];
                j != k
                    && supported[j]
                    && o.side == e.side
                    && o.event == EventKind::HeelStrike
                    && (o.time() - e.time()).abs() < within
                    && (!supported[k] || (o.time(), j) < (e.time(), k))
            })
    };
    let keep: Vec<bool> = (0..events.len()).map(|k| !conflicts(k)).collect();
    let mut k = 0;
    events.retain(|_| {
        k += 1;
        keep[k - 1]
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Side;

    /// 30 fps, a stride of 30 frames: the left ankle's image y is 600 + 20 cos, the right's
    /// 600 - 20 cos, so the left foot's vertical distance (the right's y minus the left's) has
    /// its troughs at 0, 30, 60, ... and its peaks half a stride later.
    fn feet() -> Tracks {
        let n = 160;
        let wave = |i: usize| 20.0 * (2.0 * std::f64::consts::PI * i as f64 / 30.0).cos();
        Tracks {
            fps: 30.0,
            first_frame: 0,
            names: vec!["left_ankle".into(), "right_ankle".into()],
            x: vec![vec![500.0; n], vec![520.0; n]],
            y: vec![
                (0..n).map(|i| 600.0 + wave(i)).collect(),
                (0..n).map(|i| 600.0 - wave(i)).collect(),
            ],
            likelihood: vec![vec![1.0; n]; 2],
        }
    }

    fn heel_strikes(frames: &[usize]) -> Vec<Event> {
        frames
            .iter()
            .map(|&f| Event::on_frame(Side::Left, EventKind::HeelStrike, f))
            .collect()
    }

    fn placed_at(events: &[Event]) -> Vec<f64> {
        events
            .iter()
            .map(|e| e.at.unwrap_or(e.frame as f64))
            .collect()
    }

    /// Walking toward the camera: still-run starts 5 frames before the troughs, give or take
    /// their jitter (+2, -2, 0, +1), all come out at the trough less the median lag (4.5).
    #[test]
    fn the_trough_less_the_walks_lag_removes_the_starts_jitter() {
        let t = feet();
        let mut events = heel_strikes(&[27, 53, 85, 116]);
        place(&t, View::Anterior, 0.5, &mut events);
        for (at, trough) in placed_at(&events).iter().zip([30.0, 60.0, 90.0, 120.0]) {
            assert!(
                (at - (trough - 4.5)).abs() < 0.1,
                "{at} for the trough at {trough}"
            );
        }
    }

    /// Walking away: whatever the starts' jitter, each heel strike is the landing peak (half a
    /// stride after a trough) plus 0.04 s, as the distance's fall follows each peak alike; a
    /// bump before one peak, which moves that peak, does not move its heel strike.
    #[test]
    fn the_fall_less_the_walks_lag_lands_on_the_peak() {
        let mut t = feet();
        for i in 71..=73 {
            t.y[0][i] -= 8.0;
        }
        let bumped = lead::landing_near(&t, Side::Left, 69, 86).unwrap().peak;
        assert!(
            bumped < 74.5,
            "the bump moves the peak 2 frames early: {bumped}"
        );
        let mut events = heel_strikes(&[44, 77, 104, 137]);
        place(&t, View::Posterior, 0.5, &mut events);
        for (at, peak) in placed_at(&events).iter().zip([45.0, 75.0, 105.0, 135.0]) {
            // The bump shifts its fall's halfway level a little: 0.36 frames.
            let tolerance = if peak == 75.0 { 0.5 } else { 0.1 };
            assert!(
                (at - (peak + 1.2)).abs() < tolerance,
                "{at} for the peak at {peak}"
            );
        }
    }

    /// A stride of 30 frames: heel strikes without the feature 15 and 18 frames after placed
    /// ones are spurious; of two placed on one feature the later goes, two placed 12 frames
    /// apart both stay; toe-offs are not touched.
    #[test]
    fn heel_strikes_that_conflict_with_placed_ones_are_dropped() {
        let hs = |side, at| Event::between_frames(side, EventKind::HeelStrike, at);
        let (l, r) = (Side::Left, Side::Right);
        let mut events = vec![
            hs(l, 30.0),
            hs(l, 45.0),
            hs(l, 60.0),
            hs(l, 60.3),
            hs(l, 90.0),
            hs(r, 15.0),
            hs(r, 45.0),
            hs(r, 57.0),
            hs(r, 75.0),
            Event::on_frame(l, EventKind::ToeOff, 50),
        ];
        let supported = [
            true, false, true, true, true, true, true, true, false, false,
        ];
        let stride = walk_stride(&events, &supported, 15.0).unwrap();
        assert_eq!(stride, 30.0);
        drop_conflicting(&mut events, &supported, stride);
        let kept: Vec<f64> = events.iter().map(Event::time).collect();
        assert_eq!(kept, vec![30.0, 60.0, 90.0, 15.0, 45.0, 57.0, 50.0]);
    }

    /// With fewer heel strikes than a calibration needs, walking toward the camera keeps the
    /// still runs' starts; a side view is left alone.
    #[test]
    fn too_few_heel_strikes_keep_their_estimates() {
        let t = feet();
        let mut events = heel_strikes(&[27, 53]);
        place(&t, View::Anterior, 0.5, &mut events);
        assert_eq!(placed_at(&events), vec![27.0, 53.0]);
        let mut side = heel_strikes(&[27, 53, 85, 116]);
        place(&t, View::Sagittal, 0.5, &mut side);
        assert_eq!(placed_at(&side), vec![27.0, 53.0, 85.0, 116.0]);
    }
}
