//! Frontal events from the feet's vertical image distance: the features that place heel strikes
//! (walking away, the landing peak and the fall after it; walking toward, the trough after
//! contact) and the toe-offs walking toward the camera.
//!
//! The other foot's image height minus one foot's rises as that foot gets further from the
//! camera than the other. Seen from behind, just before heel strike the landing foot is as far
//! ahead of the other one, which is about to push off, as it gets, and the distance peaks there;
//! seen from the front, the pushing-off foot is furthest behind the planted one just after toe-off
//! (Stenum et al. 2024 take frontal events from the ankles' vertical distance). A peak is an
//! extremum, so a pose model's jitter spreads it about its frame instead of dragging it one way,
//! as it drags where a foot's image speed stops or starts ([`super::events`]): the receding heel
//! hardly moves in the image for 0.1-0.2 s before it lands, and under jitter that stretch passes
//! for stance; the approaching toe's speed rises early or late with the jitter. Each peak's offset
//! from the event was measured on projected motion capture against the side view's events.

use crate::config::Side;
use crate::tracks::Tracks;

/// The distance peaks this long before the heel strike (s): with the ankle, heel and toe
/// averaged, 5-9 frames (150 Hz) before the side view's heel strike on the four walks away of
/// tests/data/frontal (two trials, each foot, motion capture), median 5.5.
const LEAD_S: f64 = 0.04;
/// Walking toward the camera, the distance peaks this long after the toe-off (s): 6-10 frames
/// (150 Hz) after the side view's toe-off on the 12 toe-offs of the two walks toward the camera,
/// mean 8.
const TOE_LAG_S: f64 = 0.053;
/// Half-width of the local quadratic fit that smooths the distance before its peak is taken
/// (s): two frames at 30 fps. At 0.1 s the mid-swing peak and the landing one merge on a
/// healthy walk (tests/frontal_mocap.rs: 8 of 10 seeds held instead of 10).
const FIT_S: f64 = 0.067;
/// Where the heel strike's peak is looked for around the start of the heel's still run (s).
/// Under jitter that start moves both ways: a two-frame jitter bump in the settling heel starts
/// the run late (the Parkinson's walk away: 0.15 s), a heel lowered slowly while it moves away
/// starts it early (up to 0.37 s). At -0.1 / +0.3 s, 6 of the 14 heel strikes more than a video
/// frame off in 10 seeds were 4-14 frames off (tests/frontal_mocap.rs); at -0.3 / +0.4, none.
pub const SEARCH_BEFORE_S: f64 = 0.3;
pub const SEARCH_AFTER_S: f64 = 0.4;
/// A peak counts only in the upper half of the distance's range over the search window: the
/// landing peak and the mid-swing one are the window's highest, while the jitter's wiggles on
/// the distance's fall through early stance are low (on the Parkinson's walk away, a wiggle at
/// -10 px was the last peak of a window whose landing peak was +25).
const UPPER_SHARE: f64 = 0.5;
/// Where the trough that follows a heel strike walking toward the camera is looked for around
/// the start of the heel's still run (s): the trough comes 0.18 s (healthy) to 0.24 s
/// (Parkinson's) after the heel strike, and that start is up to 0.13 s early under jitter.
pub const TROUGH_SEARCH_BEFORE_S: f64 = 0.2;
pub const TROUGH_SEARCH_AFTER_S: f64 = 0.5;
/// Where the toe-off's peak is looked for around the end of the toe's still run (s). Jitter
/// breaks that run, and its longest part then ends 0.2-0.45 s early: at +0.2 s, 17 of the
/// Parkinson's walker's toe-offs toward the camera in 10 seeds were not found within 6 video
/// frames (the healthy walker's: 2); at +0.5 s, 5 and 0, those that remain at the track's end,
/// where the smoother cannot reach. The distance falls through the swing that follows, so the
/// highest peak of the wider window is still the toe-off's.
pub const TOE_SEARCH_BEFORE_S: f64 = 0.1;
pub const TOE_SEARCH_AFTER_S: f64 = 0.5;

/// Walking away from the camera, near a heel strike: the landing peak of the distance and, where
/// the distance falls after it, the middle of that fall (track frames, sub-frame).
pub struct Landing {
    /// The last peak of the distance within the search window (it also peaks in mid-swing,
    /// where the foot is lifted highest, before the landing one), plus [`LEAD_S`]: the heel
    /// strike itself, unbiased on motion capture but spread by jitter where the peak is flat.
    pub peak: f64,
    /// Where the distance, within [`FALL_S`] after the peak, crosses halfway from the peak's
    /// value down to its lowest: a steep fall (the other foot leaving the floor), which jitter
    /// hardly moves, at a lag after the heel strike that differs between walkers.
    pub fall: Option<f64>,
}

