//! Joins tracks the linker made of one person: a second box on the same
//! body, a track that takes over where another ended, and two tracks that
//! take one person's frames in turn.

use crate::track::{LinkLimits, Track};

/// Two tracks are one person only when their boxes coincide in at least this
/// many frames (or in every frame of the shorter one): a single shared frame
/// is a chance, e.g. where the walker passes in front of someone.
const MIN_SHARED: usize = 3;

/// Joins tracks that are one person seen twice: the detector sometimes
/// returns a second box on the same body (another size, half the body), and
/// the linker then starts a second track that takes over from the first one
/// (e.g. where the person turns and the first track's prediction misses).
/// Two tracks are joined when they overlap in time, both are seen in at
/// least half the frames where either is seen over that time, their boxes
/// coincide (centres within a third of the body size) in every frame both
/// are seen, and their colours match. Also joined: a track that starts
/// within a detector miss of another's end, where that one was heading, in
/// its colours, at up to twice the size ratio a link allows (the detector's
/// size of a walker jumps where she turns or her arms swing wide). And two
/// tracks that take one person's frames in turn ([`in_turn`]).
pub fn stitch(mut tracks: Vec<Track>, limits: &LinkLimits) -> Vec<Track> {
    let mut i = 0;
    while i < tracks.len() {
        let mut j = i + 1;
        while j < tracks.len() {
            let (a, b) = (&tracks[i], &tracks[j]);
            if same_person(a, b, limits)
                || continues(a, b, limits)
                || continues(b, a, limits)
                || in_turn(a, b, limits)
            {
                let other = tracks.remove(j);
                merge(&mut tracks[i], other);
                j = i + 1;
            } else {
                j += 1;
            }
        }
        i += 1;
    }
    tracks
}

fn same_person(a: &Track, b: &Track, limits: &LinkLimits) -> bool {
    let mut shared = 0;
    for s in &a.sightings {
        let Ok(k) = b.sightings.binary_search_by_key(&s.frame, |x| x.frame) else {
            continue;
        };
        let o = &b.sightings[k];
        let size = s.person.size().max(o.person.size()).max(1.0);
        if s.person.distance(&o.person) > size / 3.0 {
            return false;
        }
        shared += 1;
    }
    let colours = a.appearance().distance(&b.appearance());
    let shorter = a.sightings.len().min(b.sightings.len());
    // One body seen twice gives two boxes in most frames where both tracks
    // run; two people meet for a few frames of a long common span.
    let (first, last) = (
        a.sightings[0].frame.max(b.sightings[0].frame),
        a.last().frame.min(b.last().frame),
    );
    let in_span = |t: &Track| {
        t.sightings
            .iter()
            .filter(|s| (first..=last).contains(&s.frame))
            .count()
    };
    let either = in_span(a) + in_span(b) - shared;
    shared >= MIN_SHARED.min(shorter)
        && 2 * shared >= either
        && colours.is_some_and(|c| c <= limits.max_colour_distance)
}

/// Whether `b` takes over where `a` ended (see [`stitch`]).
fn continues(a: &Track, b: &Track, limits: &LinkLimits) -> bool {
    let (end, start) = (a.last(), &b.sightings[0]);
    if start.frame <= end.frame || start.frame - end.frame > limits.short_gap_frames + 1 {
        return false;
    }
    let (d, reach) = a.offset(start);
    let size = a.size().max(1.0);
    let early = Track {
        sightings: b.sightings.iter().take(5).copied().collect(),
    };
    let ratio = (early.size().max(1.0) / size).ln().abs();
    let colours = a.appearance().distance(&b.appearance());
    d <= reach
        && ratio <= 2.0 * limits.max_size_ratio.ln()
        && colours.is_some_and(|c| c <= limits.max_colour_distance)
}

