//! Frontal-plane angles per frame, each side, from image keypoints of a front or back view.
//!
//! Signs, per side S (image y points down; "toward S" is the subject's S side in the image,
//! image right for the left side in an anterior view, image left in a posterior view):
//! - `trunk_lean`: mid-hip -> mid-shoulder against the image vertical, positive leaning
//!   toward S (so the left and right curves are mirror images);
//! - `pelvic_obliquity`: the hip line (other hip -> S's hip) above the horizontal, positive
//!   when S's hip is higher (hiking), negative when S's side drops;
//! - `hip_adduction`: the thigh against the pelvis' downward perpendicular, positive when the
//!   knee lies medial (adduction);
//! - `knee_varus`: from the thigh's direction to the shank's, positive when the shank turns
//!   medially (varus), negative valgus (the knee's frontal-plane projection angle).

use crate::config::Side;
use crate::tracks::Tracks;
use crate::view::View;

/// The measures, in the order of the tables and plots.
pub const MEASURES: [&str; 4] = [
    "trunk_lean",
    "pelvic_obliquity",
    "hip_adduction",
    "knee_varus",
];

/// Per side, per measure of [`MEASURES`], degrees per frame of the timeline (NaN: not seen).
#[derive(Debug, Clone, Default)]
pub struct FrontalAngles {
    pub left: [Vec<f64>; 4],
    pub right: [Vec<f64>; 4],
}

impl FrontalAngles {
    pub fn side(&self, side: Side) -> &[Vec<f64>; 4] {
        match side {
            Side::Left => &self.left,
            Side::Right => &self.right,
        }
    }
}

type P = (f64, f64);

fn sub(a: P, b: P) -> P {
    (a.0 - b.0, a.1 - b.1)
}

fn dot(a: P, b: P) -> f64 {
    a.0 * b.0 + a.1 * b.1
}

fn mid(a: P, b: P) -> P {
    ((a.0 + b.0) / 2.0, (a.1 + b.1) / 2.0)
}

/// The keypoints one frame's measures need, by side (NaN where missing).
struct Frame {
    hip: [Option<P>; 2],
    knee: [Option<P>; 2],
    ankle: [Option<P>; 2],
    shoulders: Option<P>,
}

impl Frame {
    fn read(t: &Tracks, i: usize) -> Self {
        let at = |side: Side, part: &str| t.leg_index(side, part).and_then(|j| t.at(j, i));
        let both = |part: &str| [at(Side::Left, part), at(Side::Right, part)];
        let shoulder = |name: &str| t.index(name).and_then(|j| t.at(j, i));
        Self {
            hip: both("hip"),
            knee: both("knee"),
            ankle: both("ankle"),
            shoulders: match (shoulder("left_shoulder"), shoulder("right_shoulder")) {
                (Some(a), Some(b)) => Some(mid(a, b)),
                _ => None,
            },
        }
    }
}

fn k(side: Side) -> usize {
    match side {
        Side::Left => 0,
        Side::Right => 1,
    }
}

/// The four measures of `side` in one frame.
fn measure(f: &Frame, side: Side, view: View) -> [f64; 4] {
    let toward = view.toward(side);
    let (s, o) = (k(side), k(side.other()));
    let mut out = [f64::NAN; 4];
    let (Some(hs), Some(ho)) = (f.hip[s], f.hip[o]) else {
        return out;
    };
    let pelvis = mid(hs, ho);
    if let Some(sh) = f.shoulders {
        let v = sub(sh, pelvis);
        out[0] = (v.0 * toward).atan2(-v.1).to_degrees();
    }
    let line = sub(hs, ho);
    out[1] = (-line.1).atan2(line.0 * toward).to_degrees();
    // The pelvis' own frame: `lateral` toward S along the hip line, `down` perpendicular to it.
    let len = line.0.hypot(line.1);
    if len == 0.0 {
        return out;
    }
    let lateral = (line.0 / len, line.1 / len);
    let down = if lateral.0 >= 0.0 {
        (-lateral.1, lateral.0)
    } else {
        (lateral.1, -lateral.0)
    };
    // Angle of a segment from `down`, positive toward medial.
    let medial_angle = |v: P| (-dot(v, lateral)).atan2(dot(v, down)).to_degrees();
    if let Some(kn) = f.knee[s] {
        let thigh = medial_angle(sub(kn, hs));
        out[2] = thigh;
        if let Some(an) = f.ankle[s] {
            out[3] = medial_angle(sub(an, kn)) - thigh;
        }
    }
    out
}

