//! Test pose plugin built with `export_pose_estimator!`. Well-behaved by
//! default; its options make it panic or return malformed keypoints so the
//! tests can check that the host turns both into errors.
//!
//! Output when well-behaved: for frame `f` (the `n`-th frame this instance
//! saw since creation or `reset`), keypoint `k` is `(k, f, 0.5)` except
//! `nose`, which is `(n, f, 1)`, and `right_toe`, which is missing. A 16th
//! keypoint `tail` follows the canonical ones.

use gait_core::{CANONICAL, Frame, Keypoint, Pose, PoseEstimator, StageContext, StageError};
use gait_plugin::PluginStage;
use serde::Deserialize;

#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Options {
    /// "create", "names" or "estimate": panic there.
    pub panic_in: String,
    /// "nan_x", "nan_likelihood", "inf_y", "missing_with_likelihood" or
    /// "short": return that kind of bad keypoint (or poses too short).
    pub bad: String,
}

pub struct TestingPose {
    options: Options,
    seen: usize,
}

impl PluginStage for TestingPose {
    type Options = Options;

    fn create(options: Options, _ctx: &StageContext) -> Result<Self, StageError> {
        if options.panic_in == "create" {
            panic!("testing-pose was asked to panic in create");
        }
        Ok(Self { options, seen: 0 })
    }
}

impl PoseEstimator for TestingPose {
    fn keypoint_names(&self) -> Vec<String> {
        if self.options.panic_in == "names" {
            panic!("testing-pose was asked to panic in keypoint_names");
        }
        CANONICAL
            .iter()
            .map(|s| s.to_string())
            .chain(["tail".to_string()])
            .collect()
    }

    fn estimate(&mut self, frames: &[Frame]) -> Result<Vec<Pose>, StageError> {
        if self.options.panic_in == "estimate" {
            let empty: Vec<u8> = Vec::new();
            // An out-of-bounds index: a real bug, not an explicit panic!.
            let _ = empty[frames.len()];
        }
        let mut poses = Vec::new();
        for frame in frames {
            let f = frame.index as f64;
            let mut keypoints: Vec<Keypoint> =
                (0..16).map(|k| Keypoint::new(k as f64, f, 0.5)).collect();
            keypoints[0] = Keypoint::new(self.seen as f64, f, 1.0);
            keypoints[14] = Keypoint::missing();
            match self.options.bad.as_str() {
                "nan_x" => keypoints[7].x = f64::NAN,
                "nan_likelihood" => keypoints[7].likelihood = f64::NAN,
                "inf_y" => keypoints[7].y = f64::INFINITY,
                "missing_with_likelihood" => keypoints[7] = Keypoint::new(f64::NAN, f64::NAN, 0.4),
                "short" => keypoints.truncate(14),
                _ => {}
            }
            self.seen += 1;
            poses.push(Pose { keypoints });
        }
        Ok(poses)
    }

    fn reset(&mut self) {
        self.seen = 0;
    }
}

gait_plugin::export_pose_estimator!(TestingPose);
