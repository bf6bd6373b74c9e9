//! The blur of the subject's legs in the frames the pose model saw, measured on the decoded
//! frames about six times a second (`gait_edge::blur_px` in a box round the leg keypoints).
//! The kinematics reject strides whose legs were too blurred for the model's keypoints
//! (`kinematics.cycle_max_blur_share`); run.json keeps the measures (`input.blur_px`) so that
//! `gait kin` on the run's keypoints judges alike.
//!
//! In every frame it also reads the contrast of each foot's outline along the rows
//! (`gait_edge::edge_contrast`), which the kinematics compare between the foot swinging and
//! standing to find motion blur (`kinematics.cycle_min_swing_contrast`, `input.feet_contrast`).

use std::collections::BTreeMap;

use gait_core::{Frame, Pose};
use gait_edge::{Region, blur_px, edge_contrast};
use gait_kin::FeetContrast;

/// Measures a frame in this many per second of video (a stride holds about six): enough for a
/// stride's median, at about 3 ms a measure at 1080p.
const PER_SECOND: f64 = 6.0;
/// The box round the leg keypoints grows by this share of its height on every side, so the
/// feet's and thighs' outlines are inside.
const MARGIN: f64 = 0.15;
/// Leg keypoints at least this likely make the box.
const MIN_LIKELIHOOD: f64 = 0.5;
/// A foot's box (ankle, heel, toe) grows by this share of the foot's length on every side, so
/// its outline is inside, and is at least this many pixels long.
const FOOT_MARGIN: f64 = 0.3;
const MIN_FOOT_PX: f64 = 10.0;

/// The blur measured so far, per frame index.
pub(crate) struct Sharpness {
    /// Columns of the leg keypoints (hips down) in the poses.
    legs: Vec<usize>,
    /// Per side (left, right), the columns of its ankle, heel and toe that the model has.
    feet: [Vec<usize>; 2],
    first: usize,
    every: usize,
    pub(crate) blur_px: BTreeMap<usize, f64>,
    pub(crate) feet_contrast: FeetContrast,
}

impl Sharpness {
    /// For poses with keypoints `names` of a video at `fps` whose range starts at `first`.
    pub(crate) fn new(names: &[String], fps: f64, first: usize) -> Self {
        let leg_part = ["hip", "knee", "ankle", "heel", "toe", "foot"];
        Self {
            legs: (0..names.len())
                .filter(|&i| leg_part.iter().any(|p| names[i].contains(p)))
                .collect(),
            feet: ["left", "right"].map(|side| {
                ["ankle", "heel", "toe"]
                    .iter()
                    .filter_map(|p| names.iter().position(|n| *n == format!("{side}_{p}")))
                    .collect()
            }),
            first,
            every: ((fps / PER_SECOND).round() as usize).max(1),
            blur_px: BTreeMap::new(),
            feet_contrast: BTreeMap::new(),
        }
    }

    /// Measures the frames of a batch that fall on the sampling grid and show the legs.
    pub(crate) fn measure(&mut self, frames: &[Frame], poses: &[Pose]) {
        for (frame, pose) in frames.iter().zip(poses) {
            self.measure_feet(frame, pose);
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

    /// Each foot's outline contrast in `frame`, where the model has two of its ankle, heel
    /// and toe.
    fn measure_feet(&mut self, frame: &Frame, pose: &Pose) {
        if frame.index < self.first || self.feet_contrast.contains_key(&frame.index) {
            return;
        }
        let read: [Option<f64>; 2] =
            std::array::from_fn(|k| foot_contrast(&self.feet[k], frame, pose));
        if read.iter().any(Option::is_some) {
            self.feet_contrast.insert(frame.index, read);
        }
    }

    /// The box round the likely leg keypoints, with its margin, clipped to the frame.
    fn legs_box(&self, pose: &Pose, frame: &Frame) -> Option<Region> {
        let seen: Vec<(f64, f64)> = likely(pose, &self.legs).collect();
        if seen.len() < 4 {
            return None;
        }
        let (y0, y1) = seen
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p.1), hi.max(p.1))
            });
        around(&seen, MARGIN * (y1 - y0), frame)
    }
}

/// The outline contrast of the foot whose keypoints are the columns `foot`, in a box round
/// them grown by [`FOOT_MARGIN`] of the foot's length; `None` with fewer than two seen.
fn foot_contrast(foot: &[usize], frame: &Frame, pose: &Pose) -> Option<f64> {
    let seen: Vec<(f64, f64)> = likely(pose, foot).collect();
    if seen.len() < 2 {
        return None;
    }
    let length = seen
        .iter()
        .flat_map(|a| seen.iter().map(move |b| (a.0 - b.0).hypot(a.1 - b.1)))
        .fold(MIN_FOOT_PX, f64::max);
    edge_contrast(&frame.image, around(&seen, FOOT_MARGIN * length, frame)?)
}

/// The keypoints of columns `columns` that are likely and finite.
fn likely<'a>(pose: &'a Pose, columns: &'a [usize]) -> impl Iterator<Item = (f64, f64)> + 'a {
    columns
        .iter()
        .map(|&i| pose.keypoints[i])
        .filter(|k| k.likelihood >= MIN_LIKELIHOOD && k.x.is_finite() && k.y.is_finite())
        .map(|k| (k.x, k.y))
}

/// The box round `points` grown by `margin` on every side, clipped to the frame; `None` when
/// under 9 pixels wide or high.
fn around(points: &[(f64, f64)], margin: f64, frame: &Frame) -> Option<Region> {
    let lo = |f: fn(&(f64, f64)) -> f64| points.iter().map(f).fold(f64::INFINITY, f64::min);
    let hi = |f: fn(&(f64, f64)) -> f64| points.iter().map(f).fold(f64::NEG_INFINITY, f64::max);
    let (x0, x1, y0, y1) = (lo(|p| p.0), hi(|p| p.0), lo(|p| p.1), hi(|p| p.1));
    let clip = |v: f64, max: u32| v.clamp(0.0, f64::from(max)) as u32;
    let region = Region {
        x0: clip(x0 - margin, frame.width()),
        y0: clip(y0 - margin, frame.height()),
        x1: clip(x1 + margin, frame.width()),
        y1: clip(y1 + margin, frame.height()),
    };
    (region.x1 > region.x0 + 8 && region.y1 > region.y0 + 8).then_some(region)
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

    /// Every frame's feet are read where the model has an ankle and a heel or toe: a sharp
    /// edge of 170 grey levels reads 85 per pixel; a foot without them is `None`.
    #[test]
    fn reads_each_foot_in_every_frame() {
        let names: Vec<String> = ["left_ankle", "left_heel", "left_toe", "right_ankle"]
            .map(String::from)
            .to_vec();
        let mut s = Sharpness::new(&names, 30.0, 3);
        let at = |x, y| Keypoint::new(x, y, 0.9);
        let foot = Pose {
            keypoints: vec![
                at(95.0, 150.0),
                at(90.0, 160.0),
                at(110.0, 160.0),
                at(150.0, 150.0),
            ],
        };
        let frames: Vec<Frame> = (3..8).map(frame).collect();
        s.measure(&frames, &vec![foot; frames.len()]);
        assert_eq!(s.feet_contrast.len(), 5, "{:?}", s.feet_contrast);
        assert!(
            s.feet_contrast
                .values()
                .all(|[l, r]| l.is_some_and(|c| (c - 85.0).abs() < 1.0) && r.is_none()),
            "{:?}",
            s.feet_contrast
        );
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
