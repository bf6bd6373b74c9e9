//! Links the people seen in each frame into tracks: one track per person,
//! by predicted position, body size and appearance.

use gait_core::PersonBox;
use serde::{Deserialize, Serialize};

use crate::appearance::Appearance;
use crate::lookahead;

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

/// Sightings whose body axis leans further than this from upright (radians)
/// are detector errors for a walking subject (e.g. a box turned upside
/// down on a half-hidden body): they are not linked into any track.
const MAX_TILT: f32 = std::f32::consts::FRAC_PI_4;

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

/// Links `frames` (frame index and the people seen in it, in frame order)
/// into tracks, in order of their first sighting.
pub fn link(frames: &[(usize, Vec<Sighting>)], limits: &LinkLimits) -> Vec<Track> {
    let mut tracks: Vec<Track> = Vec::new();
    for (i, (frame, seen)) in frames.iter().enumerate() {
        let seen: Vec<Sighting> = seen.iter().filter(|s| upright(s)).copied().collect();
        // Every plausible (track, sighting) pair, cheapest first: a greedy
        // assignment, which is exact whenever the people are well apart.
        let mut pairs: Vec<(f32, usize, usize)> = Vec::new();
        for (t, track) in tracks.iter().enumerate() {
            for (k, s) in seen.iter().enumerate() {
                if let Some(c) = track.cost(s, limits)
                    && !lookahead::contradicted(track, s, &frames[i + 1..], limits)
                {
                    pairs.push((c, t, k));
                }
            }
        }
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut track_used = vec![false; tracks.len()];
        let mut seen_used = vec![false; seen.len()];
        for (_, t, k) in pairs {
            if !track_used[t] && !seen_used[k] {
                track_used[t] = true;
                seen_used[k] = true;
                tracks[t].sightings.push(seen[k]);
            }
        }
        for (k, s) in seen.iter().enumerate() {
            if !seen_used[k] {
                debug_assert_eq!(s.frame, *frame);
                tracks.push(Track {
                    sightings: vec![*s],
                });
            }
        }
    }
    tracks
}

/// Whether the body axis (centre to top, up the image) leans less than
/// [`MAX_TILT`] from vertical.
fn upright(s: &Sighting) -> bool {
    let [cx, cy] = s.person.centre;
    let [tx, ty] = s.person.top;
    (tx - cx).abs().atan2(cy - ty) < MAX_TILT
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

    fn frames(
        people: &[&dyn Fn(usize) -> Option<Sighting>],
        n: usize,
    ) -> Vec<(usize, Vec<Sighting>)> {
        (0..n)
            .map(|f| (f, people.iter().filter_map(|p| p(f)).collect()))
            .collect()
    }

    #[test]
    fn two_people_crossing_keep_their_tracks() {
        // A walker from right to left crosses a standing person of the same
        // size; their colours differ.
        let walker = |f: usize| Some(seen(f, 1500.0 - 10.0 * f as f32, 400.0, 0.2));
        let stander = |f: usize| Some(seen(f, 800.0, 400.0, 0.8));
        let tracks = link(&frames(&[&walker, &stander], 140), &LIMITS);
        assert_eq!(tracks.len(), 2);
        for t in &tracks {
            let grey = t.sightings[0].appearance.0[0];
            assert_eq!(t.sightings.len(), 140);
            assert!(t.sightings.iter().all(|s| s.appearance.0[0] == grey));
        }
    }

    #[test]
    fn a_hidden_person_is_taken_up_again_only_by_the_same_person() {
        // The subject is hidden for frames 40-69, at frame 55 someone else
        // (other colours) enters where the subject would be.
        let subject = |f: usize| {
            (!(40..70).contains(&f)).then(|| seen(f, 1500.0 - 10.0 * f as f32, 400.0, 0.2))
        };
        let other =
            |f: usize| (f >= 55).then(|| seen(f, 1500.0 - 10.0 * f as f32 + 20.0, 400.0, 0.7));
        let tracks = link(&frames(&[&subject, &other], 100), &LIMITS);
        let first = &tracks[0];
        assert!(first.sightings.iter().all(|s| s.appearance.0[0] == 0.2));
        assert_eq!(
            first.sightings.len(),
            70,
            "the subject's track resumes at 70"
        );
        assert!(
            tracks
                .iter()
                .skip(1)
                .all(|t| t.sightings.iter().all(|s| s.appearance.0[0] == 0.7))
        );
    }

    #[test]
    fn upside_down_boxes_are_not_linked() {
        let mut flipped = seen(5, 500.0, 400.0, 0.5);
        flipped.person.top[1] = 700.0;
        let frames = vec![
            (4, vec![seen(4, 500.0, 400.0, 0.5)]),
            (5, vec![flipped]),
            (6, vec![seen(6, 500.0, 400.0, 0.5)]),
        ];
        let tracks = link(&frames, &LIMITS);
        assert_eq!(tracks.len(), 1);
        assert_eq!(
            tracks[0]
                .sightings
                .iter()
                .map(|s| s.frame)
                .collect::<Vec<_>>(),
            [4, 6]
        );
    }

    #[test]
    fn someone_of_another_size_is_not_the_subject() {
        let subject = |f: usize| (f < 20).then(|| seen(f, 500.0, 400.0, 0.5));
        let child = |f: usize| (f >= 25).then(|| seen(f, 500.0, 200.0, 0.5));
        let tracks = link(&frames(&[&subject, &child], 50), &LIMITS);
        assert_eq!(tracks.len(), 2);
    }
}