/// How long after the landing peak its fall is looked for (s): the halfway point came 0.11 s
/// after it on the healthy walk and 0.16 s on the Parkinson's (motion capture). At 0.3 / 0.4 /
/// 0.5 s the Parkinson's walk away held in 7 / 8 / 9 seeds of 10 with the jitter as measured
/// and 6 / 3 / 4 with the limbs' larger jitter (tests/frontal_mocap.rs); the healthy walk in 10.
const FALL_S: f64 = 0.5;

/// The landing of `side` within `[lo, hi]` track frames, `None` without a peak inside (an end
/// of the window is no peak).
pub fn landing_near(t: &Tracks, side: Side, lo: usize, hi: usize) -> Option<Landing> {
    let (lo, v) = distance(t, side, lo, hi)?;
    let peak = lo as f64 + last_peak(&v)?;
    let from = peak.round() as usize;
    let fall = distance(t, side, from, from + (FALL_S * t.fps).round() as usize)
        .and_then(|(start, w)| Some(start as f64 + halfway_down(&w)?));
    Some(Landing {
        peak: peak + LEAD_S * t.fps,
        fall,
    })
}

/// The sub-frame index where `v` first crosses below halfway from `v[0]` to its minimum,
/// before that minimum.
fn halfway_down(v: &[f64]) -> Option<f64> {
    let (low_at, low) =
        v.iter().enumerate().fold(
            (0, f64::INFINITY),
            |b, (k, &x)| if x < b.1 { (k, x) } else { b },
        );
    let level = 0.5 * (v.first()? + low);
    let k = (0..low_at).find(|&k| v[k] >= level && v[k + 1] < level)?;
    Some(k as f64 + (v[k] - level) / (v[k] - v[k + 1]))
}

/// Walking toward the camera, the last trough of the distance within `[lo, hi]` frames (in the
/// lower half of its range), sub-frame: the landing foot is then nearest the camera, lowest in
/// the image, against the other foot that is about to push off. It follows the heel strike by
/// the initial double support and a little more, which differs between walkers (0.18 s on the
/// healthy trial, 0.24 s on the Parkinson's), so the lag is calibrated per walk (`heel_strikes`).
pub fn trough_near(t: &Tracks, side: Side, lo: usize, hi: usize) -> Option<f64> {
    let (lo, v) = distance(t, side, lo, hi)?;
    let flipped: Vec<f64> = v.iter().map(|x| -x).collect();
    Some(lo as f64 + last_peak(&flipped)?)
}

/// The toe-off of `side` walking toward the camera: the highest peak of the distance within
/// `[lo, hi]` frames, less [`TOE_LAG_S`].
pub fn toe_off_near(t: &Tracks, side: Side, lo: usize, hi: usize) -> Option<f64> {
    let (lo, v) = distance(t, side, lo, hi)?;
    Some(lo as f64 + highest_peak(&v)? - TOE_LAG_S * t.fps)
}

/// The other foot's image height minus `side`'s (ankle, heel and toe averaged, those seen on
/// both feet), smoothed, over `[lo, hi]` clipped to where the smoother reaches: (first frame,
/// values).
fn distance(t: &Tracks, side: Side, lo: usize, hi: usize) -> Option<(usize, Vec<f64>)> {
    // Each foot point the model gives on both feet; their mean jitters less than one of them.
    let pairs: Vec<(usize, usize)> = ["ankle", "heel", "toe"]
        .iter()
        .filter_map(|p| {
            Some((
                t.seen_leg_index(side, p)?,
                t.seen_leg_index(side.other(), p)?,
            ))
        })
        .collect();
    if pairs.is_empty() {
        return None;
    }
    let gap = |i: usize| {
        let sum: f64 = pairs
            .iter()
            .map(|&(this, other)| match (t.at(this, i), t.at(other, i)) {
                (Some(a), Some(b)) => b.1 - a.1,
                _ => f64::NAN,
            })
            .sum();
        sum / pairs.len() as f64
    };
    let w = ((FIT_S * t.fps).round() as usize).max(1);
    let hi = hi.min(t.len().checked_sub(1 + w)?);
    let lo = lo.max(w);
    if hi <= lo + 1 {
        return None;
    }
    Some((lo, (lo..=hi).map(|i| quadratic_at(&gap, i, w)).collect()))
}

