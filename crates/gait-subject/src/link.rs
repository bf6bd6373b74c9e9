//! Links the people seen in each frame into tracks: one track per person,
//! by predicted position, body size and appearance.

use crate::lookahead;
use crate::track::{LinkLimits, Sighting, Track};

/// Sightings whose body axis leans further than this from upright (radians)
/// are detector errors for a walking subject (e.g. a box turned upside
/// down on a half-hidden body): they are not linked into any track.
const MAX_TILT: f32 = std::f32::consts::FRAC_PI_4;

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
mod tests {
    use super::*;
    use crate::track::tests::{LIMITS, seen};

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
