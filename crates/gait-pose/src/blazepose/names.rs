//! BlazePose's 33 landmark names and their mapping to the canonical keypoints.

use gait_core::Keypoint;
use gait_core::pose_layout::PoseLayout;

use super::landmarks::Landmark;

/// Native landmark names, in model order.
pub use gait_core::pose_layout::BLAZEPOSE_33 as NATIVE;

/// Output names: the canonical ones, then `bp_<native>` for all 33.
pub fn keypoint_names() -> Vec<String> {
    PoseLayout::Blazepose33.names()
}

/// Keypoints in frame pixels (pixel centre = integer) from the 33 normalised
/// landmarks of a `width` x `height` frame.
pub fn to_keypoints(lm: &[Landmark], width: u32, height: u32) -> Vec<Keypoint> {
    let px = |l: &Landmark| {
        Keypoint::new(
            l.x as f64 * width as f64 - 0.5,
            l.y as f64 * height as f64 - 0.5,
            l.visibility as f64,
        )
    };
    let native: Vec<Keypoint> = lm.iter().take(33).map(px).collect();
    PoseLayout::Blazepose33.to_keypoints(&native)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_canonical_name_is_found() {
        let lm = vec![
            Landmark {
                x: 0.5,
                y: 0.5,
                visibility: 0.9
            };
            33
        ];
        assert!(to_keypoints(&lm, 10, 10).iter().all(|k| k.is_found()));
        assert_eq!(keypoint_names().len(), 15 + 33);
        assert_eq!(keypoint_names()[15], "bp_nose");
    }

    #[test]
    fn midpoints_take_the_lower_likelihood() {
        let mut lm = vec![
            Landmark {
                x: 0.0,
                y: 0.0,
                visibility: 0.9
            };
            33
        ];
        lm[23] = Landmark {
            x: 0.5,
            y: 0.5,
            visibility: 0.4,
        };
        let kp = to_keypoints(&lm, 100, 100);
        let mid = kp[4];
        assert!((mid.x - (49.5 - 0.5) / 2.0).abs() < 1e-9);
        assert_eq!(mid.likelihood, 0.4f32 as f64);
        assert_eq!(kp[13], kp[15 + 31]);
    }
}