/// Whether `a` and `b` take one person's frames in turn: where both run, each
/// is seen where the other is not (or on the same spot), every sighting of
/// one lies on the other's way (the box interpolated between its sightings
/// either side, within half a body), at least [`MIN_SHARED`] of them, in
/// matching colours, and of sizes whose medians there are within the link's
/// size ratio. Single boxes may differ more: the detector boxes a walker
/// whole, then only her upper body while she passes behind someone, and the
/// linker, which allows no jump in size, starts a second track for the half
/// boxes (the sample mirrored and re-encoded twice: 102-128, where she passes
/// the man, went to a track of its own, and the walker's was cut at 100). The
/// man she passes, on her way for a few frames, is 1.8 times her size.
fn in_turn(a: &Track, b: &Track, limits: &LinkLimits) -> bool {
    let first = a.sightings[0].frame.max(b.sightings[0].frame);
    let last = a.last().frame.min(b.last().frame);
    if first >= last {
        return false;
    }
    let colours = a.appearance().distance(&b.appearance());
    colours.is_some_and(|c| c <= limits.max_colour_distance)
        && (median_size(a, first, last) / median_size(b, first, last))
            .ln()
            .abs()
            <= limits.max_size_ratio.ln()
        && on_way_of(a, b, first, last)
        && on_way_of(b, a, first, last)
}

/// The median body size of `t`'s sightings in `first..=last`.
fn median_size(t: &Track, first: usize, last: usize) -> f32 {
    let mut sizes: Vec<f32> = (t.sightings.iter())
        .filter(|s| (first..=last).contains(&s.frame))
        .map(|s| s.person.size().max(1.0))
        .collect();
    sizes.sort_by(f32::total_cmp);
    sizes.get(sizes.len() / 2).copied().unwrap_or(1.0)
}

/// Whether every sighting of `b` in `first..=last` (at least [`MIN_SHARED`])
/// lies on `a`'s way: on `a`'s own box in a frame `a` is seen, else within
/// half a body of the box interpolated between `a`'s sightings either side.
fn on_way_of(a: &Track, b: &Track, first: usize, last: usize) -> bool {
    let span = b
        .sightings
        .iter()
        .filter(|s| (first..=last).contains(&s.frame));
    let mut n = 0;
    for s in span {
        let k = a.sightings.partition_point(|x| x.frame < s.frame);
        let way = match (
            a.sightings.get(k),
            k.checked_sub(1).map(|j| &a.sightings[j]),
        ) {
            (Some(at), _) if at.frame == s.frame => at.person,
            (Some(next), Some(prev)) => prev.towards(next, s.frame),
            _ => return false,
        };
        let size = way.size().min(s.person.size()).max(1.0);
        if s.person.distance(&way) > 0.5 * size {
            return false;
        }
        n += 1;
    }
    n >= MIN_SHARED
}

/// `b`'s sightings added to `a`; where both saw the person, `a`'s stay.
fn merge(a: &mut Track, b: Track) {
    for s in b.sightings {
        if let Err(k) = a.sightings.binary_search_by_key(&s.frame, |x| x.frame) {
            a.sightings.insert(k, s);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::tests::{LIMITS, seen};

    #[test]
    fn a_second_box_on_the_same_body_is_stitched_to_its_track() {
        let first = Track {
            sightings: (0..20)
                .map(|f| seen(f, 500.0 - 5.0 * f as f32, 400.0, 0.3))
                .collect(),
        };
        // From frame 15 a bigger box on the same body, which carries on.
        let second = Track {
            sightings: (15..40)
                .map(|f| seen(f, 505.0 - 5.0 * f as f32, 520.0, 0.3))
                .collect(),
        };
        let other = Track {
            sightings: (15..40).map(|f| seen(f, 900.0, 400.0, 0.3)).collect(),
        };
        let tracks = stitch(vec![first, second, other], &LIMITS);
        assert_eq!(tracks.len(), 2);
        assert_eq!(tracks[0].sightings.len(), 40);
    }
}
