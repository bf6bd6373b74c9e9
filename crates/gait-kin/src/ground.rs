//! How fast the ground moves in the image: not at all for a camera on a tripod, at the
//! walking speed for a phone that follows the walker or for a treadmill's belt. Where it moves,
//! the distance a heel travels in the image between two of its strikes is not the stride: the
//! stride is then taken as the two steps within it, each measured within one frame (the
//! distance between the heels at a heel strike), which no camera motion changes.
//!
//! The ground's image speed is the stance foot's: over the middle half of each stance (heel
//! strike to the same foot's toe-off) a planted ankle stands where the ground is.

use serde::Serialize;

use crate::config::Side;
use crate::events::{Event, EventKind};
use crate::tracks::Tracks;

/// The ground moving at more than this share of the walking speed (the pelvis's speed over the
/// ground) makes image distances between frames unusable as lengths: on a tripod the stance
/// ankle's drift is a few percent (the ankle rolls forward over the foot); a camera that pans
/// to follow the walker moves the ground at up to the walking speed itself.
pub const MAX_SHARE: f64 = 0.2;

/// The ground's and the walker's horizontal image speeds (px/s, signed along x).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GroundMotion {
    /// The stance ankles' median image speed: the ground's.
    pub ground_px_s: f64,
    /// The pelvis's median image speed less the ground's: the walking speed.
    pub walking_px_s: f64,
    /// Stances measured.
    pub stances: usize,
}

impl GroundMotion {
    /// The ground's speed as a share of the walking speed.
    pub fn share(&self) -> f64 {
        (self.ground_px_s / self.walking_px_s).abs()
    }

    /// Whether the ground moves too fast for lengths between frames.
    pub fn moves(&self) -> bool {
        self.share() > MAX_SHARE
    }
}

/// The ground's motion over the stances of `events` (a side view's), or `None` with fewer than
/// two stances measured.
pub fn measure(t: &Tracks, events: &[Event]) -> Option<GroundMotion> {
    let hips = (
        t.leg_index(Side::Left, "hip")?,
        t.leg_index(Side::Right, "hip")?,
    );
    let pelvis_x = |i: usize| Some((t.at(hips.0, i)?.0 + t.at(hips.1, i)?.0) / 2.0);
    let (mut ground, mut pelvis) = (Vec::new(), Vec::new());
    for side in Side::BOTH {
        let Some(ankle) = t.leg_index(side, "ankle") else {
            continue;
        };
        for (a, b) in middle_halves(events, side, t.first_frame) {
            let dt = (b - a) as f64 / t.fps;
            if let (Some(p), Some(q), Some(u), Some(v)) =
                (t.at(ankle, a), t.at(ankle, b), pelvis_x(a), pelvis_x(b))
            {
                ground.push((q.0 - p.0) / dt);
                pelvis.push((v - u) / dt);
            }
        }
    }
    if ground.len() < 2 {
        return None;
    }
    let ground_px_s = median(&mut ground.clone());
    let walking_px_s = median(&mut pelvis) - ground_px_s;
    (walking_px_s.abs() > 0.0).then_some(GroundMotion {
        ground_px_s,
        walking_px_s,
        stances: ground.len(),
    })
}

/// The middle half of each stance of `side` (heel strike to its next toe-off), as track
/// indices, where it spans at least two frames.
fn middle_halves(events: &[Event], side: Side, first: usize) -> Vec<(usize, usize)> {
    let of = |kind| {
        events
            .iter()
            .filter(move |e| e.side == side && e.event == kind)
    };
    of(EventKind::HeelStrike)
        .filter_map(|hs| {
            let to = of(EventKind::ToeOff).find(|to| to.frame > hs.frame)?;
            // A stance whose toe-off is missing runs into the next one: not measured.
            if of(EventKind::HeelStrike).any(|h| h.frame > hs.frame && h.frame < to.frame) {
                return None;
            }
            let quarter = (to.frame - hs.frame) / 4;
            let (a, b) = (hs.frame + quarter, to.frame - quarter);
            (b >= a + 2 && a >= first).then(|| (a - first, b - first))
        })
        .collect()
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}
