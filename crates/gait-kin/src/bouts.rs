//! Walking bouts: the stretches of frames where the subject walks steadily across the view.
//!
//! A real video shows more than steady walking: the subject enters, stands, turns, is hidden
//! behind furniture or trees, leaves, and a tracker may follow someone else afterwards. Gait
//! events and cycles mean something only inside steady walking, so every frame is judged
//! walking (with its direction), a pause (too slow, or direction unknown: bridged when short) or
//! a break (hidden, out of view, tracker jump: always ends a bout), and walking frames are
//! joined into bouts. `kinematics.bouts` gives them by hand instead.

use serde::Serialize;

use crate::config::{KinematicsConfig, Side};
use crate::direction::Direction;
use crate::events::ground_speed;
use crate::tracks::{LEG, Tracks, dist};

/// A run of frames of steady walking in one direction.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Bout {
    /// First input frame number of the bout.
    pub first: usize,
    /// Last input frame number (inclusive).
    pub last: usize,
    pub direction: Direction,
    /// Mean forward speed of the pelvis over the ground, in leg lengths per second.
    pub mean_speed: f64,
}

impl Bout {
    pub fn contains(&self, frame: usize) -> bool {
        (self.first..=self.last).contains(&frame)
    }
}

/// Index of the bout holding input frame `frame`.
pub fn bout_of(bouts: &[Bout], frame: usize) -> Option<usize> {
    bouts.iter().position(|b| b.contains(frame))
}

/// The keypoints the bout rules look at.
pub struct Frames<'a> {
    /// Fully cleaned keypoints (gap-filled and smoothed).
    pub clean: &'a Tracks,
    /// After the likelihood gate and swap correction, before gap filling: what the pose model
    /// really gave (missing = dropped).
    pub gated: &'a Tracks,
    pub dirs: &'a [Direction],
    /// Longest gap (frames) the gap filler fills (`PostprocessConfig::max_gap`).
    pub max_gap: usize,
}

/// How one frame counts for the bouts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameState {
    Walking(Direction),
    /// Too slow, or no direction: a short pause inside a bout is bridged.
    Pause,
    /// Hidden, out of view, or the tracker jumped: ends any bout.
    Break,
}

/// Nobody walks half a leg length between two video frames (15 leg lengths/s at 30 fps): a
/// pelvis that does was lost by the tracker or belongs to someone else.
const JUMP_LEGS_PER_FRAME: f64 = 0.5;

/// Lower-limb keypoints a bout needs: hip, knee and ankle of both legs, and heel and toe where
/// the model gives them (seen in some frame; OpenPose COCO-18 has no feet).
fn lower_limb(g: &Tracks) -> Vec<usize> {
    let mut out = Vec::new();
    for side in Side::BOTH {
        for part in LEG {
            if let Some(j) = g.leg_index(side, part)
                && (["hip", "knee", "ankle"].contains(&part)
                    || g.x[j].iter().any(|v| v.is_finite()))
            {
                out.push(j);
            }
        }
    }
    out
}

/// Frames where a needed keypoint is missing and the gap filler does not fill it: a gap longer
/// than `max_gap`, or at either end of the recording (never filled).
fn hidden(g: &Tracks, joints: &[usize], max_gap: usize) -> Vec<bool> {
    let n = g.len();
    let mut out = vec![false; n];
    for &j in joints {
        let mut i = 0;
        while i < n {
            if g.at(j, i).is_some() {
                i += 1;
                continue;
            }
            let start = i;
            while i < n && g.at(j, i).is_none() {
                i += 1;
            }
            if start == 0 || i == n || i - start > max_gap {
                out[start..i].fill(true);
            }
        }
    }
    out
}

/// Frames where a needed keypoint lies within `margin` (fraction of the width) of the image
/// border: the person is entering or leaving, and a pose model extrapolates limbs it cannot see.
/// Judged on the smoothed keypoints (the model's own where nothing was smoothed): a single
/// frame's outlier of a toe near the bottom edge is noise, and on the raw keypoints it tipped
/// the bout of the bundled sample from frames 59-186 to 81-158 under an H.264 re-encode. A
/// frame counts only inside a spell at the border lasting `min_frames`: a foot that brushes
/// the border for a frame or two in mid-walk is still in view, while a walker who enters or
/// leaves stays at the border until hidden or turned away (`gone`: such a spell near those
/// frames counts whatever its length).
fn out_of_view(
    f: &Frames,
    joints: &[usize],
    (size, margin): (Option<[u32; 2]>, f64),
    gone: &[bool],
    min_frames: usize,
) -> Vec<bool> {
    let n = f.gated.len();
    let Some([w, h]) = size.map(|s| s.map(f64::from)) else {
        return vec![false; n];
    };
    let m = margin * w;
    let at_border: Vec<bool> = (0..n)
        .map(|i| {
            joints
                .iter()
                .filter_map(|&j| f.clean.at(j, i).or_else(|| f.gated.at(j, i)))
                .any(|(x, y)| x < m || x > w - m || y < m || y > h - m)
        })
        .collect();
    persistent(&at_border, gone, min_frames)
}

