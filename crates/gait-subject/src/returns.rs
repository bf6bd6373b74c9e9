//! The subject walking across the view again: a patient asked to walk to the end of the room
//! and back leaves the view, turns where the camera does not see, and comes back seconds later
//! (the sample and its mirror one after the other: 3 s out of view), too late for the linker
//! to take the track up again. Another track is the subject's return when it is a walk of its
//! own, lies wholly before or after the subject's other walks, and has the subject's colours
//! and size; the pose passes then follow every walk.

use crate::choose::MIN_WALK;
use crate::{Appearance, SubjectConfig, TrackSummary};

/// A return must be seen in at least this share of the subject's own track's frames (one
/// stride across the view at least; a passer-by's glimpse is not a walk back).
const MIN_SHARE: f32 = 0.25;

/// The tracks (ids) that are the subject `chosen` walking across the view again, each with
/// how it matched (colour distance, size ratio), in frame order.
pub(crate) fn returns(
    tracks: &[TrackSummary],
    chosen: usize,
    config: &SubjectConfig,
) -> Vec<(usize, f32, f32)> {
    let subject = &tracks[chosen];
    let colours = appearance(subject);
    let mut taken: Vec<[usize; 2]> = vec![[subject.first_frame, subject.last_frame]];
    let mut out = Vec::new();
    let mut order: Vec<usize> = (0..tracks.len()).filter(|&i| i != chosen).collect();
    // The longest walks first: of two overlapping candidates the clearer one is taken.
    order.sort_by(|&a, &b| {
        tracks[b]
            .walk
            .displacement
            .total_cmp(&tracks[a].walk.displacement)
    });
    for i in order {
        let t = &tracks[i];
        let apart = taken
            .iter()
            .all(|[a, b]| t.last_frame < *a || t.first_frame > *b);
        if !apart
            || t.walk.displacement < MIN_WALK
            || (t.frames as f32) < MIN_SHARE * subject.frames as f32
        {
            continue;
        }
        let ratio = t.mean_size.max(1.0) / subject.mean_size.max(1.0);
        let ratio = ratio.max(1.0 / ratio);
        let Some(distance) = colours.distance(&appearance(t)) else {
            continue;
        };
        if distance <= config.max_colour_distance && ratio <= config.max_size_ratio {
            taken.push([t.first_frame, t.last_frame]);
            out.push((i, distance, ratio));
        }
    }
    out.sort_by_key(|&(i, _, _)| tracks[i].first_frame);
    out
}

/// A track's colours over all its sightings.
fn appearance(t: &TrackSummary) -> Appearance {
    Appearance::mean(t.sightings.iter().map(|s| &s.appearance))
}

#[cfg(test)]
mod tests {
    use gait_core::{PersonChoice, PersonRule};

    use crate::track::tests::seen;
    use crate::{SubjectConfig, find};

    /// A person standing all along (grey 0.8); the subject (grey 0.2) walks to the left over
    /// frames 20-99, is out of view for 4 s, and walks back to the right over frames 220-299;
    /// then someone in other colours (0.5) walks across at 330-409.
    fn there_and_back() -> Vec<(usize, Vec<crate::Sighting>)> {
        (0..420)
            .map(|f| {
                let mut people = vec![seen(f, 300.0, 500.0, 0.8)];
                let x = |from: f32, step: f32, start: usize| from + step * (f - start) as f32;
                if (20..100).contains(&f) {
                    people.push(seen(f, x(1600.0, -15.0, 20), 400.0, 0.2));
                }
                if (220..300).contains(&f) {
                    people.push(seen(f, x(500.0, 15.0, 220), 420.0, 0.2));
                }
                if (330..410).contains(&f) {
                    people.push(seen(f, x(1600.0, -15.0, 330), 400.0, 0.5));
                }
                (f, people)
            })
            .collect()
    }

    #[test]
    fn the_walk_back_is_followed_and_a_stranger_s_walk_is_not() {
        let cfg = SubjectConfig::default();
        let s = find(
            &there_and_back(),
            PersonChoice::default(),
            &cfg,
            30.0,
            (1800, 1000),
        )
        .unwrap();
        assert_eq!(s.returns.len(), 1, "{:?}", s.returns);
        let back = &s.returns[0];
        assert_eq!((back.first_frame, back.last_frame), (220, 299));
        assert!(back.colour_distance < 1e-6 && (back.size_ratio - 1.05).abs() < 1e-6);
        assert!(s.boxes.contains_key(&50) && s.boxes.contains_key(&260));
        assert!(
            !s.boxes.contains_key(&370),
            "the stranger's walk is not the subject's"
        );
        assert!(s.reason.contains("1 more walk"), "{}", s.reason);
        // Off, or with another rule than the walker: one walk only.
        let off = SubjectConfig {
            returns: false,
            ..cfg.clone()
        };
        let s = find(
            &there_and_back(),
            PersonChoice::default(),
            &off,
            30.0,
            (1800, 1000),
        )
        .unwrap();
        assert!(s.returns.is_empty());
        let largest = PersonChoice::Rule(PersonRule::Largest);
        let s = find(&there_and_back(), largest, &cfg, 30.0, (1800, 1000)).unwrap();
        assert!(s.returns.is_empty());
    }
}
