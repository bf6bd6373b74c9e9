//! Limbs (keypoint pairs joined by a part-affinity field) of each model.

use super::super::OpenposeModel;

/// A limb: keypoints `a` -> `b` and the PAF channels of its x and y components.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limb {
    pub a: usize,
    pub b: usize,
    pub paf_x: usize,
    pub paf_y: usize,
    /// Whether a connection of this limb may start a new person (false for
    /// the redundant shoulder-ear limbs, as controlnet_aux's `k < 17`).
    pub starts_person: bool,
}

const fn limb(a: usize, b: usize, paf_x: usize, paf_y: usize, starts_person: bool) -> Limb {
    Limb {
        a,
        b,
        paf_x,
        paf_y,
        starts_person,
    }
}

/// COCO-18, in controlnet_aux's order (`limbSeq` - 1, `mapIdx` - 19 of
/// `controlnet_aux/open_pose/body.py`; the same as OpenPose's COCO
/// `POSE_BODY_PART_PAIRS` / `POSE_MAP_INDEX`).
const COCO18: [Limb; 19] = [
    limb(1, 2, 12, 13, true),
    limb(1, 5, 20, 21, true),
    limb(2, 3, 14, 15, true),
    limb(3, 4, 16, 17, true),
    limb(5, 6, 22, 23, true),
    limb(6, 7, 24, 25, true),
    limb(1, 8, 0, 1, true),
    limb(8, 9, 2, 3, true),
    limb(9, 10, 4, 5, true),
    limb(1, 11, 6, 7, true),
    limb(11, 12, 8, 9, true),
    limb(12, 13, 10, 11, true),
    limb(1, 0, 28, 29, true),
    limb(0, 14, 30, 31, true),
    limb(14, 16, 34, 35, true),
    limb(0, 15, 32, 33, true),
    limb(15, 17, 36, 37, true),
    limb(2, 16, 18, 19, false),
    limb(5, 17, 26, 27, false),
];

/// BODY_25, from OpenPose's `src/openpose/pose/poseParameters.cpp`
/// (`POSE_BODY_PART_PAIRS` and `POSE_MAP_INDEX` for BODY_25); the
/// shoulder-ear limbs (2-17, 5-18) are the redundant ones.
const BODY25: [Limb; 26] = [
    limb(1, 8, 0, 1, true),
    limb(1, 2, 14, 15, true),
    limb(1, 5, 22, 23, true),
    limb(2, 3, 16, 17, true),
    limb(3, 4, 18, 19, true),
    limb(5, 6, 24, 25, true),
    limb(6, 7, 26, 27, true),
    limb(8, 9, 6, 7, true),
    limb(9, 10, 2, 3, true),
    limb(10, 11, 4, 5, true),
    limb(8, 12, 8, 9, true),
    limb(12, 13, 10, 11, true),
    limb(13, 14, 12, 13, true),
    limb(1, 0, 30, 31, true),
    limb(0, 15, 32, 33, true),
    limb(15, 17, 36, 37, true),
    limb(0, 16, 34, 35, true),
    limb(16, 18, 38, 39, true),
    limb(2, 17, 20, 21, false),
    limb(5, 18, 28, 29, false),
    limb(14, 19, 40, 41, true),
    limb(19, 20, 42, 43, true),
    limb(14, 21, 44, 45, true),
    limb(11, 22, 46, 47, true),
    limb(22, 23, 48, 49, true),
    limb(11, 24, 50, 51, true),
];

/// The limbs of `model`, in the order connections are assembled.
pub fn limbs(model: OpenposeModel) -> &'static [Limb] {
    match model {
        OpenposeModel::Coco18 => &COCO18,
        OpenposeModel::Body25 => &BODY25,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_paf_channel_is_used_once_and_keypoints_are_in_range() {
        for model in [OpenposeModel::Coco18, OpenposeModel::Body25] {
            let mut used = vec![0; model.paf_channels()];
            for l in limbs(model) {
                used[l.paf_x] += 1;
                used[l.paf_y] += 1;
                assert!(l.a < model.keypoints().len() && l.b < model.keypoints().len());
            }
            assert!(used.iter().all(|&u| u == 1), "{model:?}");
        }
    }
}
