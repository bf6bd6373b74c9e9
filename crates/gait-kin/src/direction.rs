//! Walking direction per frame, side view check, and the leg nearer the camera.

use serde::Serialize;

use crate::config::Side;
use crate::tracks::Tracks;

/// Direction of travel in the image, per frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    /// Walking towards +x (image right).
    Right,
    /// Walking towards -x (image left).
    Left,
    /// Not known: nothing seen, standing with no foot visible, or not a side view.
    Unknown,
}

impl Direction {
    /// +1, -1 or 0: multiplies image x to get "forward".
    pub fn sign(self) -> f64 {
        match self {
            Direction::Right => 1.0,
            Direction::Left => -1.0,
            Direction::Unknown => 0.0,
        }
    }

    /// The leg nearer the camera. With image x right and y down the camera looks along +z, so a
    /// person walking to image right has their left side away from the camera: the right leg is
    /// nearer (and vice versa). Assumes the person faces where they walk and the video is not
    /// mirrored.
    pub fn near_side(self) -> Option<Side> {
        match self {
            Direction::Right => Some(Side::Right),
            Direction::Left => Some(Side::Left),
            Direction::Unknown => None,
        }
    }
}

/// Per-frame direction and whether the frame is a side (sagittal) view.
#[derive(Debug, Clone)]
pub struct Directions {
    pub per_frame: Vec<Direction>,
    /// Frames where the hips are far apart horizontally: the person faces or backs the camera.
    pub frontal: Vec<bool>,
}

impl Directions {
    /// No direction in any of `n` frames (a front or back view has none across the image).
    pub fn unknown(n: usize) -> Self {
        Self {
            per_frame: vec![Direction::Unknown; n],
            frontal: vec![false; n],
        }
    }

    /// Frames walking right / left / unknown.
    pub fn counts(&self) -> [usize; 3] {
        let mut counts = [0usize; 3];
        for d in &self.per_frame {
            counts[match d {
                Direction::Right => 0,
                Direction::Left => 1,
                Direction::Unknown => 2,
            }] += 1;
        }
        counts
    }

    /// The leg nearer the camera in most frames with a known direction.
    pub fn near_side(&self) -> Option<Side> {
        let c = self.counts();
        match c[0].cmp(&c[1]) {
            std::cmp::Ordering::Greater => Direction::Right.near_side(),
            std::cmp::Ordering::Less => Direction::Left.near_side(),
            std::cmp::Ordering::Equal => None,
        }
    }
}

/// -1, 0 or +1 (`f64::signum` gives +1 for 0).
fn sign(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// Walking direction from the pelvis' horizontal velocity (over +-0.1 s) when it moves faster
/// than 0.2 leg lengths per second, otherwise from which way the feet point (heel -> toe);
/// then a majority vote over +-0.25 s removes flicker. Frames whose hips lie further apart than
/// half the thigh's length in most frames within +-0.25 s are taken as frontal views and get no
/// direction.
pub fn detect(t: &Tracks) -> Directions {
    let n = t.len();
    let leg = t.leg_length();
    let fps = t.fps;
    let w = ((0.1 * fps).round() as usize).max(1);
    let half = ((0.25 * fps).round() as usize).max(1);
    let frontal = majority(&hips_apart(t, leg), half);
    let mut raw = vec![0.0f64; n];
    for i in (0..n).filter(|&i| !frontal[i]) {
        let lo = i.saturating_sub(w);
        let hi = (i + w).min(n.saturating_sub(1));
        if let (Some(a), Some(b)) = (t.pelvis(lo), t.pelvis(hi))
            && hi > lo
        {
            let v = (b.0 - a.0) / ((hi - lo) as f64 / fps);
            if leg.is_finite() && v.abs() > 0.2 * leg {
                raw[i] = v.signum();
                continue;
            }
        }
        let mut foot = 0.0;
        for side in Side::BOTH {
            if let (Some(h), Some(k)) = (t.leg_index(side, "heel"), t.leg_index(side, "toe"))
                && let (Some(a), Some(b)) = (t.at(h, i), t.at(k, i))
            {
                foot += sign(b.0 - a.0);
            }
        }
        raw[i] = sign(foot);
    }
    let per_frame = (0..n)
        .map(|i| {
            if frontal[i] || raw[i] == 0.0 {
                return Direction::Unknown;
            }
            let lo = i.saturating_sub(half);
            let hi = (i + half + 1).min(n);
            let vote: f64 = raw[lo..hi].iter().sum();
            match vote {
                v if v > 0.0 => Direction::Right,
                v if v < 0.0 => Direction::Left,
                _ => {
                    if raw[i] > 0.0 {
                        Direction::Right
                    } else {
                        Direction::Left
                    }
                }
            }
        })
        .collect();
    Directions { per_frame, frontal }
}

/// Per frame, whether the hips lie further apart across the image than half the longer
/// thigh (else a quarter of the leg): a body facing or backing the camera.
fn hips_apart(t: &Tracks, leg: f64) -> Vec<bool> {
    let hips = [Side::Left, Side::Right].map(|s| t.leg_index(s, "hip"));
    let knees = [Side::Left, Side::Right].map(|s| t.leg_index(s, "knee"));
    let ([Some(lh), Some(rh)], [Some(lk), Some(rk)]) = (hips, knees) else {
        return vec![false; t.len()];
    };
    (0..t.len())
        .map(|i| {
            let (Some(a), Some(b)) = (t.at(lh, i), t.at(rh, i)) else {
                return false;
            };
            let thigh = [(lh, lk), (rh, rk)]
                .iter()
                .filter_map(|&(h, k)| Some(crate::tracks::dist(t.at(h, i)?, t.at(k, i)?)))
                .fold(0.0, f64::max);
            let thigh = if thigh > 0.0 { thigh } else { leg / 2.0 };
            (a.0 - b.0).abs() > 0.5 * thigh
        })
        .collect()
}

/// `flags` where more than half of the flags within +-`half` are set: a side view whose hips
/// drift to the limit for a frame or two (a pelvis turned in late stance, a pose model's
/// jitter) keeps its direction there. On a healthy walk's motion capture seen from the side
/// (tests/visit.rs, 30 fps) the hips lie 66-68 px apart against a limit of 66-68 near one
/// heel strike, and jitter made 2 frames frontal: the heel strike there was lost, and with it
/// a stride.
fn majority(flags: &[bool], half: usize) -> Vec<bool> {
    (0..flags.len())
        .map(|i| {
            let (lo, hi) = (i.saturating_sub(half), (i + half + 1).min(flags.len()));
            2 * flags[lo..hi].iter().filter(|&&f| f).count() > hi - lo
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two frames of hips apart within a side view are not a front view; half a second of them
    /// (a walker turning toward the camera) is, but for its first and last frames, and a whole
    /// front view stays one.
    #[test]
    fn hips_apart_for_a_frame_or_two_are_no_front_view() {
        let half = 8;
        let mut flags = vec![false; 60];
        flags[40] = true;
        flags[41] = true;
        assert!(majority(&flags, half).iter().all(|&f| !f));
        for f in flags.iter_mut().take(35).skip(15) {
            *f = true;
        }
        let m = majority(&flags, half);
        assert!(m[18..32].iter().all(|&f| f), "{m:?}");
        assert!(!m[10] && !m[40], "{m:?}");
        assert!(majority(&[true; 30], half).iter().all(|&f| f));
    }
}