/// The sub-frame index of the last local maximum of `v` in the upper half of its range (its
/// vertex through the neighbours), not at either end.
fn last_peak(v: &[f64]) -> Option<f64> {
    let (low, high) = v
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    let floor = low + UPPER_SHARE * (high - low);
    let k = peaks(v).rfind(|&k| v[k] >= floor)?;
    Some(vertex(v, k))
}

/// The sub-frame index of the highest local maximum of `v`, not at either end.
fn highest_peak(v: &[f64]) -> Option<f64> {
    let k = peaks(v).max_by(|&a, &b| v[a].total_cmp(&v[b]))?;
    Some(vertex(v, k))
}

/// The indices of the local maxima of `v`, ends excluded.
fn peaks(v: &[f64]) -> impl DoubleEndedIterator<Item = usize> + '_ {
    (1..v.len().saturating_sub(1)).filter(|&k| v[k] >= v[k - 1] && v[k] >= v[k + 1])
}

/// `k` moved to the vertex of the parabola through `v[k - 1..=k + 1]` (at most half a frame).
fn vertex(v: &[f64], k: usize) -> f64 {
    let (a, b, c) = (v[k - 1], v[k], v[k + 1]);
    let curve = a - 2.0 * b + c;
    let shift = if curve < 0.0 {
        (0.5 * (a - c) / curve).clamp(-0.5, 0.5)
    } else {
        0.0
    };
    k as f64 + shift
}

/// The value at `i` of the least-squares quadratic through `f` over `i - w ..= i + w`
/// (a Savitzky-Golay smoother); NaN where a value is missing.
fn quadratic_at(f: &impl Fn(usize) -> f64, i: usize, w: usize) -> f64 {
    // For a symmetric window the fitted value at the centre weighs each point by
    // (3m^2 + 3m - 1 - 5k^2), m = w (Savitzky and Golay 1964).
    let m = w as f64;
    let mut num = 0.0;
    let mut den = 0.0;
    for k in -(w as i64)..=(w as i64) {
        let v = f((i as i64 + k) as usize);
        if !v.is_finite() {
            return f64::NAN;
        }
        let weight = 3.0 * m * m + 3.0 * m - 1.0 - 5.0 * (k * k) as f64;
        num += weight * v;
        den += weight;
    }
    num / den
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mid-swing peak is higher than the landing one: the last peak is the landing one, at
    /// its vertex between frames; the highest is the other. A low wiggle after it is no peak.
    #[test]
    fn the_last_peak_is_taken_between_frames() {
        let v = [1.0, 5.0, 2.0, 3.0, 3.5, 3.5, 2.0, 1.0];
        let p = last_peak(&v).unwrap();
        assert!((p - 4.5).abs() < 1e-9, "{p}");
        let wiggle = [1.0, 5.0, 2.0, 3.0, 3.5, 3.5, 2.0, 1.0, 1.2, 0.9];
        assert!((last_peak(&wiggle).unwrap() - 4.5).abs() < 1e-9);
        assert_eq!(last_peak(&[1.0, 2.0, 3.0]), None, "an end is no peak");
        // The highest is the first one, its vertex a fourteenth of a frame after it.
        let h = highest_peak(&v).unwrap();
        assert!((h - (1.0 + 1.0 / 14.0)).abs() < 1e-9, "{h}");
        assert_eq!(last_peak(&[]), None);
    }

    /// The fall is crossed halfway between its start and its lowest value, between frames; a
    /// wiggle after the lowest value does not count, nor does a series that never falls.
    #[test]
    fn the_fall_is_crossed_halfway_down() {
        let v = [10.0, 9.0, 6.0, 2.0, -2.0, -4.0, -3.0, -4.5, -2.0];
        // Halfway from 10 to -4.5 is 2.75: between 6 (k = 2) and 2 (k = 3), 0.8125 of the way.
        let k = halfway_down(&v).unwrap();
        assert!((k - 2.8125).abs() < 1e-9, "{k}");
        assert_eq!(halfway_down(&[1.0, 2.0, 3.0]), None);
    }

    /// The smoother leaves a quadratic as it is and misses no value.
    #[test]
    fn the_smoother_keeps_a_quadratic() {
        let f = |i: usize| {
            let x = i as f64;
            2.0 - 0.3 * x + 0.05 * x * x
        };
        for i in 3..10 {
            assert!((quadratic_at(&f, i, 3) - f(i)).abs() < 1e-9);
        }
        let gap = |i: usize| if i == 5 { f64::NAN } else { 1.0 };
        assert!(quadratic_at(&gap, 4, 2).is_nan());
    }
}
