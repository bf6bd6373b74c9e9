//! Which person an estimator follows on its own, when no subject pass tells
//! it (`estimate` without a subject): the first choice is made when a person
//! is first found (or lost and found again); after that the estimator keeps to
//! the person nearest to where the followed one was. Shared by the pose
//! estimators so that `person = "..."` means the same everywhere.

pub use gait_core::{PersonAt, PersonChoice, PersonRule};

/// A person found in one frame, in pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    pub cx: f32,
    pub cy: f32,
    /// Body size (e.g. the side of its crop or box).
    pub size: f32,
    pub score: f32,
}

/// Index of the person to follow among `people` in a `width` x `height`
/// image. With `last` (centre of the person followed until now, pixels), the
/// one nearest to it wins if it lies within its own body size, so the choice
/// stays with the same person; otherwise `choice` decides.
pub fn choose(
    people: &[Candidate],
    choice: PersonChoice,
    last: Option<(f32, f32)>,
    width: u32,
    height: u32,
) -> Option<usize> {
    let dist = |p: &Candidate, (x, y): (f32, f32)| (p.cx - x).hypot(p.cy - y);
    let best = |key: &dyn Fn(&Candidate) -> f32| {
        people
            .iter()
            .enumerate()
            .min_by(|a, b| key(a.1).total_cmp(&key(b.1)))
            .map(|(i, _)| i)
    };
    if let Some(c) = last {
        let near = people
            .iter()
            .enumerate()
            .filter(|(_, p)| dist(p, c) < p.size)
            .min_by(|a, b| dist(a.1, c).total_cmp(&dist(b.1, c)))
            .map(|(i, _)| i);
        if near.is_some() {
            return near;
        }
    }
    let centre = (width as f32 / 2.0, height as f32 / 2.0);
    match choice {
        PersonChoice::At(at) => best(&|p| dist(p, (at.x, at.y))),
        // Walking is a property of a track, not of one frame: on its own an
        // estimator falls back to the biggest body.
        PersonChoice::Rule(PersonRule::Walker | PersonRule::Largest) => best(&|p| -p.size),
        PersonChoice::Rule(PersonRule::MostConfident) => best(&|p| -p.score),
        PersonChoice::Rule(PersonRule::Leftmost) => best(&|p| p.cx),
        PersonChoice::Rule(PersonRule::Rightmost) => best(&|p| -p.cx),
        PersonChoice::Rule(PersonRule::MostCentral) => best(&|p| dist(p, centre)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(cx: f32, size: f32, score: f32) -> Candidate {
        Candidate {
            cx,
            cy: 50.0,
            size,
            score,
        }
    }

    #[test]
    fn each_choice() {
        // A small confident person at the left, a big one right of centre, one far right.
        let people = [at(10.0, 5.0, 0.9), at(60.0, 20.0, 0.8), at(90.0, 10.0, 0.7)];
        let pick = |r| choose(&people, PersonChoice::Rule(r), None, 100, 100).unwrap();
        assert_eq!(pick(PersonRule::MostConfident), 0);
        assert_eq!(pick(PersonRule::Leftmost), 0);
        assert_eq!(pick(PersonRule::Rightmost), 2);
        assert_eq!(pick(PersonRule::Largest), 1);
        assert_eq!(pick(PersonRule::Walker), 1);
        assert_eq!(pick(PersonRule::MostCentral), 1);
        let at = PersonChoice::At(PersonAt {
            frame: 0,
            x: 88.0,
            y: 50.0,
        });
        assert_eq!(choose(&people, at, None, 100, 100), Some(2));
        assert!(choose(&[], PersonChoice::default(), None, 100, 100).is_none());
    }

    #[test]
    fn stays_with_the_followed_person() {
        let people = [at(60.0, 20.0, 0.9), at(12.0, 5.0, 0.8)];
        let near_left = Some((10.0, 50.0));
        let largest = PersonChoice::Rule(PersonRule::Largest);
        assert_eq!(choose(&people, largest, near_left, 100, 100), Some(1));
        // Nobody near the old position: back to the configured choice.
        let far = Some((10.0, 90.0));
        assert_eq!(
            choose(
                &people[..1],
                PersonChoice::Rule(PersonRule::Leftmost),
                far,
                100,
                100
            ),
            Some(0)
        );
    }
}