/// `flags` with runs shorter than `min_len` cleared, unless an `anchor` frame or either end of
/// the recording lies within `min_len` frames of the run (it goes on out of sight).
fn persistent(flags: &[bool], anchor: &[bool], min_len: usize) -> Vec<bool> {
    let n = flags.len();
    let mut out = flags.to_vec();
    let mut i = 0;
    while i < n {
        if !flags[i] {
            i += 1;
            continue;
        }
        let start = i;
        while i < n && flags[i] {
            i += 1;
        }
        let (lo, hi) = (start.checked_sub(min_len), i + min_len);
        let anchored = lo.is_none() || hi > n || anchor[lo.unwrap_or(0)..hi].iter().any(|&a| a);
        if i - start < min_len && !anchored {
            out[start..i].fill(false);
        }
    }
    out
}

/// Frames where the (gated) pelvis has jumped since the last frame it was seen.
fn jumps(g: &Tracks, leg: f64) -> Vec<bool> {
    let mut out = vec![false; g.len()];
    let mut last: Option<(usize, (f64, f64))> = None;
    for (i, jump) in out.iter_mut().enumerate() {
        if let Some(p) = g.pelvis(i) {
            if let Some((k, q)) = last {
                *jump = dist(p, q) > JUMP_LEGS_PER_FRAME * leg * (i - k) as f64;
            }
            last = Some((i, p));
        }
    }
    out
}

/// Signed horizontal pelvis speed over the ground per frame (image x, pixels/s), averaged over
/// +-0.25 s. The ground's image speed is the stance foot's (see [`ground_speed`]): zero for a
/// fixed camera, minus the belt speed on a treadmill, so a treadmill walker is walking. Taken
/// from the gated pelvis, not the smoothed one: the low-pass filter would smear a tracker jump
/// into the frames around it; velocities across a jump are left out.
pub fn pelvis_speed(f: &Frames, jump: &[bool]) -> Vec<f64> {
    let (g, n, fps) = (f.gated, f.gated.len(), f.gated.fps);
    let ground = ground_speed(f.clean, f.dirs);
    let raw: Vec<f64> = (0..n)
        .map(|i| {
            if i == 0 || i + 1 >= n || jump[i] || jump[i + 1] {
                return f64::NAN;
            }
            match (g.pelvis(i - 1), g.pelvis(i + 1)) {
                (Some(a), Some(b)) => (b.0 - a.0) * fps / 2.0,
                _ => f64::NAN,
            }
        })
        .collect();
    let w = (0.25 * fps).round().max(1.0) as usize;
    (0..n)
        .map(|i| {
            let win: Vec<f64> = raw[i.saturating_sub(w)..(i + w + 1).min(n)]
                .iter()
                .copied()
                .filter(|v| v.is_finite())
                .collect();
            let d = f.dirs.get(i).map_or(0.0, |d| d.sign());
            match win.len() {
                0 => f64::NAN,
                k => win.iter().sum::<f64>() / k as f64 - d * ground[i],
            }
        })
        .collect()
}

/// Per frame: walking, pause or break, and the pelvis speed over the ground (pixels/s).
pub fn states(f: &Frames, kin: &KinematicsConfig) -> (Vec<FrameState>, Vec<f64>) {
    let n = f.gated.len();
    let leg = f.clean.leg_length();
    if !(leg.is_finite() && leg > 0.0) {
        return (vec![FrameState::Break; n], vec![f64::NAN; n]);
    }
    let joints = lower_limb(f.gated);
    let hidden = hidden(f.gated, &joints, f.max_gap);
    let spell = ((kin.bout_bridge_s * f.gated.fps).round() as usize).max(1);
    let edge = (kin.frame_size, kin.bout_edge_margin);
    let gone: Vec<bool> = (0..n)
        .map(|i| hidden[i] || f.dirs.get(i).is_none_or(|&d| d == Direction::Unknown))
        .collect();
    let view = out_of_view(f, &joints, edge, &gone, spell);
    let jump = jumps(f.gated, leg);
    let speed = pelvis_speed(f, &jump);
    let states = (0..n)
        .map(|i| {
            let d = f.dirs.get(i).copied().unwrap_or(Direction::Unknown);
            if hidden[i] || view[i] || jump[i] {
                FrameState::Break
            } else if d != Direction::Unknown && d.sign() * speed[i] >= kin.bout_min_speed * leg {
                FrameState::Walking(d)
            } else {
                FrameState::Pause
            }
        })
        .collect();
    (states, speed)
}

