//! Heel strikes and toe-offs from keypoints, or from a user's CSV.

use crate::config::Side;
use crate::direction::Direction;
pub use crate::event::{Event, EventKind, sort};
pub use crate::events_csv::read_csv;
use crate::margins::EventMargin;
pub use crate::peaks::find_peaks;
use crate::peaks::{Peak, gait_peaks};
pub use crate::stance_check::drop_implausible_toe_offs;
use crate::tracks::Tracks;

/// The keypoints a foot's events are taken from: heel strikes from the heel and toe-offs from
/// the toe where the model gives them, else from the ankle (Zeni's method on the ankle, as for
/// OpenPose COCO-18 and COCO-17 models, which have no feet).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EventKeypoints {
    pub side: Side,
    /// Index into the tracks' keypoints.
    pub heel_strike: usize,
    pub toe_off: usize,
}

impl EventKeypoints {
    /// The keypoints of `side` in `t`; `None` without even an ankle.
    pub fn of(t: &Tracks, side: Side) -> Option<Self> {
        let pick = |parts: &[&str]| parts.iter().find_map(|p| t.seen_leg_index(side, p));
        Some(Self {
            side,
            heel_strike: pick(&["heel", "ankle"])?,
            toe_off: pick(&["toe", "ankle"])?,
        })
    }

    /// `left_heel/left_toe`-style names, for run.json and the warnings.
    pub fn describe(&self, t: &Tracks) -> String {
        format!("{}/{}", t.names[self.heel_strike], t.names[self.toe_off])
    }
}

/// Finds gait events in cleaned trajectories with a known direction per frame.
pub trait EventDetector {
    fn detect(&self, t: &Tracks, dirs: &[Direction]) -> Vec<Event>;

    /// The events and how close the detector's decisions came to its thresholds (run.json),
    /// from one detection; no margins by default.
    fn detect_with_margins(
        &self,
        t: &Tracks,
        dirs: &[Direction],
    ) -> (Vec<Event>, Vec<EventMargin>) {
        (self.detect(t, dirs), Vec::new())
    }
}

/// Zeni et al. (2008) coordinate method, refined by foot speed. Zeni: heel strike at the most
/// forward heel position relative to the pelvis, toe-off at the most backward toe position. At
/// those extrema the foot moves over the ground exactly as fast as the pelvis; at real contact
/// the heel is still. So each heel strike is moved forward to where the heel's speed over the
/// ground has fallen to `speed_fraction` of the walking speed, searched within `refine_s`
/// (a fraction of 1 keeps Zeni's extremum).
///
/// Each toe-off is placed where the toe's speed over the ground rises through
/// `toe_speed_fraction` of the walking speed, searched within `refine_s` of Zeni's extremum
/// (backwards when the toe is already faster there, else forwards). The default 1 is Zeni's
/// own condition (the toe as fast as the pelvis), but against the walking speed, the pelvis'
/// mean speed over +-0.25 s, instead of the pelvis' speed in that frame: a pose model's hip
/// keypoints jitter by several pixels a frame, and where the toe moves at about the pelvis'
/// speed for a few frames (rolling over the toes) that jitter alone decides which frame is the
/// extremum (BlazePose on the bundled sample: the pelvis moved 1, 23, 1, 24 px in successive
/// frames where it walks a steady 11). On clean marker data the two agree to a frame. A
/// fraction below 1 would move toe-offs earlier: the toe point already moves while the foot
/// rolls over the toes, before the toe leaves the ground (on the independent trials in
/// tests/independent_mocap.rs that came 2-4 frames early). 0 keeps Zeni's extremum.
///
/// Speeds are taken over the ground, not the image: the ground's image speed is the stance
/// foot's (per frame the slower foot, median over +-0.5 s), zero for a fixed camera over a
/// floor, minus the belt speed on a treadmill. The walking speed is the pelvis' speed over it.
///
/// Finally [`drop_implausible_toe_offs`] removes toe-offs that follow their own foot's heel
/// strike by less than `min_stance_share` of the stride.
#[derive(Debug, Clone)]
pub struct ZeniRefined {
    pub speed_fraction: f64,
    pub toe_speed_fraction: f64,
    /// As `toe_speed_fraction`, for a model without toes, whose toe-offs come from the ankle.
    /// The ankle rises and moves on while the toe is still on the ground, so it passes the
    /// walking speed before the toe does: at 1 the toe-offs came 4-10 frames (150 Hz) early on
    /// the gaitkit Parkinson's trial and 2 frames (30 fps) early on the sample against the
    /// heel-and-toe run. At 1.5 the mean error on that trial is 2.7 frames (1.6 with the toe),
    /// and 7 of 7 toe-offs on the sample are within a frame of the heel-and-toe run's
    /// (tests/robustness.rs).
    pub ankle_toe_speed_fraction: f64,
    pub refine_s: f64,
    /// Peaks closer than this (seconds) are merged, keeping the larger.
    pub min_stride_s: f64,
    /// Shortest stance, heel strike to toe-off of one foot, as a share of the stride.
    pub min_stance_share: f64,
    /// A peak of the foot's excursion is a stride when its prominence is at least this share
    /// of the median prominence of the foot's peaks (and at least 0.1 leg lengths); see
    /// [`crate::peaks::gait_peaks`].
    pub excursion_share: f64,
}

