//! Sagittal hip, knee and ankle angles (degrees) from 2-D keypoints.
//!
//! Image coordinates have y down. With `d` the walking direction (+1 right, -1 left), a vector
//! (dx, dy) has forward component `d * dx` and downward component `dy`; its inclination is
//! `atan2(forward, down)`: 0 pointing straight down, positive tilted forwards.

use serde::Serialize;

use crate::config::Side;
use crate::direction::Direction;
use crate::tracks::Tracks;

/// Joint angle series for one leg; NaN where undefined.
#[derive(Debug, Clone, Default, Serialize)]
pub struct LegAngles {
    /// Thigh (hip -> knee) against the downward vertical; flexion positive.
    pub hip: Vec<f64>,
    /// Thigh inclination minus shank (knee -> ankle) inclination: 0 straight, flexion positive.
    pub knee: Vec<f64>,
    /// Foot (heel -> toe, or ankle -> toe without a heel) against the perpendicular to the
    /// shank; dorsiflexion positive.
    pub ankle: Vec<f64>,
}

/// Angles of both legs.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Angles {
    pub left: LegAngles,
    pub right: LegAngles,
}

impl Angles {
    pub fn leg(&self, side: Side) -> &LegAngles {
        match side {
            Side::Left => &self.left,
            Side::Right => &self.right,
        }
    }
}

/// Inclination of `from -> to` in degrees, or NaN.
fn inclination(t: &Tracks, from: Option<usize>, to: Option<usize>, i: usize, d: f64) -> f64 {
    match (from.and_then(|j| t.at(j, i)), to.and_then(|j| t.at(j, i))) {
        (Some(a), Some(b)) if (a.0, a.1) != (b.0, b.1) => {
            (d * (b.0 - a.0)).atan2(b.1 - a.1).to_degrees()
        }
        _ => f64::NAN,
    }
}

/// Wraps an angle difference into (-180, 180].
fn wrap(a: f64) -> f64 {
    let w = (a + 180.0).rem_euclid(360.0) - 180.0;
    if w == -180.0 { 180.0 } else { w }
}

/// Angles for every frame; frames of unknown direction get NaN.
pub fn compute(t: &Tracks, dirs: &[Direction]) -> Angles {
    let leg = |side: Side| {
        let idx = |p: &str| t.leg_index(side, p);
        let (hip, knee, ankle, heel, toe) = (
            idx("hip"),
            idx("knee"),
            idx("ankle"),
            idx("heel"),
            idx("toe"),
        );
        let mut out = LegAngles::default();
        for (i, dir) in dirs.iter().enumerate().take(t.len()) {
            let d = dir.sign();
            if d == 0.0 {
                out.hip.push(f64::NAN);
                out.knee.push(f64::NAN);
                out.ankle.push(f64::NAN);
                continue;
            }
            let thigh = inclination(t, hip, knee, i, d);
            let shank = inclination(t, knee, ankle, i, d);
            let heel_ok = heel.and_then(|j| t.at(j, i)).is_some();
            let foot = inclination(t, if heel_ok { heel } else { ankle }, toe, i, d);
            out.hip.push(thigh);
            out.knee.push(wrap(thigh - shank));
            out.ankle.push(wrap(foot - shank - 90.0));
        }
        out
    };
    Angles {
        left: leg(Side::Left),
        right: leg(Side::Right),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tracks::LEG;

    /// One right leg posed by segment inclinations (degrees from down, forward positive).
    fn leg(thigh: f64, shank: f64, foot_from_shank: f64, dir: f64) -> Tracks {
        let names: Vec<String> = LEG.iter().map(|p| format!("right_{p}")).collect();
        let r = |deg: f64, len: f64| {
            let a = deg.to_radians();
            (dir * len * a.sin(), len * a.cos())
        };
        let hip = (500.0, 100.0);
        let t1 = r(thigh, 200.0);
        let knee = (hip.0 + t1.0, hip.1 + t1.1);
        let s1 = r(shank, 200.0);
        let ankle = (knee.0 + s1.0, knee.1 + s1.1);
        let heel = (ankle.0, ankle.1);
        let f = r(shank + foot_from_shank, 80.0);
        let toe = (heel.0 + f.0, heel.1 + f.1);
        let pts = [hip, knee, ankle, (heel.0 - 0.0, heel.1), toe];
        Tracks {
            fps: 30.0,
            first_frame: 0,
            names,
            x: pts.iter().map(|p| vec![p.0]).collect(),
            y: pts.iter().map(|p| vec![p.1]).collect(),
            likelihood: vec![vec![1.0]; 5],
        }
    }

    #[test]
    fn signs_follow_the_clinical_convention_both_ways() {
        for (dir, d) in [(1.0, Direction::Right), (-1.0, Direction::Left)] {
            // Thigh 20 deg forward, shank 10 deg back: hip flexion 20, knee flexion 30;
            // foot 80 deg from the shank: 10 deg dorsiflexion.
            let t = leg(20.0, -10.0, 100.0, dir);
            let a = compute(&t, &[d]);
            assert!((a.right.hip[0] - 20.0).abs() < 1e-9, "{:?}", a.right);
            assert!((a.right.knee[0] - 30.0).abs() < 1e-9);
            assert!((a.right.ankle[0] - 10.0).abs() < 1e-9);
            assert!(a.left.hip[0].is_nan());
            // Extension and plantarflexion are negative.
            let t = leg(-15.0, -10.0, 70.0, dir);
            let a = compute(&t, &[d]);
            assert!((a.right.hip[0] + 15.0).abs() < 1e-9);
            assert!((a.right.knee[0] + 5.0).abs() < 1e-9);
            assert!((a.right.ankle[0] + 20.0).abs() < 1e-9);
        }
        let a = compute(&leg(20.0, -10.0, 100.0, 1.0), &[Direction::Unknown]);
        assert!(a.right.knee[0].is_nan());
    }
}