/// Runs `(first, last, direction)` (timeline indices) of walking frames of one direction with
/// pauses of at most `bridge` frames inside, at least `min_len` frames long.
fn join(states: &[FrameState], bridge: usize, min_len: usize) -> Vec<(usize, usize, Direction)> {
    let mut out = Vec::new();
    let mut push = |run: Option<(usize, usize, Direction)>| {
        if let Some(r) = run.filter(|r| r.1 + 1 - r.0 >= min_len) {
            out.push(r);
        }
    };
    let mut cur: Option<(usize, usize, Direction)> = None;
    for (i, s) in states.iter().enumerate() {
        match *s {
            FrameState::Walking(d) => {
                cur = match cur {
                    Some((a, b, cd)) if cd == d && i - b - 1 <= bridge => Some((a, i, d)),
                    other => {
                        push(other);
                        Some((i, i, d))
                    }
                };
            }
            FrameState::Pause => {}
            FrameState::Break => push(cur.take()),
        }
    }
    push(cur);
    out
}

/// A bout over timeline indices `a..=b`, its mean forward speed in leg lengths/s.
fn bout(t: &Tracks, speed: &[f64], a: usize, b: usize, direction: Direction) -> Bout {
    let leg = t.leg_length();
    let v: Vec<f64> = speed[a..=b]
        .iter()
        .filter(|v| v.is_finite())
        .map(|v| match direction {
            Direction::Unknown => v.abs(),
            d => d.sign() * v,
        })
        .collect();
    Bout {
        first: t.first_frame + a,
        last: t.first_frame + b,
        direction,
        mean_speed: v.iter().sum::<f64>() / v.len() as f64 / leg,
    }
}

/// Bouts found by the rules (see the module docs).
pub fn detect(f: &Frames, kin: &KinematicsConfig) -> Vec<Bout> {
    let fps = f.gated.fps;
    let (states, speed) = states(f, kin);
    let bridge = (kin.bout_bridge_s * fps).round() as usize;
    let min_len = ((kin.bout_min_s * fps - 1e-9).ceil() as usize).max(1);
    join(&states, bridge, min_len)
        .into_iter()
        .map(|(a, b, d)| bout(f.clean, &speed, a, b, d))
        .collect()
}

/// Bouts given as inclusive input frame ranges, clipped to the recording; the direction is the
/// one most frames of the range have.
pub fn given(f: &Frames, ranges: &[[usize; 2]]) -> Vec<Bout> {
    let (t, n) = (f.clean, f.clean.len());
    if n == 0 {
        return Vec::new();
    }
    let leg = t.leg_length();
    let jump = jumps(f.gated, if leg.is_finite() { leg } else { f64::INFINITY });
    let speed = pelvis_speed(f, &jump);
    let mut sorted = ranges.to_vec();
    sorted.sort_unstable();
    sorted
        .iter()
        .filter_map(|&[first, last]| {
            let a = first.max(t.first_frame) - t.first_frame;
            let b = last.checked_sub(t.first_frame)?.min(n - 1);
            (a <= b).then(|| {
                let vote: f64 = f.dirs[a..=b].iter().map(|d| d.sign()).sum();
                let d = match vote {
                    v if v > 0.0 => Direction::Right,
                    v if v < 0.0 => Direction::Left,
                    _ => Direction::Unknown,
                };
                bout(t, &speed, a, b, d)
            })
        })
        .collect()
}

/// The bouts of `kinematics.bouts` when set, else detected ones.
pub fn find(f: &Frames, kin: &KinematicsConfig) -> Vec<Bout> {
    match &kin.bouts {
        Some(r) => given(f, r),
        None => detect(f, kin),
    }
}

#[cfg(test)]
mod tests;
