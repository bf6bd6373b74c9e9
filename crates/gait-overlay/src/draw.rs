//! The skeleton and the event markers, in side colours.

use gait_core::Pose;
use gait_core::keypoint::{CANONICAL, LEG_SEGMENTS, UPPER_SEGMENTS};

use crate::canvas::Canvas;
use crate::{EventKind, EventMark, Side};

/// Left side: red, right side: blue, as pyCGM2 draws them (the issue asks
/// for this). The RGB values are the report's palette, but note that
/// gait-eval's figures (skeleton strip, kinematics) currently draw left in
/// blue and right in red; one of the two should change to match.
pub const LEFT_COLOUR: [u8; 3] = [214, 39, 40];
pub const RIGHT_COLOUR: [u8; 3] = [31, 119, 180];
/// Midline keypoints and bones (nose, neck, mid-hip): light grey, visible on
/// dark and bright video alike.
pub const CENTRE_COLOUR: [u8; 3] = [235, 235, 235];
const OUTLINE: [u8; 3] = [255, 255, 255];

/// Colour of a side.
pub fn side_colour(side: Side) -> [u8; 3] {
    match side {
        Side::Left => LEFT_COLOUR,
        Side::Right => RIGHT_COLOUR,
    }
}

fn name_colour(name: &str) -> [u8; 3] {
    if name.starts_with("left_") {
        LEFT_COLOUR
    } else if name.starts_with("right_") {
        RIGHT_COLOUR
    } else {
        CENTRE_COLOUR
    }
}

/// Sizes of strokes, in panel pixels, derived from the panel height so the
/// overlay looks alike at 240p and 1080p.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Style {
    pub line_r: f64,
    pub joint_r: f64,
    pub marker_r: f64,
}

impl Style {
    pub(crate) fn for_height(h: usize) -> Self {
        let line_r = (h as f64 / 300.0).max(1.0);
        Self {
            line_r,
            joint_r: line_r * 1.6 + 0.5,
            marker_r: line_r * 6.0 + 3.0,
        }
    }
}

/// The bones and joints to draw, resolved once from the keypoint names.
#[derive(Debug, Clone)]
pub(crate) struct Skeleton {
    bones: Vec<(usize, usize, [u8; 3])>,
    joints: Vec<(usize, [u8; 3])>,
    /// Per side (left, right): heel, toe and ankle index, where named.
    feet: [[Option<usize>; 3]; 2],
}

impl Skeleton {
    /// Resolves the canonical bones among `names`. Non-canonical extras
    /// (e.g. BlazePose's `bp_*` duplicates) are not drawn; a file with no
    /// canonical name at all shows every keypoint as a grey dot.
    pub(crate) fn new(names: &[String]) -> Self {
        let idx = |n: &str| names.iter().position(|m| m == n);
        let bones = UPPER_SEGMENTS
            .iter()
            .chain(LEG_SEGMENTS.iter())
            .filter_map(|&(a, b)| {
                // A bone takes the colour of its sided end (neck-left_shoulder is left).
                let c = if name_colour(a) == CENTRE_COLOUR {
                    name_colour(b)
                } else {
                    name_colour(a)
                };
                Some((idx(a)?, idx(b)?, c))
            })
            .collect();
        let mut joints: Vec<(usize, [u8; 3])> = CANONICAL
            .iter()
            .filter_map(|n| Some((idx(n)?, name_colour(n))))
            .collect();
        if joints.is_empty() {
            joints = (0..names.len()).map(|i| (i, CENTRE_COLOUR)).collect();
        }
        let foot = |s: &str| {
            [
                idx(&format!("{s}_heel")),
                idx(&format!("{s}_toe")),
                idx(&format!("{s}_ankle")),
            ]
        };
        Self {
            bones,
            joints,
            feet: [foot("left"), foot("right")],
        }
    }

    /// Draws `pose` with keypoint coordinates multiplied by `scale` (the
    /// panel's size over the input's).
    pub(crate) fn draw(&self, c: &mut Canvas, pose: &Pose, scale: f64, st: Style) {
        let at = |i: usize| {
            pose.keypoints
                .get(i)
                .filter(|k| k.is_found())
                .map(|k| to_panel(k.x, k.y, scale))
        };
        for &(a, b, col) in &self.bones {
            if let (Some(pa), Some(pb)) = (at(a), at(b)) {
                c.line(pa.0, pa.1, pb.0, pb.1, st.line_r, col);
            }
        }
        for &(i, col) in &self.joints {
            if let Some(p) = at(i) {
                // A white rim keeps dots apart from bones of the same colour.
                c.disc(p.0, p.1, st.joint_r + 1.0, OUTLINE);
                c.disc(p.0, p.1, st.joint_r, col);
            }
        }
    }

