//! Heel strikes and toe-offs from a front or back view, from the feet's image speed.
//!
//! A side view finds events where a foot is furthest ahead of or behind the pelvis (Zeni). A
//! frontal camera sees "ahead" as depth, and there the foot's own lift (20-30 cm at the heel,
//! against a camera about 1 m high) moves it in the image more than its distance ahead of the
//! pelvis does: on projected motion capture the heel's lowest image point fell in mid-swing of
//! a walk away from the camera. What a fixed camera does see exactly is a foot standing still:
//! a planted heel does not move in the image, whatever the view. So each stride is a peak of
//! the foot's image speed (in body sizes per second, so it does not grow as the walker comes
//! nearer), and between two swings the foot stands: the heel strike starts the longest still
//! run of the heel ([`STOP_HEEL`]), the toe-off ends the toe's. Under a pose model's jitter
//! those starts and ends move by video frames, so the heel strikes are then placed from the
//! feet's vertical image distance near each start (`heel_strikes`), and walking toward the
//! camera each toe-off where that distance peaks near the end of the toe's still run
//! ([`lead`]).

use crate::config::Side;
use crate::events::{Event, EventKeypoints, EventKind};
use crate::frontal::scale::Scale;
use crate::frontal::{heel_strikes, lead};
use crate::margins::EventMargin;
use crate::peaks::{Peak, gait_peaks};
use crate::tracks::Tracks;
use crate::view::View;

/// A swing is a speed peak of at least this share of the foot's median swing peak (as the side
/// view's rule, see [`crate::peaks::gait_peaks`]) ...
const SHARE: f64 = 0.5;
/// ... and at least this fast, in body sizes per second: a swinging foot moves at about 1
/// body size per second in the image 5 m from the camera, a planted one not at all.
const FLOOR: f64 = 0.3;
/// A foot counts as still at or below this share of the peak speed of the swings around it:
/// the heel (heel strikes) and the toe (toe-offs). Chosen on the projected trials of
/// tests/data/frontal (both views): at 0.1 a Parkinson's walker's heel, lowered slowly while it
/// moves away from a camera behind, looked still 25 frames (150 Hz) before contact; at 0.05 a
/// pose model's jitter would pass for movement. A toe rolls over before it lifts, so its
/// onset of movement is taken at the larger share.
const STOP_HEEL: f64 = 0.07;
const STOP_TOE: f64 = 0.1;
/// Walking away from the camera the toe's image speed rises slowly out of stance (the forefoot
/// lifts and moves away along the line of sight before the toe leaves the floor): at 0.1 the
/// toe-offs came 8-12 frames (150 Hz) before the side view's on the projected walks away, and
/// 2-3 video frames early under jitter; at 0.6 of the faster swing either side, 0-2 frames
/// (150 Hz) clean and within a video frame in 90-93 % of the jittered toe-offs
/// (tests/frontal_mocap.rs). Against the swing after the stance (`stances`), often the slower
/// of the two walking away, 0.65 gives the same figures (0.6: the healthy walk's clean
/// toe-offs a frame earlier and 5 more of its 50 jittered ones 2-3 video frames off).
const STOP_TOE_RECEDING: f64 = 0.65;

