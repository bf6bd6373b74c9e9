//! Keypoints and the canonical keypoint naming shared by all pose models.

use serde::{Deserialize, Serialize};

/// The canonical keypoint names, in output order. Every pose estimator maps
/// its native keypoints onto these (missing ones stay empty) and may append
/// its extra native keypoints after them.
pub const CANONICAL: [&str; 15] = [
    "nose",
    "neck",
    "left_shoulder",
    "right_shoulder",
    "mid_hip",
    "left_hip",
    "right_hip",
    "left_knee",
    "right_knee",
    "left_ankle",
    "right_ankle",
    "left_heel",
    "right_heel",
    "left_toe",
    "right_toe",
];

/// The lower-limb keypoints of [`CANONICAL`]: what the kinematics and the
/// selective regeneration look at.
pub const LOWER_LIMB: [&str; 10] = [
    "left_hip",
    "right_hip",
    "left_knee",
    "right_knee",
    "left_ankle",
    "right_ankle",
    "left_heel",
    "right_heel",
    "left_toe",
    "right_toe",
];

/// Segments above the legs (head, shoulders, trunk, pelvis), by canonical
/// name; drawn with [`LEG_SEGMENTS`] as the skeleton.
pub const UPPER_SEGMENTS: [(&str, &str); 6] = [
    ("nose", "neck"),
    ("neck", "left_shoulder"),
    ("neck", "right_shoulder"),
    ("neck", "mid_hip"),
    ("mid_hip", "left_hip"),
    ("mid_hip", "right_hip"),
];

/// The segments joining [`LOWER_LIMB`]'s keypoints, leg by leg (thigh, shank,
/// and the foot's triangle): what leg masks and skeleton plots draw.
pub const LEG_SEGMENTS: [(&str, &str); 10] = [
    ("left_hip", "left_knee"),
    ("left_knee", "left_ankle"),
    ("left_ankle", "left_heel"),
    ("left_ankle", "left_toe"),
    ("left_heel", "left_toe"),
    ("right_hip", "right_knee"),
    ("right_knee", "right_ankle"),
    ("right_ankle", "right_heel"),
    ("right_ankle", "right_toe"),
    ("right_heel", "right_toe"),
];

/// A 2-D keypoint in pixel coordinates (x right, y down, the centre of pixel
/// (i, j) at (i, j)) with the model's likelihood in [0, 1].
///
/// A keypoint that was not found has NaN coordinates and likelihood 0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Keypoint {
    pub x: f64,
    pub y: f64,
    pub likelihood: f64,
}

impl Keypoint {
    pub fn new(x: f64, y: f64, likelihood: f64) -> Self {
        Self { x, y, likelihood }
    }

    /// The keypoint of a part that was not found.
    pub fn missing() -> Self {
        Self {
            x: f64::NAN,
            y: f64::NAN,
            likelihood: 0.0,
        }
    }

    /// True when the coordinates are finite.
    pub fn is_found(&self) -> bool {
        self.x.is_finite() && self.y.is_finite()
    }
}

/// Position of `name` in [`CANONICAL`].
pub fn canonical_index(name: &str) -> Option<usize> {
    CANONICAL.iter().position(|n| *n == name)
}
