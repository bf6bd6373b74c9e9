//! Which view a run analyses: a side (sagittal) view, or a front (anterior: walking toward the
//! camera) or back (posterior: walking away) view. Declared in `kinematics.view` (the study
//! file's `view` column sets it) or decided from the keypoints.

use serde::{Deserialize, Serialize};

use crate::config::Side;
use crate::direction::Directions;
use crate::tracks::{Tracks, dist, median};

/// `kinematics.view`: what the camera saw, or `auto` to decide from the keypoints.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ViewSetting {
    #[default]
    Auto,
    /// Filmed from the subject's left side.
    Left,
    /// Filmed from the subject's right side.
    Right,
    /// From the front: the subject walks toward the camera.
    Anterior,
    /// From behind: the subject walks away from the camera.
    Posterior,
}

impl ViewSetting {
    pub fn name(self) -> &'static str {
        match self {
            ViewSetting::Auto => "auto",
            ViewSetting::Left => "left",
            ViewSetting::Right => "right",
            ViewSetting::Anterior => "anterior",
            ViewSetting::Posterior => "posterior",
        }
    }
}

/// The plane a run's angles are measured in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum View {
    Sagittal,
    Anterior,
    Posterior,
}

impl View {
    pub fn is_frontal(self) -> bool {
        self != View::Sagittal
    }

    /// +1 when the subject's left appears toward image +x (facing the camera), -1 when toward
    /// image -x (back to the camera), 0 for a side view.
    pub fn left_sign(self) -> f64 {
        match self {
            View::Anterior => 1.0,
            View::Posterior => -1.0,
            View::Sagittal => 0.0,
        }
    }

    /// The image x direction toward the subject's `side`.
    pub fn toward(self, side: Side) -> f64 {
        match side {
            Side::Left => self.left_sign(),
            Side::Right => -self.left_sign(),
        }
    }
}

/// The view analysed and what it was decided from (run.json `kinematics.view`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ViewDecision {
    pub view: View,
    pub declared: ViewSetting,
    /// One line: declared, or what the keypoints showed.
    pub how: String,
    /// Share of the frames that look frontal (hips or shoulders far apart, see `decide`).
    pub frontal_share: f64,
    /// Body size (mid-hip to mid-shoulder, else hip to ankle) at the end over the start of the
    /// frames where it is seen, from a fit: above 1 the walker comes nearer.
    pub growth: f64,
    /// Degrees between the walking direction and the camera's axis (0: toward or away, 90:
    /// across; [`crate::walk_angle`]); NaN when the frame size is not known.
    pub walk_angle_deg: f64,
}

/// A walker whose hips lie apart by more than half a thigh faces or backs the camera (as
/// [`crate::direction::detect`] judges each frame); the view is frontal when most frames are.
const FRONTAL_SHARE: f64 = 0.5;
/// Growth or shrinking by more than this factor says toward or away; less is not a walk along
/// the camera axis, and the hip order (the subject's left on the image right = facing) decides.
const GROWTH: f64 = 1.15;

/// Decides the view from gated keypoints (before any label correction), warning where the
/// keypoints disagree with a declared view; the declared view is analysed either way.
pub fn decide(t: &Tracks, declared: ViewSetting, warnings: &mut Vec<String>) -> ViewDecision {
    let share = frontal_share(t);
    let growth = growth(t);
    let facing = left_hip_on_image_right(t);
    let frontal_seen = share > FRONTAL_SHARE;
    let toward = if (growth.ln()).abs() > GROWTH.ln() {
        Some(growth > 1.0)
    } else {
        facing
    };
    let seen = format!(
        "hips or shoulders apart in {:.0} % of frames; body size x{growth:.2} over the video",
        100.0 * share
    );
    let view = match declared {
        ViewSetting::Auto => {
            let view = match (frontal_seen, toward) {
                (true, Some(true)) => View::Anterior,
                (true, Some(false)) => View::Posterior,
                _ => View::Sagittal,
            };
            let how = format!("auto: {seen}");
            return ViewDecision {
                view,
                declared,
                how,
                frontal_share: share,
                growth,
                walk_angle_deg: f64::NAN,
            };
        }
        ViewSetting::Left | ViewSetting::Right => View::Sagittal,
        ViewSetting::Anterior => View::Anterior,
        ViewSetting::Posterior => View::Posterior,
    };
    let disagree = match view {
        View::Sagittal => frontal_seen
            .then(|| "the hips or shoulders lie far apart as in a front or back view".to_string()),
        _ if !frontal_seen && share.is_finite() => {
            Some("the hips and shoulders lie close together as in a side view".into())
        }
        View::Anterior if toward == Some(false) => {
            Some("the walker moves away from the camera".into())
        }
        View::Posterior if toward == Some(true) => {
            Some("the walker comes toward the camera".into())
        }
        _ => None,
    };
    if let Some(why) = disagree {
        warnings.push(format!(
            "the keypoints disagree with kinematics.view = \"{}\": {why} ({seen}); analysed as declared",
            declared.name()
        ));
    }
    ViewDecision {
        view,
        declared,
        how: format!("declared in kinematics.view ({seen})"),
        frontal_share: share,
        growth,
        walk_angle_deg: f64::NAN,
    }
}