impl Default for ZeniRefined {
    fn default() -> Self {
        Self {
            speed_fraction: 0.5,
            toe_speed_fraction: 1.0,
            ankle_toe_speed_fraction: 1.5,
            refine_s: 0.2,
            min_stride_s: 0.5,
            // Walking has double support, so each stance is over half the stride (about 60 %
            // in healthy gait, longer in slow and pathological gait, rarely under 55 % on a
            // prosthetic side). A toe-off at under 30 % cannot be walking: it comes from
            // mislabelled legs. Half the shortest real stance leaves room for timing errors.
            min_stance_share: 0.3,
            excursion_share: 0.5,
        }
    }
}

/// Forward speed (pixels/s) of keypoint `j` at frame `i` by central differences; NaN at the ends,
/// where a neighbour is missing, or where the direction is unknown.
fn forward_speed(t: &Tracks, dirs: &[Direction], j: usize, i: usize) -> f64 {
    let d = dirs.get(i).map_or(0.0, |d| d.sign());
    if i == 0 || i + 1 >= t.len() || d == 0.0 {
        return f64::NAN;
    }
    match (t.at(j, i - 1), t.at(j, i + 1)) {
        (Some(a), Some(b)) => d * (b.0 - a.0) * t.fps / 2.0,
        _ => f64::NAN,
    }
}

/// Per-frame forward image speed of the ground under the feet: the slower foot's speed (the
/// stance foot never moves faster than the ground, a swinging one does), median over +-0.5 s
/// to bridge double support and noise. 0 where no foot is seen.
pub(crate) fn ground_speed(t: &Tracks, dirs: &[Direction]) -> Vec<f64> {
    let n = t.len();
    let feet: Vec<Vec<usize>> = Side::BOTH
        .iter()
        .map(|&s| {
            ["heel", "toe"]
                .iter()
                .filter_map(|p| t.seen_leg_index(s, p))
                .collect()
        })
        .collect();
    let raw: Vec<f64> = (0..n)
        .map(|i| {
            feet.iter()
                .filter(|f| !f.is_empty())
                .map(|f| {
                    f.iter().map(|&j| forward_speed(t, dirs, j, i)).sum::<f64>() / f.len() as f64
                })
                .filter(|v| v.is_finite())
                .fold(f64::NAN, f64::min)
        })
        .collect();
    let w = (0.5 * t.fps).round().max(1.0) as usize;
    (0..n)
        .map(|i| {
            let mut win: Vec<f64> = raw[i.saturating_sub(w)..(i + w + 1).min(n)]
                .iter()
                .copied()
                .filter(|v| v.is_finite())
                .collect();
            if win.is_empty() {
                return 0.0;
            }
            win.sort_by(f64::total_cmp);
            win[win.len() / 2]
        })
        .collect()
}

