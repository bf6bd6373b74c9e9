//! Which detected person to follow (see [`crate::person`]).

use super::PersonChoice;
use super::detection::Detection;
use super::roi::Roi;
use crate::person::{self as choice, Candidate};

/// The crop of the chosen person among `dets` (best score first) in a
/// `width` x `height` image. `last` is the centre of the person followed until
/// now (normalised); a detection within one crop side of it wins.
pub fn choose(
    dets: &[Detection],
    person: PersonChoice,
    last: Option<(f32, f32)>,
    width: u32,
    height: u32,
) -> Option<Roi> {
    let (wf, hf) = (width as f32, height as f32);
    let rois: Vec<Roi> = dets
        .iter()
        .map(|d| Roi::from_alignment(d.keypoints[0], d.keypoints[1], width, height))
        .collect();
    let people: Vec<Candidate> = rois
        .iter()
        .zip(dets)
        .map(|(r, d)| Candidate {
            cx: r.cx * wf,
            cy: r.cy * hf,
            size: r.side_px(width, height),
            score: d.score,
        })
        .collect();
    let last = last.map(|(x, y)| (x * wf, y * hf));
    choice::choose(&people, person, last, width, height).map(|i| rois[i])
}
#[cfg(test)]
mod tests {
    use super::*;
    use gait_core::PersonRule;

    /// An upright person with hips at (x, y) and body size `s` (normalised).
    fn det(score: f32, x: f32, y: f32, s: f32) -> Detection {
        Detection {
            score,
            bbox: [x - s, y - s, x + s, y + s],
            keypoints: [(x, y), (x, y - s), (x, y - s / 2.0), (x, y - s)],
        }
    }

    #[test]
    fn each_choice() {
        // Best score first: a small person at the left, a big one right of centre, one far right.
        let dets = [
            det(0.9, 0.1, 0.5, 0.05),
            det(0.8, 0.6, 0.5, 0.2),
            det(0.7, 0.9, 0.5, 0.1),
        ];
        let pick = |r| {
            choose(&dets, PersonChoice::Rule(r), None, 100, 100)
                .unwrap()
                .cx
        };
        assert!((pick(PersonRule::MostConfident) - 0.1).abs() < 1e-6);
        assert!((pick(PersonRule::Leftmost) - 0.1).abs() < 1e-6);
        assert!((pick(PersonRule::Rightmost) - 0.9).abs() < 1e-6);
        assert!((pick(PersonRule::Largest) - 0.6).abs() < 1e-6);
        assert!((pick(PersonRule::MostCentral) - 0.6).abs() < 1e-6);
        assert!(choose(&[], PersonChoice::default(), None, 100, 100).is_none());
    }

    #[test]
    fn re_detection_stays_with_the_followed_person() {
        let dets = [det(0.9, 0.6, 0.5, 0.2), det(0.8, 0.12, 0.5, 0.05)];
        let largest = PersonChoice::Rule(PersonRule::Largest);
        let r = choose(&dets, largest, Some((0.1, 0.5)), 100, 100).unwrap();
        assert!((r.cx - 0.12).abs() < 1e-6);
        // Nobody near the old position: back to the configured choice.
        let r = choose(
            &dets[..1],
            PersonChoice::Rule(PersonRule::Leftmost),
            Some((0.1, 0.9)),
            100,
            100,
        )
        .unwrap();
        assert!((r.cx - 0.6).abs() < 1e-6);
    }
}
