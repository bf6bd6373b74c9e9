//! Heels and toes drawn where the foot cannot be.
//!
//! The foot is nearly rigid from the ankle to the heel and to the toes (which flex a little at
//! push-off), and in a side view it turns in the image plane, so its image distances from the
//! ankle stay nearly constant.
//! A pose model that loses the far foot behind the near leg draws heel and toe tens of pixels
//! away from it for a frame or two while the ankle stays put, and in which frames it does so
//! changes with the encoding: on the bundled sample's CRF 18 copy the right toe stood 0.14-0.19
//! leg lengths off its usual distance from the ankle in frames 84 and 86, next to its toe-off,
//! and the toe-off came two frames early. Such a heel or toe is dropped and the gap filler
//! bridges it. The ankle is the reference because the foot hangs from it and the shank holds
//! it in place: in those frames it is where the original's is.

use crate::config::Side;
use crate::tracks::{Tracks, dist, median};

/// The foot-shape test: a heel or toe whose distance from its ankle differs from its median
/// over the surrounding `window_s` seconds by more than `tolerance` leg lengths.
#[derive(Debug, Clone)]
pub struct FootShapeRule {
    pub tolerance: f64,
    pub window_s: f64,
}

impl Default for FootShapeRule {
    fn default() -> Self {
        // Over the sample's walk the original's heels and toes stay within 0.09 leg lengths of
        // their usual distance (95 % within 0.06; the near toe flexes at push-off), the
        // misplaced far toes of its copies are 0.14-0.19 off. Chosen on the robustness matrix
        // (BENCHMARKS.md): 0.08 and 0.1 held 9 of 16 variants, 0.12 held 10, 0.15 let the CRF
        // 18 copy's toes through (9). The window follows a walker whose size changes.
        Self {
            tolerance: 0.12,
            window_s: 1.0,
        }
    }
}

impl FootShapeRule {
    /// `(keypoint, frame)` of each heel or toe too far from its usual distance to the ankle.
    pub fn find(&self, t: &Tracks) -> Vec<(usize, usize)> {
        let leg = t.leg_length();
        if !(leg.is_finite() && leg > 0.0) {
            return Vec::new();
        }
        let mut out = Vec::new();
        for side in Side::BOTH {
            let Some(ankle) = t.seen_leg_index(side, "ankle") else {
                continue;
            };
            for part in ["heel", "toe"] {
                if let Some(j) = t.seen_leg_index(side, part) {
                    out.extend(self.misplaced(t, ankle, j, leg).map(|i| (j, i)));
                }
            }
        }
        out
    }

    /// Frames where point `j` lies too far from its usual distance to `ankle`.
    fn misplaced(
        &self,
        t: &Tracks,
        ankle: usize,
        j: usize,
        leg: f64,
    ) -> impl Iterator<Item = usize> {
        let n = t.len();
        let d: Vec<f64> = (0..n)
            .map(|i| match (t.at(ankle, i), t.at(j, i)) {
                (Some(a), Some(p)) => dist(a, p),
                _ => f64::NAN,
            })
            .collect();
        let w = (self.window_s * t.fps).round().max(1.0) as usize;
        let limit = self.tolerance * leg;
        (0..n).filter(move |&i| {
            d[i].is_finite() && {
                let mut around = d[i.saturating_sub(w)..(i + w + 1).min(n)].to_vec();
                (d[i] - median(&mut around)).abs() > limit
            }
        })
    }

    /// Drops the misplaced heels and toes of `t` (x and y to NaN); returns how many.
    pub fn drop(&self, t: &mut Tracks) -> usize {
        let found = self.find(t);
        t.drop_points(&found);
        found.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::walker;

    #[test]
    fn a_toe_drawn_away_from_its_ankle_is_dropped_and_nothing_else() {
        let clean = walker(30.0, 120, |i| 100.0 + 13.0 * i as f64);
        assert!(FootShapeRule::default().find(&clean).is_empty());
        let mut t = clean.clone();
        let (toe, heel) = (
            t.index("right_toe").unwrap(),
            t.index("right_heel").unwrap(),
        );
        let leg = t.leg_length();
        // Heel and toe moved together, away from the ankle that stays put.
        for j in [toe, heel] {
            t.y[j][50] += 0.25 * leg;
        }
        assert_eq!(FootShapeRule::default().drop(&mut t), 2);
        assert!(t.x[toe][50].is_nan() && t.x[heel][50].is_nan());
        assert!(t.x[toe][49].is_finite() && t.x[toe][51].is_finite());
    }
}