impl ZeniRefined {
    fn side_events(
        &self,
        t: &Tracks,
        dirs: &[Direction],
        ground: &[f64],
        side: Side,
        leg: f64,
    ) -> (Vec<Event>, Vec<EventMargin>) {
        let n = t.len();
        let fps = t.fps;
        let Some(EventKeypoints {
            heel_strike: heel,
            toe_off: toe,
            ..
        }) = EventKeypoints::of(t, side)
        else {
            return (Vec::new(), Vec::new());
        };
        let d = |i: usize| dirs.get(i).map_or(0.0, |d| d.sign());
        let rel = |j: usize, i: usize| match (t.at(j, i), t.pelvis(i)) {
            (Some(a), Some(p)) if d(i) != 0.0 => d(i) * (a.0 - p.0),
            _ => f64::NAN,
        };
        let heel_rel: Vec<f64> = (0..n).map(|i| rel(heel, i)).collect();
        let toe_back: Vec<f64> = (0..n).map(|i| -rel(toe, i)).collect();
        let min_dist = (self.min_stride_s * fps).round() as usize;
        let prom = 0.1 * leg;
        // Speeds over the ground (pixels/s).
        let speed = |j: usize, i: usize| forward_speed(t, dirs, j, i) - ground[i];
        // Over +-0.25 s, or as much of it as the pelvis is seen: near the start of a track
        // (a heel strike a few frames after the walker comes into view) the full window would
        // leave the event on Zeni's extremum, a frame or more from the crossing.
        let walking_speed = |i: usize| -> f64 {
            let w = (0.25 * fps).round().max(1.0) as usize;
            let seen = |k: &usize| t.pelvis(*k).is_some();
            let lo = (i.saturating_sub(w)..=i).find(seen);
            let hi = (i..=(i + w).min(n - 1)).rev().find(seen);
            match (lo, hi) {
                (Some(lo), Some(hi)) if hi >= lo + w => {
                    let (a, b) = (
                        t.pelvis(lo).unwrap_or_default(),
                        t.pelvis(hi).unwrap_or_default(),
                    );
                    d(i) * (b.0 - a.0) * fps / (hi - lo) as f64 - ground[i]
                }
                _ => f64::NAN,
            }
        };
        let steps = (self.refine_s * fps).round() as usize;
        // Where the foot speed crosses `target` (linearly between the two frames around it),
        // rising or falling in time, searched from `p` forwards or backwards for `steps` frames.
        let crossing = |j: usize, p: usize, target: f64, rising: bool, forward: bool| {
            for k in 0..steps {
                let (a, b) = if forward {
                    (p + k, p + k + 1)
                } else {
                    (p.checked_sub(k + 1)?, p - k)
                };
                if b >= n {
                    return None;
                }
                let (va, vb) = (speed(j, a), speed(j, b));
                if !(va.is_finite() && vb.is_finite()) {
                    return None;
                }
                let crossed = if rising {
                    va <= target && vb > target
                } else {
                    va > target && vb <= target
                };
                if crossed {
                    return Some((a, (va - target) / (va - vb)));
                }
            }
            None
        };
        // Heel strike: forwards to where the heel has slowed to `speed_fraction`.
        let heel_strike = |p: usize| {
            let vp = walking_speed(p);
            if self.speed_fraction >= 1.0 || !(vp.is_finite() && vp > 0.0) {
                return None;
            }
            crossing(heel, p, self.speed_fraction * vp, false, true)
        };
        // Toe-off: where the toe's speed rises through `toe_speed_fraction`, searched from the
        // extremum towards the side where the toe is on the wrong side of it.
        let toe_off = |p: usize| {
            let vp = walking_speed(p);
            let v0 = speed(toe, p);
            if !(self.toe_speed_fraction > 0.0 && vp.is_finite() && vp > 0.0 && v0.is_finite()) {
                // 0 keeps Zeni's extremum for the ankle too.
                return None;
            }
            let frac = if t.names[toe].ends_with("_ankle") {
                self.ankle_toe_speed_fraction
            } else {
                self.toe_speed_fraction
            };
            let target = frac * vp;
            crossing(toe, p, target, true, v0 <= target)
        };
        // At the crossing, else at Zeni's extremum.
        let event = |event, p: usize, crossed: Option<(usize, f64)>| match crossed {
            // On the nearer frame, and the crossing itself in `at`.
            Some((a, f)) => Event {
                side,
                event,
                frame: t.first_frame + a + usize::from(f >= 0.5),
                at: Some((t.first_frame + a) as f64 + f),
            },
            None => Event::on_frame(side, event, t.first_frame + p),
        };
        let stable = |p: usize| {
            let w = (0.1 * fps).round() as usize;
            let lo = p.saturating_sub(w);
            let hi = (p + w).min(n - 1);
            (lo..=hi).all(|i| dirs.get(i) == dirs.get(p))
        };
        let mut out = Vec::new();
        let heel_peaks = gait_peaks(&heel_rel, prom, self.excursion_share, min_dist);
        let toe_peaks = gait_peaks(&toe_back, prom, self.excursion_share, min_dist);
        let margins = vec![
            EventMargin::of(side, EventKind::HeelStrike, &heel_peaks),
            EventMargin::of(side, EventKind::ToeOff, &toe_peaks),
        ];
        for &Peak { index: p, .. } in &heel_peaks.kept {
            if stable(p) {
                out.push(event(EventKind::HeelStrike, p, heel_strike(p)));
            }
        }
        for &Peak { index: p, .. } in &toe_peaks.kept {
            if stable(p) {
                out.push(event(EventKind::ToeOff, p, toe_off(p)));
            }
        }
        (out, margins)
    }

