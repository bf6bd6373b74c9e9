use serde::{Deserialize, Serialize};

use crate::Keypoint;

/// One person's keypoints in one frame, in the order of the estimator's
/// `keypoint_names()`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    pub keypoints: Vec<Keypoint>,
}

impl Pose {
    /// A pose with `n` missing keypoints (no person found).
    pub fn empty(n: usize) -> Self {
        Self {
            keypoints: vec![Keypoint::missing(); n],
        }
    }
}

/// Poses of one person over a video, with the names of the keypoints and the
/// frame rate needed to turn frames into time.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseSequence {
    pub fps: f64,
    pub names: Vec<String>,
    /// Frame index in the input of each pose (usually 0, 1, 2, ...).
    pub frames: Vec<usize>,
    pub poses: Vec<Pose>,
}

impl PoseSequence {
    /// Column of keypoint `name`, if the sequence has it.
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// The trajectory of keypoint `name` over all frames.
    pub fn track(&self, name: &str) -> Option<Vec<Keypoint>> {
        let i = self.index_of(name)?;
        Some(self.poses.iter().map(|p| p.keypoints[i]).collect())
    }

    pub fn len(&self) -> usize {
        self.poses.len()
    }

    pub fn is_empty(&self) -> bool {
        self.poses.is_empty()
    }
}