/// The frontal angles move at the stride's frequency and its first harmonics (a pelvis drops
/// and rises once a stride), slower than the feet whose keypoints the 6 Hz keypoint filter is
/// set for; a pose model's jitter on two hips 40 px apart tilts their line by degrees. So the
/// angles are low-passed again at this cutoff (zero-phase Butterworth, order 2).
pub const CUTOFF_HZ: f64 = 3.0;

/// Every frame's measures, both sides.
pub fn compute(t: &Tracks, view: View) -> FrontalAngles {
    let mut a = raw(t, view);
    let filter = crate::butterworth::Butterworth {
        order: 2,
        cutoff_hz: CUTOFF_HZ,
    };
    for series in a.left.iter_mut().chain(a.right.iter_mut()) {
        crate::smooth::smooth_segments(&filter, series, t.fps);
    }
    a
}

/// The measures of each frame as its keypoints give them.
fn raw(t: &Tracks, view: View) -> FrontalAngles {
    let n = t.len();
    let mut out = FrontalAngles {
        left: std::array::from_fn(|_| vec![f64::NAN; n]),
        right: std::array::from_fn(|_| vec![f64::NAN; n]),
    };
    for i in 0..n {
        let f = Frame::read(t, i);
        for side in Side::BOTH {
            let m = measure(&f, side, view);
            let dst = match side {
                Side::Left => &mut out.left,
                Side::Right => &mut out.right,
            };
            for (d, v) in dst.iter_mut().zip(m) {
                d[i] = v;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(hl: P, hr: P, kl: P, al: P, sh: Option<P>) -> Frame {
        Frame {
            hip: [Some(hl), Some(hr)],
            knee: [Some(kl), Some((hr.0, hr.1 + 40.0))],
            ankle: [Some(al), Some((hr.0, hr.1 + 80.0))],
            shoulders: sh,
        }
    }

    /// Posterior view: the subject's left on the image left. The left hip 10 px higher than
    /// the right over a 40 px hip line hikes the left side by atan(10/40); the trunk leaning
    /// to image left leans toward the left; the left knee toward image right is medial.
    #[test]
    fn signs_follow_the_subject_not_the_image() {
        let f = frame(
            (80.0, 90.0),
            (120.0, 100.0),
            (110.0, 130.0),
            (100.0, 170.0),
            Some((90.0, 30.0)),
        );
        let l = measure(&f, Side::Left, View::Posterior);
        let r = measure(&f, Side::Right, View::Posterior);
        let hike = 10f64.atan2(40.0).to_degrees();
        assert!(
            (l[1] - hike).abs() < 1e-9 && (r[1] + hike).abs() < 1e-9,
            "{l:?} {r:?}"
        );
        assert!(l[0] > 0.0 && (l[0] + r[0]).abs() < 1e-9, "{l:?} {r:?}");
        assert!(l[2] > 0.0, "left knee medial of the hip: adduction {l:?}");
        // The shank comes back laterally (ankle left of the knee): valgus.
        assert!(l[3] < 0.0, "{l:?}");
        // Seen from the front the same image is the mirror: the left leg now lies on the image
        // right's side of the body and the same knee offset is lateral.
        let fl = frame(
            (120.0, 100.0),
            (80.0, 90.0),
            (110.0, 130.0),
            (100.0, 170.0),
            None,
        );
        let a = measure(&fl, Side::Left, View::Anterior);
        assert!(
            a[2] > 0.0,
            "knee at x 110 is medial of the left hip at x 120: {a:?}"
        );
        assert!(
            a[0].is_nan() && a[1] < 0.0,
            "the left hip is lower here: {a:?}"
        );
    }
}