    /// Each side's events and margins, `None` without a usable leg length or frame rate.
    fn both_sides(&self, t: &Tracks, dirs: &[Direction]) -> Option<(Vec<Event>, Vec<EventMargin>)> {
        let leg = t.leg_length();
        if !leg.is_finite() || t.fps <= 0.0 {
            return None;
        }
        let ground = ground_speed(t, dirs);
        let (mut ev, mut margins) = (Vec::new(), Vec::new());
        for s in Side::BOTH {
            let (e, m) = self.side_events(t, dirs, &ground, s, leg);
            ev.extend(e);
            margins.extend(m);
        }
        Some((ev, margins))
    }
}

impl EventDetector for ZeniRefined {
    fn detect(&self, t: &Tracks, dirs: &[Direction]) -> Vec<Event> {
        self.detect_with_margins(t, dirs).0
    }

    fn detect_with_margins(
        &self,
        t: &Tracks,
        dirs: &[Direction],
    ) -> (Vec<Event>, Vec<EventMargin>) {
        let Some((mut ev, margins)) = self.both_sides(t, dirs) else {
            return (Vec::new(), Vec::new());
        };
        sort(&mut ev);
        drop_implausible_toe_offs(&mut ev, self.min_stance_share);
        (ev, margins)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{self, toe_offs};

    /// A pose model's hip jitter (here the pelvis alternately 8 px ahead and behind, more than
    /// it walks in a frame) leaves the toe-offs where they were; Zeni's bare extremum moves.
    #[test]
    fn toe_offs_do_not_follow_pelvis_jitter() {
        let clean = testing::walker(30.0, 150, |i| 100.0 + 13.0 * i as f64);
        let mut noisy = clean.clone();
        let pelvis = noisy.index("mid_hip").unwrap();
        for (i, x) in noisy.x[pelvis].iter_mut().enumerate() {
            *x += if i % 2 == 0 { 8.0 } else { -8.0 };
        }
        let dirs = vec![Direction::Right; clean.len()];
        let detect = |d: &ZeniRefined, t: &Tracks| toe_offs(&d.detect(t, &dirs));
        let ours = ZeniRefined::default();
        let before = detect(&ours, &clean);
        assert!(before.len() >= 6, "{before:?}");
        assert_eq!(detect(&ours, &noisy), before);
        let zeni = ZeniRefined {
            toe_speed_fraction: 0.0,
            ..ZeniRefined::default()
        };
        let (a, b) = (detect(&zeni, &clean), detect(&zeni, &noisy));
        assert_eq!(a.len(), b.len());
        assert!(
            a.iter()
                .zip(&b)
                .all(|(x, y)| x.0 == y.0 && x.1.abs_diff(y.1) <= 1)
        );
        assert_ne!(a, b, "the jitter moves Zeni's extremum");
    }

    /// A heel strike a few frames after the walker comes into view is placed at its speed
    /// crossing, as in mid-walk (before, the walking speed over +-0.25 s needed the pelvis
    /// before the track began, and the event stayed on Zeni's extremum).
    #[test]
    fn a_heel_strike_near_the_start_of_the_track_gets_its_crossing() {
        let full = testing::walker(30.0, 150, |i| 100.0 + 13.0 * i as f64);
        let dirs = vec![Direction::Right; full.len()];
        let all = ZeniRefined::default().detect(&full, &dirs);
        let strike = all
            .iter()
            .find(|e| e.event == EventKind::HeelStrike && e.frame > 30)
            .copied()
            .unwrap();
        let mut late = full.clone();
        for coord in late.x.iter_mut().chain(late.y.iter_mut()) {
            coord[..strike.frame - 4].fill(f64::NAN);
        }
        let found = ZeniRefined::default().detect(&late, &dirs);
        let again = found.iter().find(|e| e.key() == strike.key()).unwrap();
        assert!(again.at.is_some(), "{again:?}");
        assert!(
            (again.time() - strike.time()).abs() < 0.5,
            "{again:?} vs {strike:?}"
        );
    }
}
