//! Keypoint trajectories on a dense frame timeline, the working form of a [`PoseSequence`].

use gait_core::{Keypoint, Pose, PoseSequence};

use crate::config::Side;

/// Per keypoint: x, y and likelihood over every frame from `first_frame` on (NaN = missing).
#[derive(Debug, Clone)]
pub struct Tracks {
    pub fps: f64,
    pub first_frame: usize,
    pub names: Vec<String>,
    pub x: Vec<Vec<f64>>,
    pub y: Vec<Vec<f64>>,
    pub likelihood: Vec<Vec<f64>>,
}

/// The lower-limb segments of one leg, proximal to distal.
pub const LEG: [&str; 5] = ["hip", "knee", "ankle", "heel", "toe"];

/// The parts of [`LEG`] below the hip.
pub const LOWER_LEG: [&str; 4] = ["knee", "ankle", "heel", "toe"];

impl Tracks {
    /// Lays the poses out on `frames[0]..=frames[last]`; frames absent from the input are missing.
    pub fn from_sequence(seq: &PoseSequence) -> Self {
        let first = seq.frames.iter().copied().min().unwrap_or(0);
        let last = seq.frames.iter().copied().max().unwrap_or(0);
        let len = if seq.frames.is_empty() {
            0
        } else {
            last - first + 1
        };
        let k = seq.names.len();
        let mut t = Self {
            fps: seq.fps,
            first_frame: first,
            names: seq.names.clone(),
            x: vec![vec![f64::NAN; len]; k],
            y: vec![vec![f64::NAN; len]; k],
            likelihood: vec![vec![0.0; len]; k],
        };
        for (frame, pose) in seq.frames.iter().zip(&seq.poses) {
            let i = frame - first;
            for (j, kp) in pose.keypoints.iter().enumerate().take(k) {
                if kp.is_found() {
                    t.x[j][i] = kp.x;
                    t.y[j][i] = kp.y;
                    t.likelihood[j][i] = if kp.likelihood.is_finite() {
                        kp.likelihood
                    } else {
                        0.0
                    };
                }
            }
        }
        t
    }

    /// Back to a sequence over the dense timeline.
    pub fn to_sequence(&self) -> PoseSequence {
        let len = self.len();
        let poses = (0..len)
            .map(|i| Pose {
                keypoints: (0..self.names.len())
                    .map(|j| {
                        let (x, y) = (self.x[j][i], self.y[j][i]);
                        if x.is_finite() && y.is_finite() {
                            Keypoint::new(x, y, self.likelihood[j][i])
                        } else {
                            Keypoint::missing()
                        }
                    })
                    .collect(),
            })
            .collect();
        PoseSequence {
            fps: self.fps,
            names: self.names.clone(),
            frames: (self.first_frame..self.first_frame + len).collect(),
            poses,
        }
    }

    pub fn len(&self) -> usize {
        self.x.first().map_or(0, Vec::len)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    pub fn index(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// Index of `{side}_{part}`, e.g. `left_knee`.
    pub fn leg_index(&self, side: Side, part: &str) -> Option<usize> {
        self.index(&format!("{}_{part}", side.name()))
    }

    /// As [`Self::leg_index`], only for a keypoint seen in some frame: a model without feet
    /// (COCO-17, COCO-18) has empty heel and toe columns in gait's own keypoints.csv, and a
    /// column that is there but never filled must not stand in for one the model gives.
    pub fn seen_leg_index(&self, side: Side, part: &str) -> Option<usize> {
        self.leg_index(side, part)
            .filter(|&j| self.x[j].iter().any(|v| v.is_finite()))
    }

    /// The point `j` at frame `i` when both coordinates are present.
    pub fn at(&self, j: usize, i: usize) -> Option<(f64, f64)> {
        let (x, y) = (*self.x.get(j)?.get(i)?, self.y[j][i]);
        (x.is_finite() && y.is_finite()).then_some((x, y))
    }

    /// Removes the points `(keypoint, frame)` (x and y to NaN), for the gap filler to bridge.
    pub fn drop_points(&mut self, points: &[(usize, usize)]) {
        for &(j, i) in points {
            self.x[j][i] = f64::NAN;
            self.y[j][i] = f64::NAN;
        }
    }

    /// Pelvis position: `mid_hip`, else the mean of the two hips.
    pub fn pelvis(&self, i: usize) -> Option<(f64, f64)> {
        if let Some(p) = self.index("mid_hip").and_then(|j| self.at(j, i)) {
            return Some(p);
        }
        let l = self
            .leg_index(Side::Left, "hip")
            .and_then(|j| self.at(j, i));
        let r = self
            .leg_index(Side::Right, "hip")
            .and_then(|j| self.at(j, i));
        match (l, r) {
            (Some(a), Some(b)) => Some(((a.0 + b.0) / 2.0, (a.1 + b.1) / 2.0)),
            (a, b) => a.or(b),
        }
    }

    /// Median over frames and sides of thigh + shank length in pixels (NaN when never seen).
    pub fn leg_length(&self) -> f64 {
        let mut lengths = Vec::new();
        for side in Side::BOTH {
            let idx = ["hip", "knee", "ankle"].map(|p| self.leg_index(side, p));
            let [Some(h), Some(k), Some(a)] = idx else {
                continue;
            };
            for i in 0..self.len() {
                if let (Some(h), Some(k), Some(a)) = (self.at(h, i), self.at(k, i), self.at(a, i)) {
                    lengths.push(dist(h, k) + dist(k, a));
                }
            }
        }
        median(&mut lengths)
    }
}

pub fn dist(a: (f64, f64), b: (f64, f64)) -> f64 {
    (a.0 - b.0).hypot(a.1 - b.1)
}

/// Median of the finite values (NaN when there are none).
pub fn median(v: &mut Vec<f64>) -> f64 {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dense_timeline_and_back() {
        let seq = PoseSequence {
            fps: 30.0,
            names: vec!["left_hip".into(), "right_hip".into()],
            frames: vec![3, 5],
            poses: vec![
                Pose {
                    keypoints: vec![Keypoint::new(1.0, 2.0, 0.9), Keypoint::new(3.0, 2.0, 0.8)],
                },
                Pose {
                    keypoints: vec![Keypoint::missing(), Keypoint::new(4.0, 4.0, 0.7)],
                },
            ],
        };
        let t = Tracks::from_sequence(&seq);
        assert_eq!((t.first_frame, t.len()), (3, 3));
        assert!(t.at(0, 1).is_none());
        assert_eq!(t.pelvis(0), Some((2.0, 2.0)));
        assert_eq!(t.pelvis(2), Some((4.0, 4.0)));
        let back = t.to_sequence();
        assert_eq!(back.frames, vec![3, 4, 5]);
        assert_eq!(back.poses[2].keypoints[1], Keypoint::new(4.0, 4.0, 0.7));
        assert_eq!(median(&mut vec![3.0, f64::NAN, 1.0, 2.0]), 2.0);
    }
}
