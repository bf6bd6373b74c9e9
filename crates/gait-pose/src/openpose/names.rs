//! OpenPose keypoints mapped to the canonical names.

use gait_core::Keypoint;
use gait_core::pose_layout::{to_canonical, with_native_names};

use super::OpenposeModel;

/// Output names: the canonical ones, then `op_<name>` for every keypoint of
/// the model in its own order.
pub fn keypoint_names(model: OpenposeModel) -> Vec<String> {
    with_native_names(model.keypoints(), "op_")
}

/// Keypoints in output order from the model-order detections of one person
/// (`None` = not found). Canonical keypoints the model lacks (COCO-18 has no
/// heels or toes) stay missing rather than being guessed; COCO-18's mid-hip
/// is the midpoint of the hips.
pub fn to_keypoints(model: OpenposeModel, found: &[Option<[f32; 3]>]) -> Vec<Keypoint> {
    let layout = model.keypoints();
    let native: Vec<Keypoint> = (0..layout.len())
        .map(|i| match found.get(i).copied().flatten() {
            Some([x, y, s]) => Keypoint::new(x as f64, y as f64, s as f64),
            None => Keypoint::missing(),
        })
        .collect();
    to_canonical(layout, &native, &[])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coco_has_no_feet_and_a_derived_mid_hip() {
        let m = OpenposeModel::Coco18;
        let mut found = vec![None; 18];
        found[8] = Some([10.0, 20.0, 0.9]); // right hip
        found[11] = Some([14.0, 20.0, 0.7]); // left hip
        found[10] = Some([11.0, 40.0, 0.8]); // right ankle
        let kp = to_keypoints(m, &found);
        let names = keypoint_names(m);
        assert_eq!(kp.len(), names.len());
        let at = |n: &str| kp[names.iter().position(|x| x == n).unwrap()];
        assert_eq!((at("mid_hip").x, at("mid_hip").y), (12.0, 20.0));
        assert_eq!(at("mid_hip").likelihood, 0.7f32 as f64);
        assert_eq!(at("right_ankle").x, 11.0);
        for n in [
            "left_heel",
            "right_heel",
            "left_toe",
            "right_toe",
            "left_knee",
        ] {
            assert!(!at(n).is_found(), "{n}");
        }
        assert_eq!(at("op_right_ankle"), at("right_ankle"));
    }

    #[test]
    fn body25_feet_are_canonical() {
        let m = OpenposeModel::Body25;
        let mut found = vec![None; 25];
        found[24] = Some([5.0, 6.0, 0.5]); // right heel
        found[19] = Some([7.0, 8.0, 0.6]); // left big toe
        let kp = to_keypoints(m, &found);
        let names = keypoint_names(m);
        let at = |n: &str| kp[names.iter().position(|x| x == n).unwrap()];
        assert_eq!(at("right_heel").x, 5.0);
        assert_eq!(at("left_toe").y, 8.0);
        assert!(!at("mid_hip").is_found());
    }
}
