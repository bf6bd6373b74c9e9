//! Frames where the pose model drew both legs on one leg ("collapsed" legs).
//!
//! A side-view pose model sometimes puts the left and the right knee, ankle, heel and toe
//! (nearly) on top of each other for a frame or a few, while the legs are well apart just
//! before and just after. Such a frame carries no usable leg labels and wrong positions for at
//! least one leg. It also misleads the swap correction: its constant-velocity prediction
//! through the collapsed frame points the legs towards each other, so the correct labels of
//! the next frames look exchanged. [`CollapseRule::find`] marks those frames, and the cleaning chain drops
//! their lower-leg keypoints before the swap correction; gap filling then bridges them.
//!
//! Telling a collapse from a real crossing of the legs (the swing foot passing the stance
//! foot, which happens in every stride): interpolate each leg between the frames just before
//! and just after a short run of frames, with the model's labels. When the legs cross in
//! between, the interpolated left-right offset changes sign and passes through zero, so the
//! interpolation itself has the legs close together: nothing is marked. Only when the
//! interpolated legs stay apart while the drawn ones are close has the model collapsed them.
//! The left-right offset does not depend on the labels, so a frame whose labels are merely
//! exchanged is never marked (that is the swap correction's job). An end frame with exchanged
//! labels, though, flips its offset's sign and makes a collapse beside it look like a crossing:
//! where the offset would have to turn round faster than a swing foot passes the stance foot,
//! the end is taken with its labels the other way round (a 720p copy of the sample: one frame
//! exchanged, the next collapsed, and the swap correction, predicting through the collapse,
//! then exchanged the six correct frames after it).

use crate::config::Side;
use crate::tracks::{LOWER_LEG, Tracks};

/// The collapse test: a run of at most `max_run_s` is collapsed when in each of its frames the
/// drawn legs are closer than `max_ratio` times the interpolated distance and at least
/// `min_drop` leg lengths (hip to ankle) closer, and the legs are at least `min_drop` leg
/// lengths apart in the frames either side (distances are means over knee, ankle, heel, toe).
#[derive(Debug, Clone)]
pub struct CollapseRule {
    /// Longest run of collapsed frames, in seconds. Longer runs cannot be told from standing
    /// with the feet together, and could not be bridged by interpolation anyway. The default
    /// 0.1 s is `kinematics.cycle_max_filled_s`: a stride with a longer gap is rejected.
    pub max_run_s: f64,
    /// The drawn legs' mean left-right distance must be below this share of the interpolated
    /// one. 0.5: at least half the distance between the legs has vanished.
    pub max_ratio: f64,
    /// ... and it must have shrunk by this many leg lengths, so that noise on legs that are
    /// close anyway (seen from the front, small images) never counts. 0.25 hip-to-ankle
    /// lengths is about a quarter of a step and ten times the frame-to-frame jitter of a pose
    /// model's feet.
    pub min_drop: f64,
    /// The fastest the legs' left-right offset can turn round in a real crossing, in leg
    /// lengths (hip to ankle) per second: a swing foot passes the planted one at up to about
    /// 4.5 leg lengths a second (3.5-4 m/s on a 0.85 m leg); 7.5 leaves a margin for jitter.
    /// Ends whose offsets point opposite ways and differ by more than that are one crossing
    /// too fast, so one of them has its labels exchanged.
    pub max_crossing_speed: f64,
}

impl Default for CollapseRule {
    fn default() -> Self {
        Self {
            max_run_s: 0.1,
            max_ratio: 0.5,
            min_drop: 0.25,
            max_crossing_speed: 7.5,
        }
    }
}

/// `[left, right]` indices of the lower-leg parts present on both sides (the hips are close
/// together in any side view and say nothing).
fn pairs(t: &Tracks) -> Vec<[usize; 2]> {
    LOWER_LEG
        .iter()
        .filter_map(|p| Some([t.leg_index(Side::Left, p)?, t.leg_index(Side::Right, p)?]))
        .collect()
}

/// Left minus right of a pair at frame `i`.
fn offset(t: &Tracks, pair: [usize; 2], i: usize) -> Option<(f64, f64)> {
    let (l, r) = (t.at(pair[0], i)?, t.at(pair[1], i)?);
    Some((l.0 - r.0, l.1 - r.1))
}

impl CollapseRule {
    /// Per frame of `t`, whether its legs are collapsed.
    pub fn find(&self, t: &Tracks) -> Vec<bool> {
        let n = t.len();
        let mut out = vec![false; n];
        let pairs = pairs(t);
        let leg = crate::swap::median_leg_length(t).unwrap_or(f64::NAN);
        if pairs.is_empty() || !leg.is_finite() || leg <= 0.0 || t.fps <= 0.0 {
            return out;
        }
        let max_run = ((self.max_run_s * t.fps).round() as usize).max(1);
        // Is frame j collapsed relative to the legs interpolated between frames a and b?
        let collapsed = |a: usize, j: usize, b: usize| -> bool {
            let w = (j - a) as f64 / (b - a) as f64;
            let turn_max = self.max_crossing_speed * leg * (b - a) as f64 / t.fps;
            let (mut drawn, mut expected, mut ends, mut k) = (0.0, 0.0, [0.0; 2], 0);
            for &p in &pairs {
                let (Some(da), Some(dj), Some(db)) =
                    (offset(t, p, a), offset(t, p, j), offset(t, p, b))
                else {
                    continue;
                };
                let turned = da.0 * db.0 + da.1 * db.1 < 0.0;
                let da = if turned && (db.0 - da.0).hypot(db.1 - da.1) > turn_max {
                    (-da.0, -da.1)
                } else {
                    da
                };
                let e = (da.0 + w * (db.0 - da.0), da.1 + w * (db.1 - da.1));
                drawn += dj.0.hypot(dj.1);
                expected += e.0.hypot(e.1);
                ends[0] += da.0.hypot(da.1);
                ends[1] += db.0.hypot(db.1);
                k += 1;
            }
            if k == 0 {
                return false;
            }
            let k = k as f64;
            let (drawn, expected) = (drawn / k, expected / k);
            let min = self.min_drop * leg;
            // The frames either side must show the legs apart themselves, or a long collapse
            // would be cut into short ones with one end inside it.
            ends.iter().all(|&e| e / k > min)
                && drawn < self.max_ratio * expected
                && expected - drawn > min
        };
        for a in 0..n {
            for len in 1..=max_run {
                let b = a + len + 1;
                if b >= n {
                    break;
                }
                if (a + 1..b).all(|j| collapsed(a, j, b)) {
                    for o in &mut out[a + 1..b] {
                        *o = true;
                    }
                }
            }
        }
        out
    }
}

