//! How much a track walks: its longest sustained displacement across the
//! view in one direction at a walking (or running) pace.

use serde::Serialize;

use crate::track::Track;

/// Slowest pace that counts as moving across the view, body sizes per second
/// (a slow pathological walk of 0.3 m/s is about 0.15 body sizes/s).
const MIN_PACE: f32 = 0.08;
/// Faster than this is a detection jumping between people, not a walk.
const MAX_PACE: f32 = 4.0;
/// The pace is taken over this window, so that the sway of each step and a
/// detector's jitter do not flip the direction.
const WINDOW_S: f32 = 0.5;

/// A track's longest walk.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Walk {
    /// Horizontal displacement in body sizes (the walking score).
    pub displacement: f32,
    /// Its duration in seconds.
    pub seconds: f32,
    /// +1 towards the image right, -1 towards the left, 0 without a walk.
    pub direction: i8,
    pub first_frame: usize,
    pub last_frame: usize,
}

/// The longest run of sightings that move the same way at a walking pace.
pub fn longest_walk(track: &Track, fps: f64) -> Walk {
    let s = &track.sightings;
    let fps = fps as f32;
    let half = ((WINDOW_S * fps / 2.0).round() as usize).max(1);
    // Pace at each sighting over the window around it, body sizes/s.
    let pace: Vec<f32> = (0..s.len())
        .map(|i| {
            let (a, b) = (&s[i.saturating_sub(half)], &s[(i + half).min(s.len() - 1)]);
            let dt = (b.frame - a.frame) as f32 / fps;
            let size = 0.5 * (a.person.size() + b.person.size());
            if dt <= 0.0 || size <= 0.0 {
                0.0
            } else {
                (b.person.centre[0] - a.person.centre[0]) / size / dt
            }
        })
        .collect();
    let moving = |p: f32| (MIN_PACE..=MAX_PACE).contains(&p.abs());
    let mut best = Walk::default();
    let mut i = 0;
    while i < s.len() {
        if !moving(pace[i]) {
            i += 1;
            continue;
        }
        let sign = pace[i].signum();
        let mut j = i;
        while j + 1 < s.len() && moving(pace[j + 1]) && pace[j + 1].signum() == sign {
            j += 1;
        }
        let sizes: f32 = s[i..=j].iter().map(|x| x.person.size()).sum::<f32>() / (j - i + 1) as f32;
        let dx = s[j].person.centre[0] - s[i].person.centre[0];
        let walk = Walk {
            displacement: dx.abs() / sizes.max(1.0),
            seconds: (s[j].frame - s[i].frame) as f32 / fps,
            direction: sign as i8,
            first_frame: s[i].frame,
            last_frame: s[j].frame,
        };
        if walk.displacement > best.displacement {
            best = walk;
        }
        i = j + 1;
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::tests::seen;

    #[test]
    fn a_walk_across_the_view_scores_its_displacement() {
        // 400 px bodies walking 6 px/frame to the left at 30 fps (0.45 sizes/s)
        // for 100 frames, after 30 frames standing.
        let track = Track {
            sightings: (0..130)
                .map(|f| seen(f, 1600.0 - 6.0 * f.saturating_sub(30) as f32, 400.0, 0.5))
                .collect(),
        };
        let w = longest_walk(&track, 30.0);
        assert_eq!(w.direction, -1);
        assert!((w.displacement - 1.5).abs() < 0.1, "{w:?}");
        assert!((25..=35).contains(&w.first_frame), "{w:?}");
        assert_eq!(w.last_frame, 129);
    }

    #[test]
    fn standing_and_jumping_in_place_is_no_walk() {
        let track = Track {
            sightings: (0..100)
                .map(|f| seen(f, 800.0 + 3.0 * ((f as f32) * 0.7).sin(), 400.0, 0.5))
                .collect(),
        };
        assert_eq!(longest_walk(&track, 30.0).displacement, 0.0);
    }
}
