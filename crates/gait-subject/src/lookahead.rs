//! A link at the edge of what the linker allows is weighed against the next
//! few frames before it is made. Where a person passes in front of another
//! the detector often misses the one in front for a few frames, and her
//! track, looking for her, reaches the other's box at the limit of distance
//! and size at once. If within a detector miss she is seen again where her
//! own track was heading, at her size, the marginal box was someone else's:
//! the link is refused and her track waits for her. The sample's HDR copy:
//! at frame 86 her track took the man's box (size ratio 1.40 against a
//! limit of 1.4, 0.97 of the distance it may move), and from 92 his old
//! track took her; the walker's result was his. A box that grows at the
//! limit and stays grown (her legs coming back into view) finds no such
//! sighting and is linked as before; only a box bigger than the track's, off
//! its way, is ever refused ([`contradicted`]).

use crate::track::{LinkLimits, Sighting, Track};

/// A link is marginal when the sum of its squared distance and size change,
/// each against its limit, exceeds this: near both limits at once (each
/// alone may reach its limit: a walker's box jumps in size where her feet
/// leave the image, and moves far where she is missed for a frame).
const MARGINAL: f32 = 1.0;
/// A later sighting confirms the track's own way when that sum is at most
/// this: well inside both limits.
const CONFIRMING: f32 = 0.5;
/// The marginal box is another body only when its centre lies off the way
/// from the track's last sighting to the confirming one by more than this
/// share of the track's body size: the man the HDR copy's walker passed
/// 0.19-0.30, her own box grown where her legs came back into view (CRF 28,
/// the detector boxing her whole and then her upper body again) 0.06.
const OFF_WAY: f32 = 0.1;

/// Whether linking `s` to `track` is marginal and contradicted by the frames
/// `later` (after `s`'s, in frame order): a sighting within a detector miss
/// of the track's last one fits the track well, in its colours, is not the
/// person of `s` moving on, and places the track's body away from `s`. Only
/// a box bigger than the track's is refused: a smaller one at the limits is
/// most often the same person partly hidden (the detector boxes her upper
/// body while she passes behind someone), and refusing those split the
/// walker's track in two that took her frames in turn (the sample at 720p
/// with a long exposure, tests/robustness.rs).
pub(crate) fn contradicted(
    track: &Track,
    s: &Sighting,
    later: &[(usize, Vec<Sighting>)],
    limits: &LinkLimits,
) -> bool {
    if s.person.size() <= track.size() || strain(track, s, limits) <= MARGINAL {
        return false;
    }
    let last = track.last();
    let horizon = last.frame + limits.short_gap_frames + 1;
    let (look, size) = (track.appearance(), track.size().max(1.0));
    let other = Track {
        sightings: vec![*s],
    };
    later
        .iter()
        .take_while(|(frame, _)| *frame <= horizon)
        .flat_map(|(_, seen)| seen)
        .any(|x| {
            let colours = look.distance(&x.appearance);
            let off_way = s.person.distance(&last.towards(x, s.frame)) / size;
            strain(track, x, limits) <= CONFIRMING
                && colours.is_none_or(|c| c <= limits.max_colour_distance)
                && other.cost(x, limits).is_none()
                && off_way > OFF_WAY
        })
}

/// `(distance / reach)^2 + (size change / largest size change)^2` of `s`
/// against `track`; infinite where the track may not take `s` at all.
fn strain(track: &Track, s: &Sighting, limits: &LinkLimits) -> f32 {
    if track.cost(s, limits).is_none() {
        return f32::INFINITY;
    }
    let (d, reach) = track.offset(s);
    let ratio = (s.person.size().max(1.0) / track.size().max(1.0))
        .ln()
        .abs();
    (d / reach).powi(2) + (ratio / limits.max_size_ratio.ln()).powi(2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::tests::{LIMITS, seen};

    fn walker_to(frame: usize) -> Track {
        Track {
            sightings: (0..=frame)
                .map(|f| seen(f, 1000.0 - 10.0 * f as f32, 400.0, 0.3))
                .collect(),
        }
    }

    #[test]
    fn a_marginal_box_is_refused_when_the_track_is_seen_again_on_its_way() {
        let track = walker_to(20);
        // Someone 1.39 times her size, 0.73 of the reach away, at frame 21.
        let big = seen(21, 790.0 + 70.0, 556.0, 0.32);
        let st = strain(&track, &big, &LIMITS);
        assert!(st > MARGINAL, "{st}");
        // She is seen again at 25 where she was heading.
        let later = vec![
            (22, vec![seen(22, 790.0 + 70.0, 556.0, 0.32)]),
            (25, vec![seen(25, 750.0, 380.0, 0.3)]),
        ];
        assert!(contradicted(&track, &big, &later, &LIMITS));
        // Without her, the box is hers (it grew and stays grown).
        assert!(!contradicted(&track, &big, &later[..1], &LIMITS));
        // A well-fitting box is never refused.
        let near = seen(21, 790.0, 410.0, 0.3);
        assert!(!contradicted(&track, &near, &later, &LIMITS));
        // Nor a smaller one at the limits (her upper body boxed alone).
        let part = seen(21, 790.0 - 70.0, 290.0, 0.3);
        assert!(strain(&track, &part, &LIMITS) > MARGINAL);
        assert!(!contradicted(&track, &part, &later, &LIMITS));
        // Nor a bigger one on her own way (her whole body boxed again).
        let whole = seen(21, 790.0 + 30.0, 556.0, 0.3);
        assert!(strain(&track, &whole, &LIMITS) > MARGINAL);
        let later_on_way = vec![(25, vec![seen(25, 750.0, 380.0, 0.3)])];
        assert!(!contradicted(&track, &whole, &later_on_way, &LIMITS));
    }
}
