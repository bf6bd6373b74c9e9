//! The inpainting mask of `mode = "inpaint"`: the lower limbs of the pose
//! found on the original frame, drawn as capsules (thick segments) along
//! hip-knee-ankle-heel/toe, so only the legs are regenerated.

use gait_core::keypoint::canonical_index;
use gait_core::{Pose, Resize};
use serde::{Deserialize, Serialize};

/// The `[regenerator.mask]` table. A frame whose original-frame pose has no
/// leg segment (both ends found with `min_likelihood`) is handed on
/// unchanged, with a note in the run's warnings, rather than failing the run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LegMaskConfig {
    /// Keypoints below this likelihood are left out of the mask.
    pub min_likelihood: f64,
    /// Capsule radius as a fraction of the longest leg segment found
    /// (thigh or shank, usually), so the mask scales with the person.
    pub radius: f64,
    /// Put the frame's own pixels back outside the mask after decoding.
    /// diffusers leaves this to the user (the VAE round trip changes them
    /// slightly), so the default `false` matches diffusers.
    pub paste_back: bool,
}

impl Default for LegMaskConfig {
    fn default() -> Self {
        Self {
            min_likelihood: 0.3,
            radius: 0.35,
            paste_back: false,
        }
    }
}

impl LegMaskConfig {
    pub fn validate(&self) -> Result<(), String> {
        if !(0.0..=1.0).contains(&self.min_likelihood) {
            return Err(format!(
                "regenerator.mask.min_likelihood = {} must be in [0, 1]",
                self.min_likelihood
            ));
        }
        if !(self.radius > 0.0 && self.radius.is_finite()) {
            return Err(format!(
                "regenerator.mask.radius = {} must be positive",
                self.radius
            ));
        }
        Ok(())
    }
}

/// The legs of one pose as capsules in frame pixels.
#[derive(Debug, Clone, PartialEq)]
pub struct LegMask {
    segments: Vec<[(f64, f64); 2]>,
    radius: f64,
}

impl LegMask {
    /// The capsules of every leg segment whose two ends were found with
    /// enough likelihood; `None` when there is none (nothing to inpaint).
    pub fn from_pose(pose: &Pose, cfg: &LegMaskConfig) -> Option<Self> {
        let point = |name: &str| {
            let k = pose.keypoints.get(canonical_index(name)?)?;
            (k.is_found()
                && k.likelihood >= cfg.min_likelihood
                && k.x.is_finite()
                && k.y.is_finite())
            .then_some((k.x, k.y))
        };
        let segments: Vec<[(f64, f64); 2]> = gait_core::keypoint::LEG_SEGMENTS
            .iter()
            .filter_map(|(a, b)| Some([point(a)?, point(b)?]))
            .collect();
        let longest = segments
            .iter()
            .map(|[a, b]| (a.0 - b.0).hypot(a.1 - b.1))
            .fold(0.0, f64::max);
        (longest > 0.0).then_some(Self {
            segments,
            radius: cfg.radius * longest,
        })
    }

    /// True when frame pixel (x, y) is to be regenerated.
    pub fn contains(&self, x: f64, y: f64) -> bool {
        self.segments
            .iter()
            .any(|s| dist_to_segment((x, y), s) <= self.radius)
    }

    /// The mask on the generation canvas, `(height * width)` values in {0, 1}.
    pub fn on_canvas(&self, canvas: &Resize) -> Vec<f32> {
        let mut out = Vec::with_capacity((canvas.dst_width * canvas.dst_height) as usize);
        for y in 0..canvas.dst_height {
            for x in 0..canvas.dst_width {
                let (fx, fy) = canvas.to_source(f64::from(x), f64::from(y));
                out.push(if self.contains(fx, fy) { 1.0 } else { 0.0 });
            }
        }
        out
    }
}

fn dist_to_segment(p: (f64, f64), [a, b]: &[(f64, f64); 2]) -> f64 {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p.0 - a.0 - t * dx).hypot(p.1 - a.1 - t * dy)
}

#[cfg(test)]
mod tests {
    use gait_core::{CANONICAL, Keypoint};

    use super::*;

    fn pose(points: &[(&str, f64, f64, f64)]) -> Pose {
        let mut p = Pose::empty(CANONICAL.len());
        for &(name, x, y, l) in points {
            p.keypoints[canonical_index(name).unwrap()] = Keypoint::new(x, y, l);
        }
        p
    }

    #[test]
    fn capsules_follow_the_leg_and_scale_with_it() {
        let p = pose(&[
            ("left_hip", 50.0, 100.0, 0.9),
            ("left_knee", 50.0, 200.0, 0.9),
            ("left_ankle", 50.0, 300.0, 0.9),
            ("nose", 50.0, 10.0, 0.9),
        ]);
        let m = LegMask::from_pose(&p, &LegMaskConfig::default()).unwrap();
        // Radius 0.35 * 100 px.
        assert!(m.contains(50.0, 150.0) && m.contains(84.0, 250.0));
        assert!(!m.contains(86.0, 250.0));
        assert!(m.contains(50.0, 334.0) && !m.contains(50.0, 336.0));
        assert!(!m.contains(50.0, 10.0), "the head is kept");
    }

    #[test]
    fn unlikely_or_lonely_keypoints_give_no_mask() {
        let cfg = LegMaskConfig::default();
        let weak = pose(&[
            ("left_hip", 50.0, 100.0, 0.9),
            ("left_knee", 50.0, 200.0, 0.1),
        ]);
        assert_eq!(LegMask::from_pose(&weak, &cfg), None);
        let lonely = pose(&[("right_knee", 5.0, 5.0, 0.9), ("nose", 5.0, 0.0, 1.0)]);
        assert_eq!(LegMask::from_pose(&lonely, &cfg), None);
        assert_eq!(LegMask::from_pose(&Pose::empty(0), &cfg), None);
    }

    #[test]
    fn canvas_mask_maps_through_the_resize() {
        let p = pose(&[
            ("right_knee", 10.0, 0.0, 0.9),
            ("right_ankle", 10.0, 39.0, 0.9),
        ]);
        let cfg = LegMaskConfig {
            radius: 0.1,
            ..Default::default()
        };
        let m = LegMask::from_pose(&p, &cfg).unwrap();
        // Frame 40x40 onto a 20x20 canvas: the leg at x = 10 lands near x = 4.75.
        let v = m.on_canvas(&Resize::stretch(40, 40, 20, 20));
        let row: Vec<f32> = v[200..220].to_vec();
        let on: Vec<usize> = (0..20).filter(|&x| row[x] > 0.0).collect();
        assert!(
            !on.is_empty() && on.iter().all(|&x| (3..=6).contains(&x)),
            "{on:?}"
        );
    }
}