/// Frames with a walking direction needed to judge a declared side (seconds) ...
const SIDE_EVIDENCE_S: f64 = 1.0;
/// ... and the share of them that must show the other side: a short clip, or someone else
/// drawn for a few frames, is not evidence.
const SIDE_MAJORITY: f64 = 0.75;

/// A side view declared for one side (a visit's `--left`, `--right`) whose walker shows the
/// other side to the camera in most of at least a second of frames (at `fps`): the warning that
/// names it, else `None`. The walk's direction across the image says which leg is near:
/// walking toward the image's right, the subject's right side faces the camera.
pub fn side_disagreement(declared: ViewSetting, dirs: &Directions, fps: f64) -> Option<String> {
    let want = match declared {
        ViewSetting::Left => Side::Left,
        ViewSetting::Right => Side::Right,
        _ => return None,
    };
    let seen = dirs.near_side()?;
    let [right, left, _] = dirs.counts();
    let (most, all) = (right.max(left), right + left);
    let clear = all as f64 >= SIDE_EVIDENCE_S * fps && most as f64 >= SIDE_MAJORITY * all as f64;
    (seen != want && clear).then(|| {
        format!(
            "the keypoints disagree with kinematics.view = \"{}\": the {} leg is nearer the camera (the walker moves toward the image's {} in {most} of {all} frames with a direction); analysed as declared",
            declared.name(),
            seen.name(),
            seen.name(),
        )
    })
}

/// Share of the frames (with both hips and a knee seen) that look frontal: the hips apart by
/// more than half a thigh, or the shoulders apart by more than half the trunk's length. Seen
/// from the side both pairs overlap; from the front or back a pose model's hips lie about
/// 0.3-0.4 thigh lengths apart when it puts them at the joint centres (the Parkinson's trial's
/// hip joint centres: 14 cm apart over 40 cm thighs), while the shoulders lie 0.7-0.8 trunk
/// lengths apart.
fn frontal_share(t: &Tracks) -> f64 {
    let idx = |s, p| t.leg_index(s, p);
    let (Some(lh), Some(rh), Some(lk), Some(rk)) = (
        idx(Side::Left, "hip"),
        idx(Side::Right, "hip"),
        idx(Side::Left, "knee"),
        idx(Side::Right, "knee"),
    ) else {
        return f64::NAN;
    };
    let shoulders = (t.index("left_shoulder"), t.index("right_shoulder"));
    let (mut apart, mut seen) = (0usize, 0usize);
    for i in 0..t.len() {
        let (Some(a), Some(b)) = (t.at(lh, i), t.at(rh, i)) else {
            continue;
        };
        let thigh = [(a, t.at(lk, i)), (b, t.at(rk, i))]
            .iter()
            .filter_map(|&(h, k)| Some(dist(h, k?)))
            .fold(0.0, f64::max);
        if thigh <= 0.0 {
            continue;
        }
        seen += 1;
        let pelvis = ((a.0 + b.0) / 2.0, (a.1 + b.1) / 2.0);
        let wide_shoulders = match shoulders {
            (Some(ls), Some(rs)) => match (t.at(ls, i), t.at(rs, i)) {
                (Some(p), Some(q)) => {
                    let trunk = dist(pelvis, ((p.0 + q.0) / 2.0, (p.1 + q.1) / 2.0));
                    (p.0 - q.0).abs() > 0.5 * trunk
                }
                _ => false,
            },
            _ => false,
        };
        apart += usize::from((a.0 - b.0).abs() > 0.5 * thigh || wide_shoulders);
    }
    if seen == 0 {
        f64::NAN
    } else {
        apart as f64 / seen as f64
    }
}

