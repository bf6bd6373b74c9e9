//! BlazePose's 33 landmark names and their mapping to the canonical keypoints.

use gait_core::{CANONICAL, Keypoint};

use super::landmarks::Landmark;

/// Native landmark names, in model order.
pub const NATIVE: [&str; 33] = [
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

/// Source of each canonical keypoint: one landmark or the midpoint of two.
fn source(name: &str) -> (usize, Option<usize>) {
    match name {
        "neck" => (11, Some(12)),
        "mid_hip" => (23, Some(24)),
        "left_toe" => (31, None),
        "right_toe" => (32, None),
        other => (NATIVE.iter().position(|n| *n == other).unwrap_or(0), None),
    }
}

/// Output names: the canonical ones, then `bp_<native>` for all 33.
pub fn keypoint_names() -> Vec<String> {
    CANONICAL
        .iter()
        .map(|s| s.to_string())
        .chain(NATIVE.iter().map(|n| format!("bp_{n}")))
        .collect()
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
    let canonical = CANONICAL.iter().map(|name| {
        let (a, b) = source(name);
        match b {
            None => native[a],
            Some(b) => Keypoint::new(
                (native[a].x + native[b].x) / 2.0,
                (native[a].y + native[b].y) / 2.0,
                native[a].likelihood.min(native[b].likelihood),
            ),
        }
    });
    canonical.chain(native.iter().copied()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_canonical_name_has_a_source() {
        for name in CANONICAL {
            let (a, b) = source(name);
            assert!(
                NATIVE[a] == name || b.is_some() || name.ends_with("_toe"),
                "{name}"
            );
        }
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
