//! The subject's box in every frame it is followed: its track's sightings,
//! and the frames between them where the detector missed it.

use std::collections::BTreeMap;

use gait_core::PersonBox;

use crate::track::Sighting;
use crate::{Appearance, TrackSummary};

/// How far the subject's boxes reach beyond its sightings, in frames.
pub(crate) struct Reach {
    /// Gaps bridged by interpolation.
    pub fill: usize,
    /// Gaps that may take the subject's sightings from other tracks.
    pub max_gap: usize,
    /// Frames before the first and after the last sighting.
    pub lead: usize,
    /// The first and last frame of the pass.
    pub range: (usize, usize),
}

/// The boxes of the chosen track's sightings, with the gaps between them
/// closed in two steps, and carried on for `lead` frames at either end. A gap longer than `fill` (up to `max_gap` frames)
/// takes the sightings of other tracks that lie on the subject's way across
/// it (the box interpolated between the sightings either side) in the
/// subject's colours: the subject, detected with a box the linker gave to
/// another track. Then gaps of up to `fill` frames are bridged by linear
/// interpolation, except where someone else is seen on the bridged box: a
/// sighting of another track there whose colours differ from the subject's
/// (the pose model would find that person). At the ends the box moves on at
/// the subject's speed over its first or last half second, again not onto
/// someone else.
pub(crate) fn boxes(
    tracks: &[TrackSummary],
    chosen: usize,
    reach: &Reach,
    max_colour: f32,
) -> BTreeMap<usize, PersonBox> {
    let (fill, max_gap) = (reach.fill, reach.max_gap);
    let own = &tracks[chosen].sightings;
    let look = Lookalike {
        tracks,
        chosen,
        own,
        window: max_gap,
        max_colour,
    };
    let seen = look.across_long_gaps(own, fill, max_gap);
    let mut out = BTreeMap::new();
    for w in seen.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        out.insert(a.frame, a.person);
        if b.frame - a.frame - 1 > fill {
            continue;
        }
        for f in a.frame + 1..b.frame {
            let between = a.towards(b, f);
            if look.someone_else(f, &between).is_none() {
                out.insert(f, between);
            }
        }
    }
    if let Some(s) = seen.last() {
        out.insert(s.frame, s.person);
    }
    for (f, b) in leads(&seen, reach) {
        if look.someone_else(f, &b).is_none() {
            out.insert(f, b);
        }
    }
    out
}

/// The boxes of the `lead` frames before and after each stretch of `seen`
/// that the interpolation bridges (the track's ends and the gaps longer
/// than `fill`), within the pass, moved on at the speed between the
/// stretch's end and its sighting nearest half a second (15 frames) from it.
fn leads(seen: &[Sighting], reach: &Reach) -> Vec<(usize, PersonBox)> {
    let mut out = Vec::new();
    let stretches = seen.chunk_by(|a, b| b.frame - a.frame - 1 <= reach.fill);
    for part in stretches {
        let (first, last) = (&part[0], &part[part.len() - 1]);
        let within = |a: &Sighting, s: &&Sighting| s.frame.abs_diff(a.frame) <= 15;
        let start = part.iter().take_while(|s| within(first, s)).last();
        let end = part.iter().rev().take_while(|s| within(last, s)).last();
        let before = first.frame.saturating_sub(reach.lead).max(reach.range.0);
        let after = (last.frame + reach.lead).min(reach.range.1);
        out.extend((before..first.frame).map(|f| (f, moved(first, start.unwrap_or(first), f))));
        out.extend((last.frame + 1..=after).map(|f| (f, moved(last, end.unwrap_or(last), f))));
    }
    out
}

/// The box of `at` moved to `frame` at the speed from `at` to `other`.
fn moved(at: &Sighting, other: &Sighting, frame: usize) -> PersonBox {
    let span = other.frame as f32 - at.frame as f32;
    let k = if span == 0.0 {
        0.0
    } else {
        (frame as f32 - at.frame as f32) / span
    };
    let shift = |p: [f32; 2], q: [f32; 2], r: [f32; 2]| {
        [r[0] + k * (q[0] - p[0]), r[1] + k * (q[1] - p[1])]
    };
    PersonBox {
        centre: shift(at.person.centre, other.person.centre, at.person.centre),
        top: shift(at.person.centre, other.person.centre, at.person.top),
        score: at.person.score,
        interpolated: false,
    }
}

/// How much further (times `max_colour_distance`) the colours of a sighting
/// right on the subject's way may differ from the subject's.
const NEAR_COLOUR: f32 = 1.5;

/// Tells the subject from other people on its way, by its colours.
struct Lookalike<'a> {
    tracks: &'a [TrackSummary],
    chosen: usize,
    own: &'a [Sighting],
    /// Frames either side whose sightings give the subject's colours.
    window: usize,
    max_colour: f32,
}