/// Whether the left hip lies on the image right in most frames (the subject faces the camera).
fn left_hip_on_image_right(t: &Tracks) -> Option<bool> {
    let (lh, rh) = (
        t.leg_index(Side::Left, "hip")?,
        t.leg_index(Side::Right, "hip")?,
    );
    let mut d: Vec<f64> = (0..t.len())
        .filter_map(|i| Some(t.at(lh, i)?.0 - t.at(rh, i)?.0))
        .collect();
    let m = median(&mut d);
    m.is_finite().then_some(m > 0.0)
}

/// The body's size in the image per frame: mid-hip to mid-shoulder, else the longer hip to
/// ankle distance (NaN where not seen). Unlike a leg's length it hardly changes with the
/// phase of the stride, only with the distance to the camera.
pub fn body_size(t: &Tracks, i: usize) -> f64 {
    let mid = |a: Option<usize>, b: Option<usize>| -> Option<(f64, f64)> {
        let (p, q) = (t.at(a?, i)?, t.at(b?, i)?);
        Some(((p.0 + q.0) / 2.0, (p.1 + q.1) / 2.0))
    };
    let hips = mid(
        t.leg_index(Side::Left, "hip"),
        t.leg_index(Side::Right, "hip"),
    );
    let shoulders = mid(t.index("left_shoulder"), t.index("right_shoulder"));
    if let (Some(h), Some(s)) = (hips, shoulders) {
        return dist(h, s);
    }
    Side::BOTH
        .iter()
        .filter_map(|&s| {
            let (h, a) = (t.leg_index(s, "hip")?, t.leg_index(s, "ankle")?);
            Some(dist(t.at(h, i)?, t.at(a, i)?))
        })
        .fold(f64::NAN, f64::max)
}

/// Size at the end over the start, from a least-squares line through log size over time.
fn growth(t: &Tracks) -> f64 {
    let pts: Vec<(f64, f64)> = (0..t.len())
        .map(|i| (i as f64, body_size(t, i)))
        .filter(|(_, s)| s.is_finite() && *s > 0.0)
        .map(|(i, s)| (i, s.ln()))
        .collect();
    if pts.len() < 2 {
        return 1.0;
    }
    let n = pts.len() as f64;
    let (mx, my) = pts
        .iter()
        .fold((0.0, 0.0), |a, p| (a.0 + p.0 / n, a.1 + p.1 / n));
    let (sxy, sxx) = pts.iter().fold((0.0, 0.0), |a, p| {
        (a.0 + (p.0 - mx) * (p.1 - my), a.1 + (p.0 - mx).powi(2))
    });
    if sxx == 0.0 {
        return 1.0;
    }
    let span = pts[pts.len() - 1].0 - pts[0].0;
    (sxy / sxx * span).exp()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::direction::Direction;

    fn walking(right: usize, left: usize) -> Directions {
        let mut per_frame = vec![Direction::Right; right];
        per_frame.extend(vec![Direction::Left; left]);
        per_frame.push(Direction::Unknown);
        Directions {
            frontal: vec![false; per_frame.len()],
            per_frame,
        }
    }

    /// A pass given as the right view whose walker shows her left side (the sample, walking
    /// toward the image's left) is named; the right label on it, auto and frontal views are not,
    /// nor a short clip or one without a clear majority.
    #[test]
    fn a_side_view_showing_the_other_side_is_named() {
        let judge =
            |declared, right, left| side_disagreement(declared, &walking(right, left), 30.0);
        let w = judge(ViewSetting::Right, 3, 140).unwrap();
        assert!(
            w.contains("view = \"right\": the left leg is nearer"),
            "{w}"
        );
        assert!(w.contains("140 of 143"), "{w}");
        assert!(judge(ViewSetting::Left, 3, 140).is_none());
        for declared in [
            ViewSetting::Auto,
            ViewSetting::Anterior,
            ViewSetting::Posterior,
        ] {
            assert!(judge(declared, 3, 140).is_none());
        }
        assert!(judge(ViewSetting::Left, 0, 0).is_none());
        // Under a second of frames with a direction, or no clear majority: not judged.
        assert!(judge(ViewSetting::Left, 12, 1).is_none());
        assert!(judge(ViewSetting::Left, 60, 40).is_none());
        assert!(judge(ViewSetting::Left, 80, 20).is_some());
    }
}
