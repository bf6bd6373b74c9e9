//! The smoothing step: a [`Smoother`] runs on each run of consecutive present samples.

/// A low-pass filter for one coordinate of one keypoint. `x` has no NaN and is uniformly sampled
/// at `fps`; the result has the same length.
pub trait Smoother {
    fn smooth(&self, x: &[f64], fps: f64) -> Vec<f64>;
}

/// Leaves the trajectory unchanged (`filter = "none"`).
#[derive(Debug, Clone, Default)]
pub struct Identity;

impl Smoother for Identity {
    fn smooth(&self, x: &[f64], _fps: f64) -> Vec<f64> {
        x.to_vec()
    }
}

/// Smooths every maximal run of finite samples separately; NaN stays NaN.
pub fn smooth_segments(s: &dyn Smoother, x: &mut [f64], fps: f64) {
    let mut i = 0;
    while i < x.len() {
        if !x[i].is_finite() {
            i += 1;
            continue;
        }
        let start = i;
        while i < x.len() && x[i].is_finite() {
            i += 1;
        }
        let y = s.smooth(&x[start..i], fps);
        x[start..i].copy_from_slice(&y);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Double;
    impl Smoother for Double {
        fn smooth(&self, x: &[f64], _fps: f64) -> Vec<f64> {
            x.iter().map(|v| v * 2.0).collect()
        }
    }

    #[test]
    fn segments_keep_gaps() {
        let mut x = [1.0, f64::NAN, 2.0, 3.0, f64::NAN];
        smooth_segments(&Double, &mut x, 30.0);
        assert_eq!(x[0], 2.0);
        assert!(x[1].is_nan() && x[4].is_nan());
        assert_eq!(&x[2..4], &[4.0, 6.0]);
    }
}