    /// A ring around the foot point of the event: the heel for a heel strike,
    /// the toe for a toe-off (the ankle when that keypoint is missing).
    pub(crate) fn event_marker(
        &self,
        c: &mut Canvas,
        pose: &Pose,
        ev: &EventMark,
        scale: f64,
        st: Style,
    ) {
        let foot = match ev.side {
            Side::Left => self.feet[0],
            Side::Right => self.feet[1],
        };
        let order = match ev.kind {
            EventKind::HeelStrike => [foot[0], foot[2]],
            EventKind::ToeOff => [foot[1], foot[2]],
        };
        let Some(k) = order
            .iter()
            .flatten()
            .filter_map(|&i| pose.keypoints.get(i))
            .find(|k| k.is_found())
        else {
            return;
        };
        let (x, y) = to_panel(k.x, k.y, scale);
        let r = st.marker_r;
        let t = st.line_r * 1.5;
        c.ring(x, y, r - t - 1.0, r + 1.0, OUTLINE);
        c.ring(x, y, r - t, r, side_colour(ev.side));
    }
}

/// Input pixel coordinates (pixel centres at integers) to panel coordinates.
fn to_panel(x: f64, y: f64, scale: f64) -> (f64, f64) {
    ((x + 0.5) * scale - 0.5, (y + 0.5) * scale - 0.5)
}

#[cfg(test)]
mod tests {
    use super::*;
    use gait_core::Keypoint;

    fn names() -> Vec<String> {
        CANONICAL.iter().map(|s| s.to_string()).collect()
    }

    /// A standing figure in a 100x100 frame, left leg at x 40, right at x 60.
    fn pose() -> Pose {
        let n = names();
        let mut p = Pose::empty(n.len());
        let mut put = |name: &str, x: f64, y: f64| {
            let i = n.iter().position(|m| m == name).unwrap();
            p.keypoints[i] = Keypoint::new(x, y, 0.9);
        };
        put("mid_hip", 50.0, 40.0);
        put("left_hip", 40.0, 40.0);
        put("right_hip", 60.0, 40.0);
        put("left_knee", 40.0, 60.0);
        put("right_knee", 60.0, 60.0);
        put("left_ankle", 40.0, 80.0);
        put("right_ankle", 60.0, 80.0);
        put("left_heel", 38.0, 85.0);
        put("right_heel", 58.0, 85.0);
        p
    }

    fn px(buf: &[u8], w: usize, x: usize, y: usize) -> [u8; 3] {
        let i = (y * w + x) * 3;
        [buf[i], buf[i + 1], buf[i + 2]]
    }

    #[test]
    fn legs_are_drawn_in_side_colours() {
        let mut buf = vec![0u8; 100 * 100 * 3];
        let mut c = Canvas::new(&mut buf, 100, 0, 0, 100, 100);
        Skeleton::new(&names()).draw(&mut c, &pose(), 1.0, Style::for_height(100));
        assert_eq!(px(&buf, 100, 40, 60), LEFT_COLOUR, "left knee");
        assert_eq!(px(&buf, 100, 60, 60), RIGHT_COLOUR, "right knee");
        assert_eq!(px(&buf, 100, 40, 50), LEFT_COLOUR, "left thigh");
        assert_eq!(px(&buf, 100, 60, 70), RIGHT_COLOUR, "right shank");
        assert_eq!(px(&buf, 100, 50, 40), CENTRE_COLOUR, "mid hip");
        assert_eq!(px(&buf, 100, 10, 10), [0, 0, 0], "background untouched");
    }

    #[test]
    fn keypoints_scale_with_the_panel() {
        let mut buf = vec![0u8; 50 * 50 * 3];
        let mut c = Canvas::new(&mut buf, 50, 0, 0, 50, 50);
        Skeleton::new(&names()).draw(&mut c, &pose(), 0.5, Style::for_height(50));
        assert_eq!(px(&buf, 50, 20, 30), LEFT_COLOUR);
        assert_eq!(px(&buf, 50, 30, 30), RIGHT_COLOUR);
    }

    #[test]
    fn markers_ring_the_heel() {
        let mut buf = vec![0u8; 100 * 100 * 3];
        let mut c = Canvas::new(&mut buf, 100, 0, 0, 100, 100);
        let st = Style::for_height(100);
        let ev = EventMark {
            side: Side::Right,
            kind: EventKind::HeelStrike,
            age_frames: 0,
        };
        Skeleton::new(&names()).event_marker(&mut c, &pose(), &ev, 1.0, st);
        let r = st.marker_r - st.line_r * 0.5;
        assert_eq!(px(&buf, 100, (58.0 + r).round() as usize, 85), RIGHT_COLOUR);
        assert_eq!(
            px(&buf, 100, 58, 85),
            [0, 0, 0],
            "the heel itself stays visible"
        );
    }

    #[test]
    fn missing_keypoints_and_foreign_names_do_not_panic() {
        let mut buf = vec![0u8; 10 * 10 * 3];
        let mut c = Canvas::new(&mut buf, 10, 0, 0, 10, 10);
        let sk = Skeleton::new(&["snout".to_string()]);
        sk.draw(&mut c, &Pose::empty(0), 1.0, Style::for_height(10));
        sk.draw(
            &mut c,
            &Pose {
                keypoints: vec![Keypoint::new(5.0, 5.0, 1.0)],
            },
            1.0,
            Style::for_height(10),
        );
        assert_eq!(px(&buf, 10, 5, 5), CENTRE_COLOUR);
    }
}