/// The events of both feet, heel strikes from the heel (else the ankle) and toe-offs from the
/// toe (else the ankle), with the margins of the swing decisions.
pub fn detect(
    t: &Tracks,
    view: View,
    scale: &Scale,
    min_stride_s: f64,
) -> (Vec<Event>, Vec<EventMargin>) {
    let min_dist = ((0.8 * min_stride_s * t.fps).round() as usize).max(1);
    let mut events = Vec::new();
    let mut margins = Vec::new();
    for side in Side::BOTH {
        let Some(kp) = EventKeypoints::of(t, side) else {
            continue;
        };
        for (kind, j) in [
            (EventKind::HeelStrike, kp.heel_strike),
            (EventKind::ToeOff, kp.toe_off),
        ] {
            let v = speed(t, j, scale);
            let swings = gait_peaks(&v, FLOOR, SHARE, min_dist);
            margins.push(EventMargin::of(side, kind, &swings));
            let stop = match (kind, view) {
                (EventKind::HeelStrike, _) => STOP_HEEL,
                (EventKind::ToeOff, View::Posterior) => STOP_TOE_RECEDING,
                (EventKind::ToeOff, _) => STOP_TOE,
            };
            let frames = stances(&v, &swings.kept, (stop, kind), t.fps)
                .into_iter()
                .filter_map(|(a, b)| match kind {
                    // A heel strike starts a stance that follows a swing; a toe-off ends one that
                    // precedes a swing.
                    EventKind::HeelStrike => a,
                    EventKind::ToeOff => b,
                });
            events.extend(frames.map(|i| match (kind, view) {
                (EventKind::ToeOff, View::Anterior) => approaching_toe_off(t, side, i),
                _ => Event::on_frame(side, kind, t.first_frame + i),
            }));
        }
    }
    heel_strikes::place(t, view, min_stride_s, &mut events);
    events.sort_by_key(|e| (e.frame, e.side == Side::Right, e.event));
    // Two toe still runs before one swing can end at the same distance peak (walking toward
    // the camera): one toe-off.
    events.dedup_by(|a, b| a.key() == b.key() && (a.time() - b.time()).abs() < 0.5);
    (events, margins)
}

/// A toe-off of a walk toward the camera: where the feet's vertical distance peaks around
/// `end`, the end of the toe's still run ([`lead`]), else that end.
fn approaching_toe_off(t: &Tracks, side: Side, end: usize) -> Event {
    let frames = |s: f64| (s * t.fps).round() as usize;
    let lo = end.saturating_sub(frames(lead::TOE_SEARCH_BEFORE_S));
    match lead::toe_off_near(t, side, lo, end + frames(lead::TOE_SEARCH_AFTER_S)) {
        Some(at) => {
            Event::between_frames(side, EventKind::ToeOff, t.first_frame as f64 + at.max(0.0))
        }
        None => Event::on_frame(side, EventKind::ToeOff, t.first_frame + end),
    }
}

/// Image speed of keypoint `j` per frame, in body sizes per second (central differences).
fn speed(t: &Tracks, j: usize, scale: &Scale) -> Vec<f64> {
    let n = t.len();
    (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n.saturating_sub(1)));
            match (t.at(j, a), t.at(j, b), scale.size[i]) {
                (Some(p), Some(q), s) if b > a && s > 0.0 => {
                    (q.0 - p.0).hypot(q.1 - p.1) / s * t.fps / (b - a) as f64
                }
                _ => f64::NAN,
            }
        })
        .collect()
}

/// Still frames separated by moving ones for at most this long (s) are one still run: a pose
/// model's keypoint on a planted foot jitters.
const JITTER_S: f64 = 0.03;
/// A still run shorter than this (s) is no stance: stance lasts half a stride, while a foot
/// that moves along the camera's line of sight stands still in the image only for a moment
/// (walking away, a heel lowered as it moves away: 0.05 s in mid-swing of projected motion
/// capture).
const MIN_STANCE_S: f64 = 0.1;

