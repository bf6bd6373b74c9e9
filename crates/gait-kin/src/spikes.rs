//! Single-frame jumps of a lower-leg keypoint.
//!
//! A pose model misplaces a toe, a heel or a knee by a few dozen pixels for one frame (motion
//! blur, the other leg passing), and in which frames it does so changes with the encoding and
//! the crop. The low-pass filter spreads such a jump over the frames around it, where it moves
//! the foot's speed and with it the events: on the bundled sample the right toe stood 40-47 px
//! ahead for one frame near its toe-off under HEVC and in the mirrored copy, and the toe-off
//! came 2-3 frames early. A point further from the midpoint of its two neighbours than any
//! walking foot or knee gets is dropped, and the gap filler bridges it.
//!
//! Why the midpoint: a point that moves on steadily, speeds up or stops lies within half a
//! frame's change of speed of it. The sharpest real change is the heel stopping at heel strike
//! or the toe leaving the ground, 15-30 px/frame within a frame or two at 30 fps (7-15 px off
//! the midpoint, under 0.1 leg lengths), and it is smaller at higher frame rates.

use crate::config::Side;
use crate::tracks::{LOWER_LEG, Tracks, dist};

/// The spike test: a sample seen with both neighbours further than `tolerance` leg lengths
/// (thigh + shank) from their midpoint.
#[derive(Debug, Clone)]
pub struct SpikeRule {
    pub tolerance: f64,
}

impl Default for SpikeRule {
    fn default() -> Self {
        // Twice the sharpest real change of a foot at 30 fps (see the module docs); the toes
        // misplaced on the sample are 0.22-0.25 leg lengths off. Chosen on the robustness
        // matrix (BENCHMARKS.md): 0.15 dropped real motion (9 of 16 variants held), 0.18 and
        // 0.2 held 11, 0.25 let the misplaced toes through (9).
        Self { tolerance: 0.2 }
    }
}

impl SpikeRule {
    /// `(keypoint, frame)` of each spike of a lower-leg keypoint of `t`. The furthest off go
    /// first, and a sample next to one already taken is not judged: its midpoint would hold
    /// the spike (on the sample's CRF 18 copy a left heel 78 px off at frame 152 made the good
    /// heel of frame 151 look 48 px off, both were dropped, and the gap's spline moved the
    /// heel strike by a frame).
    pub fn find(&self, t: &Tracks) -> Vec<(usize, usize)> {
        let leg = t.leg_length();
        if !(leg.is_finite() && leg > 0.0) {
            return Vec::new();
        }
        let limit = self.tolerance * leg;
        let points = Side::BOTH
            .iter()
            .flat_map(|&s| LOWER_LEG.iter().filter_map(move |p| t.leg_index(s, p)));
        let mut out = Vec::new();
        for j in points {
            let mut off: Vec<(f64, usize)> = (1..t.len().saturating_sub(1))
                .filter_map(|i| {
                    let (a, p, b) = (t.at(j, i - 1)?, t.at(j, i)?, t.at(j, i + 1)?);
                    let d = dist(p, ((a.0 + b.0) / 2.0, (a.1 + b.1) / 2.0));
                    (d > limit).then_some((d, i))
                })
                .collect();
            off.sort_by(|x, y| y.0.total_cmp(&x.0));
            let mut taken: Vec<usize> = Vec::new();
            for (_, i) in off {
                if !taken.iter().any(|&k| k.abs_diff(i) == 1) {
                    taken.push(i);
                }
            }
            taken.sort_unstable();
            out.extend(taken.into_iter().map(|i| (j, i)));
        }
        out
    }

    /// Drops the spikes of `t` (x and y to NaN); returns how many.
    pub fn drop(&self, t: &mut Tracks) -> usize {
        let spikes = self.find(t);
        t.drop_points(&spikes);
        spikes.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::walker;

    #[test]
    fn a_toe_ahead_for_one_frame_is_dropped_and_nothing_else() {
        let clean = walker(30.0, 120, |i| 100.0 + 13.0 * i as f64);
        assert!(SpikeRule::default().find(&clean).is_empty());
        let mut t = clean.clone();
        let toe = t.index("right_toe").unwrap();
        let leg = t.leg_length();
        t.x[toe][50] += 0.25 * leg;
        assert_eq!(SpikeRule::default().drop(&mut t), 1);
        assert!(t.x[toe][50].is_nan() && t.x[toe][49].is_finite());
    }

    #[test]
    fn a_spike_does_not_take_its_neighbour_with_it() {
        let mut t = walker(30.0, 120, |i| 100.0 + 13.0 * i as f64);
        let heel = t.index("left_heel").unwrap();
        let leg = t.leg_length();
        // Far enough off that the good sample before it also lies beyond the limit from the
        // midpoint of its neighbours.
        t.x[heel][60] += 0.45 * leg;
        let found = SpikeRule::default().find(&t);
        assert_eq!(found, vec![(heel, 60)]);
    }
}