/// Removes the lower-leg keypoints (knee, ankle, heel, toe) of both legs at the marked frames;
/// the hips stay.
pub fn drop_frames(t: &mut Tracks, frames: &[bool]) {
    for side in Side::BOTH {
        for p in LOWER_LEG {
            let Some(j) = t.leg_index(side, p) else {
                continue;
            };
            for (i, _) in frames.iter().enumerate().filter(|f| *f.1) {
                t.x[j][i] = f64::NAN;
                t.y[j][i] = f64::NAN;
                t.likelihood[j][i] = 0.0;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::swap::swap_frame;
    use crate::testing;

    fn lower(t: &Tracks, side: Side) -> Vec<usize> {
        LOWER_LEG
            .iter()
            .map(|p| t.leg_index(side, p).unwrap())
            .collect()
    }

    /// Draws the right lower leg onto the left one (a few pixels off) at frame `i`.
    fn collapse(t: &mut Tracks, i: usize) {
        for (l, r) in lower(t, Side::Left).into_iter().zip(lower(t, Side::Right)) {
            t.x[r][i] = t.x[l][i] + 6.0;
            t.y[r][i] = t.y[l][i] - 4.0;
        }
    }

    /// Frames where the synthetic legs are further apart than `min` pixels (mean over parts).
    fn apart(t: &Tracks, i: usize, min: f64) -> bool {
        let (l, r) = (lower(t, Side::Left), lower(t, Side::Right));
        let d: f64 = l
            .iter()
            .zip(&r)
            .map(|(&a, &b)| crate::tracks::dist(t.at(a, i).unwrap(), t.at(b, i).unwrap()))
            .sum();
        d / 4.0 > min
    }

    #[test]
    fn real_crossings_and_swapped_labels_are_not_collapses() {
        // The synthetic feet pass each other every step, at 30 and at 150 frames a second,
        // overground and on a treadmill.
        for t in [
            testing::walker(30.0, 150, |i| 100.0 + 13.0 * i as f64),
            testing::walker(150.0, 600, |i| 100.0 + 2.6 * i as f64),
            testing::treadmill(30.0, 150, 400.0),
        ] {
            assert!(CollapseRule::default().find(&t).iter().all(|c| !c));
            let mut s = t.clone();
            for i in (20..25).chain([60, 61, 90]) {
                swap_frame(&mut s, i);
            }
            assert!(CollapseRule::default().find(&s).iter().all(|c| !c));
        }
    }

    #[test]
    fn legs_drawn_on_one_leg_are_found_and_dropped() {
        let clean = testing::walker(30.0, 150, |i| 100.0 + 13.0 * i as f64);
        // Frames where the legs are well apart (100 px, a third of the 300 px leg).
        let wide: Vec<usize> = (10..140).filter(|&i| apart(&clean, i, 100.0)).collect();
        let (one, run) = (wide[3], wide[wide.len() / 2]);
        assert!((run - 1..=run + 1).all(|i| wide.contains(&i)), "{wide:?}");
        let mut t = clean.clone();
        collapse(&mut t, one);
        for i in run - 1..=run + 1 {
            collapse(&mut t, i);
        }
        let found = CollapseRule::default().find(&t);
        let expect: Vec<usize> = [one, run - 1, run, run + 1].into();
        let got: Vec<usize> = (0..t.len()).filter(|&i| found[i]).collect();
        assert_eq!(got, expect);

        drop_frames(&mut t, &found);
        for &i in &expect {
            for j in lower(&t, Side::Left)
                .into_iter()
                .chain(lower(&t, Side::Right))
            {
                assert!(t.at(j, i).is_none() && t.likelihood[j][i] == 0.0);
            }
            for side in Side::BOTH {
                let hip = t.leg_index(side, "hip").unwrap();
                assert_eq!(t.at(hip, i), clean.at(hip, i));
            }
        }
        assert_eq!(t.at(1 + 2, one + 1), clean.at(1 + 2, one + 1));

        // A collapse beside a frame with exchanged labels: the offset would turn round from one
        // end to the other faster than a foot moves, so it is no crossing.
        let mut beside = clean.clone();
        swap_frame(&mut beside, run - 1);
        collapse(&mut beside, run);
        let found = CollapseRule::default().find(&beside);
        let got: Vec<usize> = (0..beside.len()).filter(|&i| found[i]).collect();
        assert_eq!(got, vec![run]);

        // A run longer than max_run_s (0.1 s = 3 frames) is not a glitch that can be bridged.
        let mut long = clean.clone();
        let start = wide
            .windows(5)
            .find(|w| w[4] == w[0] + 4)
            .map(|w| w[0])
            .unwrap();
        for i in start..start + 5 {
            collapse(&mut long, i);
        }
        let found = CollapseRule::default().find(&long);
        assert!(found.iter().all(|c| !c), "{start}");
    }
}