/// The stance between each pair of consecutive swing peaks (and before the first, after the
/// last): the longest run of still frames there, as (first, last) frames; `None` at an end
/// of the track, where the stance is cut off. Still is under `stop` of the swing the event
/// belongs to: for a heel strike the swing before the stance, for a toe-off the one after (the
/// other where the track has none). Under jitter two swings' peaks differ: walking away, a
/// toe-off judged against the faster swing before its stance found the slower swing after it
/// never fast enough and ran on to the next peak (8-9 video frames late).
fn stances(
    v: &[f64],
    swings: &[Peak],
    (stop, kind): (f64, EventKind),
    fps: f64,
) -> Vec<(Option<usize>, Option<usize>)> {
    let jitter = (JITTER_S * fps).round() as usize;
    let min_len = ((MIN_STANCE_S * fps).round() as usize).max(2);
    let floor = low_percentile(v);
    let mut bounds: Vec<usize> = vec![0];
    bounds.extend(swings.iter().map(|p| p.index));
    bounds.push(v.len());
    let mut out = Vec::new();
    for (k, w) in bounds.windows(2).enumerate() {
        let (lo, hi) = (w[0], w[1]);
        let (before, after) = (k.checked_sub(1), Some(k));
        let order = match kind {
            EventKind::HeelStrike => [before, after],
            EventKind::ToeOff => [after, before],
        };
        let Some(peak) = (order.iter().flatten()).find_map(|&i| swings.get(i).map(|p| v[p.index]))
        else {
            continue;
        };
        let limit = (stop * peak).max(NOISE_FLOOR * floor);
        let Some((a, b)) = longest_still(&v[lo..hi], limit, jitter) else {
            continue;
        };
        if b + 1 - a < min_len {
            continue;
        }
        let first = k > 0 || a > 0;
        let last = k < swings.len() || hi < v.len();
        // A stance that touches the track's start has no heel strike in view, one that touches
        // its end no toe-off.
        out.push((
            (first && lo + a > 0 && k > 0).then_some(lo + a),
            (last && lo + b + 1 < v.len() && k < swings.len()).then_some(lo + b),
        ));
    }
    out
}

/// A pose model's jitter makes a planted foot move in the image: the still limit is at least
/// this many times the foot's 10th-percentile speed. A foot stands for about 60 % of the time,
/// so that percentile is the jitter of a planted foot (on motion capture nearly 0); for
/// Gaussian jitter the speed's 90th percentile is 4.7 times its 10th; 3.5 kept the posterior
/// walks of tests/data/frontal within 5 frames (at 4.5 one heel strike came 6 early).
const NOISE_FLOOR: f64 = 3.5;

/// The 10th percentile of the finite values (0 without any).
fn low_percentile(v: &[f64]) -> f64 {
    let mut w: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    w.sort_by(f64::total_cmp);
    w.get(w.len() / 10).copied().unwrap_or(0.0)
}

/// The longest run of values at or under `limit` (joined across at most `jitter` others), as
/// (first, last) indices.
fn longest_still(v: &[f64], limit: f64, jitter: usize) -> Option<(usize, usize)> {
    let mut best: Option<(usize, usize)> = None;
    let mut run: Option<(usize, usize)> = None;
    for (i, &x) in v.iter().enumerate() {
        if !(x.is_finite() && x <= limit) {
            continue;
        }
        run = match run {
            Some((a, b)) if i - b - 1 <= jitter => Some((a, i)),
            _ => Some((i, i)),
        };
        let (a, b) = run.expect("set above");
        if best.is_none_or(|(p, q)| b - a > q - p) {
            best = Some((a, b));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fast swing (peak 2), a stance, then a slow swing (peak 1, moving at 0.9 from frame 20):
    /// the toe-off is where the slow swing starts, not at its peak, and the heel strike is
    /// judged against the swing before.
    #[test]
    fn a_toe_off_is_judged_against_the_swing_it_starts() {
        let mut v = vec![0.05; 30];
        v[2] = 2.0;
        v[3] = 1.5;
        for x in &mut v[20..25] {
            *x = 0.9;
        }
        v[25] = 1.0;
        let swings = [2, 25].map(|index| Peak {
            index,
            prominence: 1.0,
        });
        let toe = stances(&v, &swings, (0.65, EventKind::ToeOff), 30.0);
        assert_eq!(toe[0].1, Some(19), "{toe:?}");
        let heel = stances(&v, &swings, (0.65, EventKind::HeelStrike), 30.0);
        assert_eq!(heel[0].0, Some(4), "{heel:?}");
    }
}