impl Lookalike<'_> {
    /// The subject's colours around `frame`: the mean of its sightings
    /// within `window` frames. Over a whole walk they drift with the light
    /// (backlit, in a tree's shade): against the mean of the whole track the
    /// walker of the sample at 60 fps differed by 0.10-0.13 at frames 159
    /// and 175 and was taken for someone else.
    fn colours(&self, frame: usize) -> Appearance {
        let near = |s: &&Sighting| s.frame.abs_diff(frame) <= self.window;
        Appearance::mean(self.own.iter().filter(near).map(|s| &s.appearance))
    }

    /// Another track's sightings in `frame` on the box `b`, nearest first,
    /// with whether each is the subject: in its colours, or close to them
    /// ([`NEAR_COLOUR`]) right on its way (within a tenth of a body). The
    /// sample's walker passes through shade where her colours differ from
    /// those around by 0.10-0.14 for a few frames, on her way to a few
    /// pixels; a bystander there differs by more or stands off her way.
    fn on_box(&self, frame: usize, b: &PersonBox) -> Vec<(&Sighting, bool)> {
        let colours = self.colours(frame);
        let size = |o: &Sighting| b.size().max(o.person.size());
        let mut on: Vec<(&Sighting, bool)> = (self.tracks.iter().enumerate())
            .filter(|(i, _)| *i != self.chosen)
            .filter_map(|(_, t)| t.sighting_at(frame))
            .filter(|o| o.person.distance(b) < 0.5 * size(o))
            .map(|o| {
                let d = colours.distance(&o.appearance).unwrap_or(f32::INFINITY);
                let on_way = o.person.distance(b) < 0.1 * size(o);
                let max = self.max_colour * if on_way { NEAR_COLOUR } else { 1.0 };
                (o, d <= max)
            })
            .collect();
        on.sort_by(|x, y| x.0.person.distance(b).total_cmp(&y.0.person.distance(b)));
        on
    }

    /// Someone in other colours on the box `b` in `frame`.
    fn someone_else(&self, frame: usize, b: &PersonBox) -> Option<&Sighting> {
        self.on_box(frame, b)
            .into_iter()
            .find(|o| !o.1)
            .map(|o| o.0)
    }

    /// `own` with, in each gap of more than `fill` and at most `max_gap`
    /// frames, the nearest sighting in the subject's colours on its way.
    fn across_long_gaps(&self, own: &[Sighting], fill: usize, max_gap: usize) -> Vec<Sighting> {
        let mut out = Vec::with_capacity(own.len());
        for w in own.windows(2) {
            let (a, b) = (&w[0], &w[1]);
            out.push(*a);
            let gap = b.frame - a.frame - 1;
            if gap <= fill || gap > max_gap {
                continue;
            }
            for f in a.frame + 1..b.frame {
                let on = self.on_box(f, &a.towards(b, f));
                if let Some((o, true)) = on.first() {
                    out.push(**o);
                }
            }
        }
        out.extend(own.last().copied());
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::{Track, tests::seen};

    fn reach() -> Reach {
        Reach {
            fill: 30,
            max_gap: 60,
            lead: 0,
            range: (0, 200),
        }
    }

    fn summary(id: usize, sightings: Vec<Sighting>) -> TrackSummary {
        TrackSummary::new(id, Track { sightings }, 30.0)
    }

    /// A walker from right to left, 10 px a frame, body size 400.
    fn walker(f: usize, grey: f32) -> Sighting {
        seen(f, 1500.0 - 10.0 * f as f32, 400.0, grey)
    }

    #[test]
    fn a_long_gap_takes_the_subjects_sightings_from_another_track() {
        // Frames 40-79 of the walker went to a second track (the linker lost
        // her where her detected size jumped); someone in other colours is
        // seen on her way in 85-90, inside a later long gap.
        let own: Vec<Sighting> = (0..40)
            .chain(80..84)
            .chain(120..130)
            .map(|f| walker(f, 0.3))
            .collect();
        let taken: Vec<Sighting> = (40..80).map(|f| walker(f, 0.32)).collect();
        let other: Vec<Sighting> = (85..91).map(|f| walker(f, 0.8)).collect();
        let tracks = vec![summary(0, own), summary(1, taken), summary(2, other)];
        let b = boxes(&tracks, 0, &reach(), 0.1);
        assert!((0..84).all(|f| b.contains_key(&f)), "{:?}", b.keys());
        assert!((84..120).all(|f| !b.contains_key(&f)), "{:?}", b.keys());
        assert!((120..130).all(|f| b.contains_key(&f)));
    }

    #[test]
    fn a_short_gap_is_bridged_over_the_subject_in_shade_but_not_over_someone_else() {
        let own: Vec<Sighting> = (0..20).chain(26..40).map(|f| walker(f, 0.3)).collect();
        // In shade, right on her way: 0.13 darker.
        let shade: Vec<Sighting> = (20..26).map(|f| walker(f, 0.17)).collect();
        let tracks = vec![summary(0, own.clone()), summary(1, shade)];
        assert_eq!(boxes(&tracks, 0, &reach(), 0.1).len(), 40);
        // The same colours a quarter body off her way: someone else.
        let beside: Vec<Sighting> = (20..26)
            .map(|f| seen(f, 1600.0 - 10.0 * f as f32, 400.0, 0.17))
            .collect();
        let tracks = vec![summary(0, own), summary(1, beside)];
        let b = boxes(&tracks, 0, &reach(), 0.1);
        assert!((20..26).all(|f| !b.contains_key(&f)), "{:?}", b.keys());
    }
}
