//! The first cleaning step: drop keypoints the pose model is not sure of.

use crate::tracks::Tracks;

/// Marks unreliable keypoints as missing (NaN) in place.
pub trait KeypointGate {
    fn apply(&self, t: &mut Tracks);
}

/// Drops every keypoint whose likelihood is below the threshold (paper: 0.5).
#[derive(Debug, Clone)]
pub struct LikelihoodThreshold(pub f64);

impl KeypointGate for LikelihoodThreshold {
    fn apply(&self, t: &mut Tracks) {
        for j in 0..t.names.len() {
            for i in 0..t.len() {
                let l = t.likelihood[j][i];
                if l.is_nan() || l < self.0 {
                    t.x[j][i] = f64::NAN;
                    t.y[j][i] = f64::NAN;
                    t.likelihood[j][i] = 0.0;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drops_below_threshold_only() {
        let mut t = Tracks {
            fps: 30.0,
            first_frame: 0,
            names: vec!["left_knee".into()],
            x: vec![vec![1.0, 2.0, 3.0]],
            y: vec![vec![1.0, 2.0, 3.0]],
            likelihood: vec![vec![0.49, 0.5, f64::NAN]],
        };
        LikelihoodThreshold(0.5).apply(&mut t);
        assert!(t.x[0][0].is_nan() && t.x[0][2].is_nan());
        assert_eq!(t.x[0][1], 2.0);
    }
}
