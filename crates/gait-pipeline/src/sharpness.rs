//! The blur of the subject's legs in the frames the pose model saw, measured on the decoded
//! frames about six times a second (`gait_edge::blur_px` in a box round the leg keypoints).
//! The kinematics reject strides whose legs were too blurred for the model's keypoints
//! (`kinematics.cycle_max_blur_share`); run.json keeps the measures (`input.blur_px`) so that
//! `gait kin` on the run's keypoints judges alike.

use std::collections::BTreeMap;

use gait_core::{Frame, Pose};
use gait_edge::{Region, blur_px};

/// Measures a frame in this many per second of video (a stride holds about six): enough for a
/// stride's median, at about 3 ms a measure at 1080p.
const PER_SECOND: f64 = 6.0;
/// The box round the leg keypoints grows by this share of its height on every side, so the
/// feet's and thighs' outlines are inside.
const MARGIN: f64 = 0.15;
/// Leg keypoints at least this likely make the box.
const MIN_LIKELIHOOD: f64 = 0.5;

/// The blur measured so far, per frame index.
pub(crate) struct Sharpness {
    /// Columns of the leg keypoints (hips down) in the poses.
    legs: Vec<usize>,
    first: usize,
    every: usize,
    pub(crate) blur_px: BTreeMap<usize, f64>,
}

impl Sharpness {
    /// For poses with keypoints `names` of a video at `fps` whose range starts at `first`.
    pub(crate) fn new(names: &[String], fps: f64, first: usize) -> Self {
        let leg_part = ["hip", "knee", "ankle", "heel", "toe", "foot"];
        Self {
            legs: (0..names.len())
                .filter(|&i| leg_part.iter().any(|p| names[i].contains(p)))
                .collect(),
            first,
            every: ((fps / PER_SECOND).round() as usize).max(1),
            blur_px: BTreeMap::new(),
        }
    }

    /// Measures the frames of a batch that fall on the sampling grid and show the legs.
    pub(crate) fn measure(&mut self, frames: &[Frame], poses: &[Pose]) {
        for (frame, pose) in frames.iter().zip(poses) {
            let on_grid =
                frame.index >= self.first && (frame.index - self.first).is_multiple_of(self.every);
            if !on_grid || self.blur_px.contains_key(&frame.index) {
                continue;
            }
            let Some(region) = self.legs_box(pose, frame) else {
                continue;
            };
            if let Some(b) = blur_px(&frame.image, region) {
                self.blur_px.insert(frame.index, b);
            }
        }
    }

    /// The box round the likely leg keypoints, with its margin, clipped to the frame.
    fn legs_box(&self, pose: &Pose, frame: &Frame) -> Option<Region> {
        let seen: Vec<(f64, f64)> = self
            .legs
            .iter()
            .map(|&i| pose.keypoints[i])
            .filter(|k| k.likelihood >= MIN_LIKELIHOOD && k.x.is_finite() && k.y.is_finite())
            .map(|k| (k.x, k.y))
            .collect();
        if seen.len() < 4 {
            return None;
        }
        let lo = |f: fn(&(f64, f64)) -> f64| seen.iter().map(f).fold(f64::INFINITY, f64::min);
        let hi = |f: fn(&(f64, f64)) -> f64| seen.iter().map(f).fold(f64::NEG_INFINITY, f64::max);
        let (x0, x1, y0, y1) = (lo(|p| p.0), hi(|p| p.0), lo(|p| p.1), hi(|p| p.1));
        let m = MARGIN * (y1 - y0);
        let clip = |v: f64, max: u32| v.clamp(0.0, f64::from(max)) as u32;
        let region = Region {
            x0: clip(x0 - m, frame.width()),
            y0: clip(y0 - m, frame.height()),
            x1: clip(x1 + m, frame.width()),
            y1: clip(y1 + m, frame.height()),
        };
        (region.x1 > region.x0 + 8 && region.y1 > region.y0 + 8).then_some(region)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use gait_core::Keypoint;

    fn names() -> Vec<String> {
        [
            "nose",
            "left_hip",
            "right_hip",
            "left_knee",
            "right_knee",
            "left_ankle",
        ]
        .map(String::from)
        .to_vec()
    }

    /// A frame with a sharp dark bar where the legs are.
    fn frame(index: usize) -> Frame {
        Frame::new(
            index,
            image::RgbImage::from_fn(200, 200, |x, y| {
                let v = if (90..110).contains(&x) && (60..160).contains(&y) {
                    30
                } else {
                    200
                };
                image::Rgb([v, v, v])
            }),
        )
    }

    fn pose(likelihood: f64) -> Pose {
        let at = |x, y| Keypoint::new(x, y, likelihood);
        Pose {
            keypoints: vec![
                at(100.0, 20.0),
                at(95.0, 60.0),
                at(105.0, 60.0),
                at(95.0, 110.0),
                at(105.0, 110.0),
                at(100.0, 160.0),
            ],
        }
    }

    #[test]
    fn measures_grid_frames_with_legs_only() {
        let mut s = Sharpness::new(&names(), 30.0, 3);
        let frames: Vec<Frame> = (3..14).map(frame).collect();
        let mut poses = vec![pose(0.9); frames.len()];
        poses[5] = pose(0.1); // frame 8: legs unsure
        s.measure(&frames, &poses);
        // Every 5th frame from 3: 3, 8, 13; frame 8 has no likely legs.
        assert_eq!(s.blur_px.keys().copied().collect::<Vec<_>>(), vec![3, 13]);
        assert!(s.blur_px.values().all(|b| *b < 1.5), "{:?}", s.blur_px);
    }
}
