//! A person seen in a frame, and the track of one person's sightings: where
//! it predicts the person next, and what continuing it with a sighting costs.

use gait_core::PersonBox;
use serde::{Deserialize, Serialize};

use crate::appearance::Appearance;

/// One person seen in one frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Sighting {
    pub frame: usize,
    pub person: PersonBox,
    pub appearance: Appearance,
}

impl Sighting {
    /// The box in `frame` on the straight way from this sighting to `later`.
    pub fn towards(&self, later: &Sighting, frame: usize) -> PersonBox {
        let t = (frame - self.frame) as f32 / (later.frame - self.frame) as f32;
        self.person.lerp(&later.person, t)
    }
}

/// The sightings of one person, in frame order.
#[derive(Debug, Clone, PartialEq)]
pub struct Track {
    pub sightings: Vec<Sighting>,
}

/// How far a track may be carried over frames without a sighting, and how
/// alike a later sighting must be to continue it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkLimits {
    /// Frames a track may go unseen and still be taken up again.
    pub max_gap_frames: usize,
    /// Largest body-size ratio between a track and its next sighting.
    pub max_size_ratio: f32,
    /// Largest colour difference (see [`Appearance::distance`]) to take a
    /// track up again after a missed frame.
    pub max_colour_distance: f32,
    /// Gaps up to this many frames are ordinary detector misses; a track
    /// unseen for this long costs [`UNSEEN_COST`] more to continue.
    pub short_gap_frames: usize,
}

/// The cost of a track going unseen for `short_gap_frames` (a link costs
/// about 0.1-1 otherwise: distance over reach, size change, colour). Without
/// it a track unseen for 12 frames took the walker from the one that saw her
/// a frame before (CRF 23 at frame 118). It is a balance, measured on the
/// sample's re-encodings and tests/scenes.rs: at 0.3 two look-alikes crossing
/// were swapped where one was missed for a few frames; at 0.15 the walker of
/// the mirrored sample (CRF 12) was lost where she passes the man.
const UNSEEN_COST: f32 = 0.18;

impl Track {
    pub(crate) fn last(&self) -> &Sighting {
        &self.sightings[self.sightings.len() - 1]
    }

    /// The body size now: the median of the last few sightings (one odd
    /// detection does not change it).
    pub(crate) fn size(&self) -> f32 {
        let mut s: Vec<f32> = self.recent(5).map(|x| x.person.size()).collect();
        s.sort_by(f32::total_cmp);
        s[s.len() / 2]
    }

    fn recent(&self, n: usize) -> impl Iterator<Item = &Sighting> {
        self.sightings[self.sightings.len().saturating_sub(n)..].iter()
    }

    /// Where the body centre should be in `frame`, from its recent velocity.
    fn predict(&self, frame: usize) -> [f32; 2] {
        let last = self.last();
        let first = self.recent(6).next().unwrap_or(last);
        let span = (last.frame - first.frame) as f32;
        let dt = (frame - last.frame) as f32;
        let [x, y] = last.person.centre;
        if span == 0.0 {
            return [x, y];
        }
        let vx = (x - first.person.centre[0]) / span;
        let vy = (y - first.person.centre[1]) / span;
        [x + vx * dt, y + vy * dt]
    }

    /// How far `s` lies from where this track predicts it (in body sizes), and
    /// how far it may: the prediction grows uncertain with the gap (a walker
    /// covers about 0.02 body sizes a frame, a runner 0.07).
    pub(crate) fn offset(&self, s: &Sighting) -> (f32, f32) {
        let dt = s.frame.saturating_sub(self.last().frame);
        let p = self.predict(s.frame);
        let d = (p[0] - s.person.centre[0]).hypot(p[1] - s.person.centre[1]);
        (d / self.size().max(1.0), (0.2 + 0.04 * dt as f32).min(1.0))
    }

    pub(crate) fn appearance(&self) -> Appearance {
        Appearance::mean(self.recent(10).map(|s| &s.appearance))
    }

    /// The cost of continuing this track with `s`, or `None` when `s` is not
    /// this person (too far, another size, other colours after a gap).
    pub(crate) fn cost(&self, s: &Sighting, limits: &LinkLimits) -> Option<f32> {
        let dt = s.frame - self.last().frame;
        if dt == 0 || dt > limits.max_gap_frames.saturating_add(1) {
            return None;
        }
        let size = self.size().max(1.0);
        let (d, reach) = self.offset(s);
        let ratio = (s.person.size().max(1.0) / size).ln().abs();
        if d > reach || ratio > limits.max_size_ratio.ln() {
            return None;
        }
        let colour = self.appearance().distance(&s.appearance);
        // After a miss the colours must match too: a bystander whose track went
        // unseen for a few frames can sit where the subject now is, at her
        // size (her detected size jumps where her feet leave the image).
        if dt > 1 && colour.is_none_or(|c| c > limits.max_colour_distance) {
            return None;
        }
        // A track seen a moment ago is the likelier owner of a sighting than
        // one unseen for a while whose prediction happens to land there too
        // (two tracks on one walker otherwise take her frames in turn).
        let unseen = (dt - 1) as f32 / limits.short_gap_frames.max(1) as f32;
        Some(d / reach + ratio + 4.0 * colour.unwrap_or(0.0) + UNSEEN_COST * unseen)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub(crate) const LIMITS: LinkLimits = LinkLimits {
        max_gap_frames: 60,
        max_size_ratio: 1.4,
        max_colour_distance: 0.1,
        short_gap_frames: 6,
    };

    pub(crate) fn seen(frame: usize, x: f32, size: f32, grey: f32) -> Sighting {
        Sighting {
            frame,
            person: PersonBox::upright(x, 500.0, size, 0.9),
            appearance: Appearance([grey; 6]),
        }
    }
}
