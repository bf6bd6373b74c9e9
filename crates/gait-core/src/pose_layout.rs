//! Native keypoint layouts of pose models and their mapping onto the
//! canonical names: shared by the built-in estimators and by stages written
//! outside gait (Python), so equal layouts give equal columns.

use crate::keypoint::{CANONICAL, Keypoint};
use crate::openpose_layout::COCO_18;

/// BlazePose's 33 landmark names, in model order.
pub const BLAZEPOSE_33: [&str; 33] = [
    "nose",
    "left_eye_inner",
    "left_eye",
    "left_eye_outer",
    "right_eye_inner",
    "right_eye",
    "right_eye_outer",
    "left_ear",
    "right_ear",
    "mouth_left",
    "mouth_right",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_wrist",
    "right_wrist",
    "left_pinky",
    "right_pinky",
    "left_index",
    "right_index",
    "left_thumb",
    "right_thumb",
    "left_hip",
    "right_hip",
    "left_knee",
    "right_knee",
    "left_ankle",
    "right_ankle",
    "left_heel",
    "right_heel",
    "left_foot_index",
    "right_foot_index",
];

/// The 17 COCO keypoints (ViTPose, RTMPose, YOLO-pose, Detectron2), in order.
pub const COCO_17: [&str; 17] = [
    "nose",
    "left_eye",
    "right_eye",
    "left_ear",
    "right_ear",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_wrist",
    "right_wrist",
    "left_hip",
    "right_hip",
    "left_knee",
    "right_knee",
    "left_ankle",
    "right_ankle",
];

/// BlazePose calls the toe "foot index".
const BLAZEPOSE_ALIASES: [(&str, &str); 2] = [
    ("left_toe", "left_foot_index"),
    ("right_toe", "right_foot_index"),
];

/// A layout a pose model outside gait may declare for what it returns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PoseLayout {
    Blazepose33,
    Coco17,
    Coco18,
}

impl PoseLayout {
    /// Every layout, with the name a stage declares it by.
    pub const ALL: [(&'static str, PoseLayout); 3] = [
        ("blazepose33", PoseLayout::Blazepose33),
        ("coco17", PoseLayout::Coco17),
        ("coco18", PoseLayout::Coco18),
    ];

    /// The layout declared as `name` (e.g. "coco17").
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.iter().find(|(n, _)| *n == name).map(|(_, l)| *l)
    }

    /// Native keypoint names in model order.
    pub fn native(self) -> &'static [&'static str] {
        match self {
            PoseLayout::Blazepose33 => &BLAZEPOSE_33,
            PoseLayout::Coco17 => &COCO_17,
            PoseLayout::Coco18 => &COCO_18,
        }
    }

    /// Output names: the canonical ones, then the native ones prefixed as
    /// the built-in estimator of that layout names them (`bp_`, `op_`).
    pub fn names(self) -> Vec<String> {
        let prefix = match self {
            PoseLayout::Blazepose33 => "bp_",
            PoseLayout::Coco17 => "coco_",
            PoseLayout::Coco18 => "op_",
        };
        with_native_names(self.native(), prefix)
    }

    /// Keypoints in output order from native-order keypoints.
    pub fn to_keypoints(self, native: &[Keypoint]) -> Vec<Keypoint> {
        let aliases: &[(&str, &str)] = match self {
            PoseLayout::Blazepose33 => &BLAZEPOSE_ALIASES,
            _ => &[],
        };
        to_canonical(self.native(), native, aliases)
    }
}

/// The canonical names, then `prefix` + each native name.
pub fn with_native_names(native: &[&str], prefix: &str) -> Vec<String> {
    CANONICAL
        .iter()
        .map(|s| s.to_string())
        .chain(native.iter().map(|n| format!("{prefix}{n}")))
        .collect()
}

/// The canonical keypoints, then `native` unchanged. A canonical keypoint is
/// the native one of the same name (or of its alias); the neck and mid-hip a
/// layout lacks are the midpoints of the shoulders and hips; others stay missing.
pub fn to_canonical(
    layout: &[&str],
    native: &[Keypoint],
    aliases: &[(&str, &str)],
) -> Vec<Keypoint> {
    let at = |name: &str| {
        let name = aliases
            .iter()
            .find(|(canonical, _)| *canonical == name)
            .map_or(name, |(_, native_name)| native_name);
        layout
            .iter()
            .position(|n| *n == name)
            .and_then(|i| native.get(i).copied())
    };
    let between = |a: &str, b: &str| match (at(a), at(b)) {
        (Some(a), Some(b)) => midpoint(a, b),
        _ => Keypoint::missing(),
    };
    let canonical = CANONICAL.iter().map(|&name| match at(name) {
        Some(k) => k,
        None if name == "neck" => between("left_shoulder", "right_shoulder"),
        None if name == "mid_hip" => between("left_hip", "right_hip"),
        None => Keypoint::missing(),
    });
    canonical.chain(native.iter().copied()).collect()
}

/// Midpoint of two keypoints with the lower likelihood; missing unless both are found.
fn midpoint(a: Keypoint, b: Keypoint) -> Keypoint {
    if !a.is_found() || !b.is_found() {
        return Keypoint::missing();
    }
    Keypoint::new(
        (a.x + b.x) / 2.0,
        (a.y + b.y) / 2.0,
        a.likelihood.min(b.likelihood),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn numbered(n: usize) -> Vec<Keypoint> {
        (0..n)
            .map(|i| Keypoint::new(i as f64, 10.0 * i as f64, 0.5 + i as f64 / 100.0))
            .collect()
    }

    #[test]
    fn blazepose_toes_are_foot_index_and_neck_is_between_the_shoulders() {
        let kp = PoseLayout::Blazepose33.to_keypoints(&numbered(33));
        let names = PoseLayout::Blazepose33.names();
        let get = |n: &str| kp[names.iter().position(|x| x == n).unwrap()];
        assert_eq!(get("left_toe"), get("bp_left_foot_index"));
        assert_eq!(get("neck").x, 11.5);
        assert_eq!(get("neck").likelihood, 0.61);
        assert_eq!(names.len(), 15 + 33);
        assert_eq!(names[15], "bp_nose");
    }

    #[test]
    fn coco17_has_no_feet_and_derives_neck_and_mid_hip() {
        let kp = PoseLayout::Coco17.to_keypoints(&numbered(17));
        let names = PoseLayout::Coco17.names();
        let get = |n: &str| kp[names.iter().position(|x| x == n).unwrap()];
        assert!(!get("left_heel").is_found() && !get("right_toe").is_found());
        assert_eq!(get("mid_hip").x, 11.5);
        assert_eq!(get("neck").y, 55.0);
        assert_eq!(get("right_ankle"), get("coco_right_ankle"));
    }

    #[test]
    fn a_missing_hip_leaves_mid_hip_missing() {
        let mut native = numbered(18);
        native[8] = Keypoint::missing();
        let kp = PoseLayout::Coco18.to_keypoints(&native);
        assert!(!kp[4].is_found());
        assert_eq!(PoseLayout::parse("coco18"), Some(PoseLayout::Coco18));
        assert_eq!(PoseLayout::parse("coco"), None);
    }
}
