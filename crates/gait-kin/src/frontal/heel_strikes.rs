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
use crate::frontal::events::placed;
use crate::frontal::lead;
use crate::tracks::{self, Tracks};
use crate::view::View;

/// Fewest heel strikes whose lags calibrate a feature: with fewer, the estimates stay. Both
/// feet's lags are pooled: per foot (3 each on the Parkinson's walk toward the camera) the
/// median of so few noisy lags moved more heel strikes than it corrected (held in 6 seeds of
/// 10 instead of 9). A walker whose lags differ by d between the legs gets each foot's heel
/// strikes d/2 off, in opposite directions.
const MIN_CALIBRATION: usize = 3;

/// The heel strikes of `events` (each on its still run's start) placed for `view`.
pub fn place(t: &Tracks, view: View, events: &mut [Event]) {
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
    for (k, estimate, feature) in found {
        let at = match (feature, lag) {
            (Some(feature), Some(lag)) => feature - lag,
            _ => estimate,
        };
        events[k] = placed(t, events[k].side, EventKind::HeelStrike, 0, Some(at));
    }
}
