//! People found in a frame and the rule that picks the subject among them,
//! shared by the pose estimators (which find people) and the subject pass
//! (which links them into tracks and picks one).

use serde::{Deserialize, Serialize};

/// One person found in one frame, in the frame's pixels.
///
/// The body is given as BlazePose's detector gives it: a centre point (the
/// mid-hip) and a point towards the top of the body whose distance from the
/// centre is a fixed fraction of the body's size. An estimator told to follow
/// this person crops around exactly these two points.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PersonBox {
    /// Body centre (mid-hip), pixels.
    pub centre: [f32; 2],
    /// A point up the body axis at 0.4 body sizes from the centre, pixels.
    pub top: [f32; 2],
    /// The detector's score in [0, 1].
    pub score: f32,
    /// Interpolated between the detections of the frames either side (the
    /// subject pass ran no detector on this frame, see `[subject]
    /// detect_every`): an estimator that crops from the box detects again.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub interpolated: bool,
}

impl PersonBox {
    /// The side of a square that holds the whole body, pixels.
    pub fn size(&self) -> f32 {
        let d = (self.top[0] - self.centre[0]).hypot(self.top[1] - self.centre[1]);
        2.5 * d
    }

    /// A person box from a body centre and size (an upright body).
    pub fn upright(cx: f32, cy: f32, size: f32, score: f32) -> Self {
        Self {
            centre: [cx, cy],
            top: [cx, cy - size / 2.5],
            score,
            interpolated: false,
        }
    }

    /// The box a share `t` of the way from `self` to `other` (centre and top
    /// point on straight lines; the lower score).
    pub fn lerp(&self, other: &PersonBox, t: f32) -> Self {
        let mix = |p: [f32; 2], q: [f32; 2]| [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])];
        Self {
            centre: mix(self.centre, other.centre),
            top: mix(self.top, other.top),
            score: self.score.min(other.score),
            interpolated: false,
        }
    }

    /// `xmin, ymin, xmax, ymax` of the square body box, pixels.
    pub fn bounds(&self) -> [f32; 4] {
        let h = self.size() / 2.0;
        let [x, y] = self.centre;
        [x - h, y - h, x + h, y + h]
    }

    /// Distance between the centres of two boxes, pixels.
    pub fn distance(&self, other: &PersonBox) -> f32 {
        (self.centre[0] - other.centre[0]).hypot(self.centre[1] - other.centre[1])
    }
}

/// Which person is the subject when several are in view (`[pose] person`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum PersonChoice {
    /// A rule over the people (or tracks) in view.
    Rule(PersonRule),
    /// The track nearest this point in this frame.
    At(PersonAt),
}

impl Default for PersonChoice {
    fn default() -> Self {
        PersonChoice::Rule(PersonRule::Walker)
    }
}

impl PersonChoice {
    /// The rule, unless the choice is a point.
    pub fn rule(self) -> Option<PersonRule> {
        match self {
            PersonChoice::Rule(r) => Some(r),
            PersonChoice::At(_) => None,
        }
    }
}

/// `person = { frame = N, x = X, y = Y }`: the person nearest (x, y) in frame N.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PersonAt {
    pub frame: usize,
    pub x: f32,
    pub y: f32,
}

/// The named rules of [`PersonChoice`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PersonRule {
    /// The person who walks across the view (the longest walking track).
    Walker,
    /// The biggest body (usually the one nearest the camera).
    Largest,
    Leftmost,
    Rightmost,
    /// Nearest the image centre.
    MostCentral,
    /// The model's best score.
    MostConfident,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Deserialize)]
    struct T {
        person: PersonChoice,
    }

    #[test]
    fn choice_reads_a_name_or_a_point() {
        let t: T = toml::from_str("person = \"walker\"").unwrap();
        assert_eq!(t.person, PersonChoice::Rule(PersonRule::Walker));
        let t: T = toml::from_str("person = \"most_central\"").unwrap();
        assert_eq!(t.person.rule(), Some(PersonRule::MostCentral));
        let t: T = toml::from_str("person = { frame = 12, x = 300.5, y = 200 }").unwrap();
        assert_eq!(
            t.person,
            PersonChoice::At(PersonAt {
                frame: 12,
                x: 300.5,
                y: 200.0
            })
        );
        assert!(toml::from_str::<T>("person = \"tallest\"").is_err());
        assert_eq!(PersonChoice::default().rule(), Some(PersonRule::Walker));
    }

    #[test]
    fn box_geometry() {
        let b = PersonBox::upright(100.0, 200.0, 50.0, 0.9);
        assert!((b.size() - 50.0).abs() < 1e-4);
        assert_eq!(b.bounds(), [75.0, 175.0, 125.0, 225.0]);
    }
}
