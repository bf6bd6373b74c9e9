//! Frames the subject pass's detector may skip (`[subject] detect_every`).
//! Between two detected frames a few frames apart whose people pair up one to
//! one (each moved a little, kept its size and stands clearly apart from
//! the others), the people of the frames between are interpolated. Anywhere
//! else (nobody in view, someone comes into view or leaves, is missed, or
//! people meet) every frame is detected, so the tracks are linked from the
//! same evidence as with a detection in every frame.

use gait_core::PersonBox;

use crate::track::Sighting;

/// Largest move of a person between the two detected frames, in body sizes
/// per frame: a walker covers about 0.02, a runner 0.07, and the detector's
/// box wobbles by a few hundredths from frame to frame.
const MAX_MOVE_PER_FRAME: f32 = 0.1;
/// Largest change of body size between the two detected frames (the
/// detector's box of a walker changes by 5-15 % from frame to frame; it
/// jumps by half where a foot leaves the image).
const MAX_SIZE_RATIO: f32 = 1.25;
/// People closer than this (centre to centre, in sizes of the larger) are
/// detected in every frame: where they meet, boxes merge, swap or drop out.
const MIN_APART: f32 = 1.0;
/// A detection under this score may drop out in the frames between:
/// detected in every frame. BlazePose's detector keeps people from 0.5; on
/// the sample the walker scores 0.5-0.97 and a weak box on her comes and
/// goes with the next frame anyway.
const MIN_SCORE: f32 = 0.5;

/// The people of each frame strictly between the detected frames `a` and `b`
/// (frame index and the people seen there), interpolated, or `None` when
/// those frames need the detector.
pub fn between(
    a: (usize, &[Sighting]),
    b: (usize, &[Sighting]),
) -> Option<Vec<(usize, Vec<PersonBox>)>> {
    let ((fa, sa), (fb, sb)) = (a, b);
    if fb <= fa + 1 {
        return Some(Vec::new());
    }
    // Nobody either side: someone seen only in between (the subject's first
    // glimpse, as at frame 59 of the sample's HEVC copy) would be lost.
    if sa.is_empty() {
        return None;
    }
    let pairs = pairs(sa, sb, (fb - fa) as f32)?;
    if !apart(sa) || !apart(sb) {
        return None;
    }
    Some(
        (fa + 1..fb)
            .map(|f| {
                let t = (f - fa) as f32 / (fb - fa) as f32;
                let boxes = pairs
                    .iter()
                    .map(|(p, q)| PersonBox {
                        interpolated: true,
                        ..p.person.lerp(&q.person, t)
                    })
                    .collect();
                (f, boxes)
            })
            .collect(),
    )
}

/// Each person of `a` with the one of `b` that is nearest to it and to
/// which it is nearest, when every person pairs up within the limits over
/// `frames` frames.
fn pairs<'a>(
    a: &'a [Sighting],
    b: &'a [Sighting],
    frames: f32,
) -> Option<Vec<(&'a Sighting, &'a Sighting)>> {
    if a.len() != b.len() {
        return None;
    }
    let nearest = |s: &Sighting, among: &'a [Sighting]| {
        among.iter().min_by(|x, y| {
            s.person
                .distance(&x.person)
                .total_cmp(&s.person.distance(&y.person))
        })
    };
    a.iter()
        .map(|p| {
            let q = nearest(p, b)?;
            let back = nearest(q, a)?;
            let size = p.person.size().max(1.0);
            let ratio = q.person.size().max(1.0) / size;
            let close = p.person.distance(&q.person) <= MAX_MOVE_PER_FRAME * frames * size;
            let same_size = (1.0 / MAX_SIZE_RATIO..=MAX_SIZE_RATIO).contains(&ratio);
            let sure = p.person.score.min(q.person.score) >= MIN_SCORE;
            (std::ptr::eq(back, p) && close && same_size && sure).then_some((p, q))
        })
        .collect()
}

/// Whether every two people in one frame stand clearly apart.
fn apart(people: &[Sighting]) -> bool {
    people.iter().enumerate().all(|(i, p)| {
        people[i + 1..].iter().all(|q| {
            let size = p.person.size().max(q.person.size()).max(1.0);
            p.person.distance(&q.person) >= MIN_APART * size
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::tests::seen;

    fn people(f: usize, xs: &[f32]) -> Vec<Sighting> {
        xs.iter().map(|&x| seen(f, x, 400.0, 0.3)).collect()
    }

    #[test]
    fn two_people_apart_are_interpolated_between_detections() {
        let (a, b) = (people(10, &[500.0, 1500.0]), people(12, &[520.0, 1500.0]));
        let got = between((10, &a), (12, &b)).expect("unambiguous");
        assert_eq!(got.len(), 1);
        let (f, boxes) = &got[0];
        assert_eq!(*f, 11);
        assert_eq!(boxes.len(), 2);
        assert!(boxes.iter().all(|b| b.interpolated));
        assert!((boxes[0].centre[0] - 510.0).abs() < 1e-3, "{boxes:?}");
        assert!((boxes[1].centre[0] - 1500.0).abs() < 1e-3);
        // Nobody in view either side: a glimpse between must not be lost.
        assert!(between((0, &[]), (2, &[])).is_none());
    }

    #[test]
    fn emptiness_arrivals_jumps_meetings_and_weak_detections_are_detected() {
        let a = people(10, &[500.0, 1500.0]);
        // Someone came into view.
        let b = people(12, &[520.0, 1500.0, 900.0]);
        assert!(between((10, &a), (12, &b)).is_none());
        // One moved a body size in two frames: not the same person, or a jump.
        let b = people(12, &[900.0, 1500.0]);
        assert!(between((10, &a), (12, &b)).is_none());
        // One's box grew by half.
        let mut b = people(12, &[520.0, 1500.0]);
        b[0].person.top[1] -= 80.0;
        assert!(between((10, &a), (12, &b)).is_none());
        // Two people side by side.
        let (a2, b2) = (people(10, &[500.0, 600.0]), people(12, &[510.0, 600.0]));
        assert!(between((10, &a2), (12, &b2)).is_none());
        // A weak detection.
        let mut b = people(12, &[520.0, 1500.0]);
        b[1].person.score = 0.45;
        assert!(between((10, &a), (12, &b)).is_none());
        // Neighbouring frames: nothing between.
        assert_eq!(between((10, &a), (11, &a)), Some(vec![]));
    }
}
