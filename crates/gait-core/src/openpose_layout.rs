//! Keypoint orders of OpenPose's body models, in canonical names where one
//! exists; shared by the OpenPose estimator and the OpenPose JSON reader.

/// BODY_25 keypoints, mapped to canonical names where one exists (the big toe
/// is the canonical toe); others keep a descriptive name.
pub const BODY_25: [&str; 25] = [
    "nose",
    "neck",
    "right_shoulder",
    "right_elbow",
    "right_wrist",
    "left_shoulder",
    "left_elbow",
    "left_wrist",
    "mid_hip",
    "right_hip",
    "right_knee",
    "right_ankle",
    "left_hip",
    "left_knee",
    "left_ankle",
    "right_eye",
    "left_eye",
    "right_ear",
    "left_ear",
    "left_toe",
    "left_small_toe",
    "left_heel",
    "right_toe",
    "right_small_toe",
    "right_heel",
];

/// COCO-18 keypoints (OpenPose's COCO model), mapped like [`BODY_25`].
pub const COCO_18: [&str; 18] = [
    "nose",
    "neck",
    "right_shoulder",
    "right_elbow",
    "right_wrist",
    "left_shoulder",
    "left_elbow",
    "left_wrist",
    "right_hip",
    "right_knee",
    "right_ankle",
    "left_hip",
    "left_knee",
    "left_ankle",
    "right_eye",
    "left_eye",
    "right_ear",
    "left_ear",
];
