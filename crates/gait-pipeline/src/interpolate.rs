//! Keypoints of the frames a stride skipped, from the processed frames on
//! either side.

use gait_core::{Keypoint, Pose};

/// The pose at `frame` between processed frames `(fa, a)` and `(fb, b)`:
/// each coordinate linear in time. A keypoint missing at either end stays
/// missing. The likelihood is the smaller of the two ends, so an
/// interpolated keypoint is never trusted more than its weaker end and the
/// postprocess's likelihood threshold drops it whenever it would drop
/// either end.
pub fn between(fa: usize, a: &Pose, fb: usize, b: &Pose, frame: usize) -> Pose {
    let t = if fb > fa {
        (frame as f64 - fa as f64) / (fb as f64 - fa as f64)
    } else {
        0.0
    };
    Pose {
        keypoints: a
            .keypoints
            .iter()
            .zip(&b.keypoints)
            .map(|(ka, kb)| {
                if ka.is_found() && kb.is_found() {
                    Keypoint::new(
                        ka.x + t * (kb.x - ka.x),
                        ka.y + t * (kb.y - ka.y),
                        ka.likelihood.min(kb.likelihood),
                    )
                } else {
                    Keypoint::missing()
                }
            })
            .collect(),
    }
}

/// Fills every frame of `frames` (sorted) from the processed `known`
/// poses (sorted by frame, first and last frame included); returns the
/// poses in frame order and the frames that were interpolated.
pub fn fill(frames: &[usize], known: &[(usize, Pose)], n: usize) -> (Vec<Pose>, Vec<usize>) {
    let mut out = Vec::with_capacity(frames.len());
    let mut filled = Vec::new();
    let mut k = 0;
    for &f in frames {
        while k + 1 < known.len() && known[k + 1].0 <= f {
            k += 1;
        }
        match known.get(k) {
            Some((fa, a)) if *fa == f => out.push(a.clone()),
            Some((fa, a)) if *fa < f => match known.get(k + 1) {
                Some((fb, b)) => {
                    out.push(between(*fa, a, *fb, b, f));
                    filled.push(f);
                }
                None => out.push(Pose::empty(n)),
            },
            _ => out.push(Pose::empty(n)),
        }
    }
    (out, filled)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(points: &[Keypoint]) -> Pose {
        Pose {
            keypoints: points.to_vec(),
        }
    }

    #[test]
    fn linear_in_time_with_the_weaker_likelihood() {
        let a = pose(&[Keypoint::new(10.0, 20.0, 0.9), Keypoint::new(0.0, 0.0, 0.8)]);
        let b = pose(&[Keypoint::new(40.0, 5.0, 0.6), Keypoint::missing()]);
        let mid = between(3, &a, 6, &b, 4);
        assert_eq!(mid.keypoints[0], Keypoint::new(20.0, 15.0, 0.6));
        assert!(!mid.keypoints[1].is_found());
        assert_eq!(mid.keypoints[1].likelihood, 0.0);
        let two_thirds = between(3, &a, 6, &b, 5);
        assert!((two_thirds.keypoints[0].x - 30.0).abs() < 1e-12);
        assert!((two_thirds.keypoints[0].y - 10.0).abs() < 1e-12);
    }

    #[test]
    fn fill_keeps_processed_frames_and_interpolates_the_rest() {
        let p = |x: f64| pose(&[Keypoint::new(x, 0.0, 1.0)]);
        let known = vec![(10, p(0.0)), (13, p(3.0)), (14, p(10.0))];
        let frames: Vec<usize> = (10..=14).collect();
        let (poses, filled) = fill(&frames, &known, 1);
        let xs: Vec<f64> = poses.iter().map(|p| p.keypoints[0].x).collect();
        assert_eq!(xs, vec![0.0, 1.0, 2.0, 3.0, 10.0]);
        assert_eq!(filled, vec![11, 12]);
    }
}
