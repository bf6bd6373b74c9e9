//! Which way the walk runs against the camera: straight toward or away from it (a front or back
//! view), across it (a side view), or obliquely, where neither view's angles hold.
//!
//! A walk along a straight line, seen through a pinhole camera, has a vanishing point: where
//! its image would end if the walker went on for ever. Image x and body size then lie on one
//! straight line, `x - x_v = k * size` (size falls as 1 / depth, the offset from the vanishing
//! point too), so the line through the (x, size) points of the walk meets size 0 at `x_v`, and
//! the walking direction makes `atan((x_v - c) / f)` with the camera's axis, `c` the image
//! centre and `f` the focal length in pixels. Across the camera the size stays the same and
//! `x_v` lies at infinity: 90 degrees. The focal length is not known from the keypoints; a
//! phone's main camera (26 mm equivalent, 69 degrees across a landscape frame) is assumed, and
//! a lens 20 % longer or shorter turns tan(angle) by 20 %: at most 5 degrees, at 45
//! (tools/frontal/oblique.py: within 3 degrees of the true angle on projected motion capture
//! from 0 to 180 degrees with the assumed lens).

use crate::tracks::Tracks;
use crate::view::{View, body_size};

/// The assumed horizontal field of view (degrees) of the camera.
const FIELD_OF_VIEW_DEG: f64 = 69.0;
/// Fewest frames with the hips and a body size for an estimate.
const MIN_FRAMES: usize = 10;
/// Beyond this many degrees from straight toward (or away from) the camera in a front or back
/// view, or from across it in a side view, the view's angles no longer hold: on projected
/// motion capture (tools/frontal/oblique.py) hip adduction in a front view was 1.7-2.7 deg off
/// its 3-D value at 10 degrees and 3.4-5.0 at 20 (target 3); a side view lost one side's cycles
/// at 20 degrees and its knee angle was 1.4-1.6 deg further off than across the camera.
pub const TOLERANCE_DEG: f64 = 15.0;

/// Degrees between the walking direction and the camera's axis (0: straight toward or away,
/// 90: across), from the mid-hip's image x and the body's size over the frames of `t` in a
/// frame `width` pixels wide; NaN with too few frames or without a clear line.
pub fn estimate(t: &Tracks, width: u32) -> f64 {
    let Some(((mx, ms), (dx, ds))) = walk_points(t).and_then(|p| principal_line(&p)) else {
        return f64::NAN;
    };
    let focal = f64::from(width) / 2.0 / (FIELD_OF_VIEW_DEG.to_radians() / 2.0).tan();
    let centre = f64::from(width) / 2.0;
    // x_v = mx - ms * dx / ds; tan(angle) = (x_v - centre) / focal, kept finite as ds -> 0.
    let angle = ((mx - centre) * ds - ms * dx)
        .atan2(focal * ds)
        .to_degrees()
        .abs();
    angle.min(180.0 - angle)
}

/// The image x of the walk's vanishing point: where every line parallel to the walk, at any
/// height and lateral offset, ends in the image. `None` without a walk along the camera's axis
/// (the body's size changing by less than 10 % over the walk), where it lies far outside.
pub fn vanishing_x(t: &Tracks) -> Option<f64> {
    let points = walk_points(t)?;
    let ((mx, ms), (dx, ds)) = principal_line(&points)?;
    let mut sizes: Vec<f64> = points.iter().map(|p| p.1).collect();
    sizes.sort_by(f64::total_cmp);
    let at = |q: f64| sizes[((sizes.len() - 1) as f64 * q).round() as usize];
    (at(0.9) > 1.1 * at(0.1) && ds.abs() > 1e-9).then(|| mx - ms * dx / ds)
}

/// The mid-hip's image x and the body's size over the frames with both; `None` with too few.
fn walk_points(t: &Tracks) -> Option<Vec<(f64, f64)>> {
    let (lh, rh) = (
        t.leg_index(crate::config::Side::Left, "hip")?,
        t.leg_index(crate::config::Side::Right, "hip")?,
    );
    let points: Vec<(f64, f64)> = (0..t.len())
        .filter_map(|i| {
            let (a, b) = (t.at(lh, i)?, t.at(rh, i)?);
            let size = body_size(t, i);
            (size.is_finite() && size > 0.0).then_some(((a.0 + b.0) / 2.0, size))
        })
        .collect();
    (points.len() >= MIN_FRAMES).then_some(points)
}

/// The line through `points` that fits them best in both coordinates (their principal axis):
/// its point (the means) and unit direction; `None` when the points do not spread.
fn principal_line(points: &[(f64, f64)]) -> Option<((f64, f64), (f64, f64))> {
    let n = points.len() as f64;
    let (mx, my) = points
        .iter()
        .fold((0.0, 0.0), |a, p| (a.0 + p.0 / n, a.1 + p.1 / n));
    let (sxx, syy, sxy) = points.iter().fold((0.0, 0.0, 0.0), |a, p| {
        let (u, v) = (p.0 - mx, p.1 - my);
        (a.0 + u * u, a.1 + v * v, a.2 + u * v)
    });
    if sxx + syy <= 0.0 {
        return None;
    }
    let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    Some(((mx, my), (theta.cos(), theta.sin())))
}

/// The warning for a walk more than [`TOLERANCE_DEG`] off what `view` needs, else `None`.
pub fn warning(view: View, angle: f64) -> Option<String> {
    if !angle.is_finite() {
        return None;
    }
    let off = degrees_off(view.is_frontal(), angle);
    let what = match view {
        View::Sagittal => "across the camera (a side view)",
        _ => "straight toward or away from the camera (a front or back view)",
    };
    (off > TOLERANCE_DEG).then(|| {
        format!(
            "the walk runs about {angle:.0} deg off the camera's axis (estimated from the body's image size along its path, for a phone's {FIELD_OF_VIEW_DEG:.0} deg field of view), {off:.0} deg from {what}: beyond {TOLERANCE_DEG:.0} deg the angles are distorted (BENCHMARKS.md, \"Oblique walks\"); film the walk straight across, toward or away from the camera"
        )
    })
}

/// Degrees between a walk at `angle` to the camera's axis and what its view needs: straight
/// toward or away for a front or back view (`frontal`), across for a side view.
pub fn degrees_off(frontal: bool, angle: f64) -> f64 {
    if frontal { angle } else { 90.0 - angle }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A walker 1.7 m tall projected through a 1920 px wide camera of the assumed field of view,
    /// walking 4 m on a line at `angle` degrees from the camera's axis, 2 m to its right.
    fn walk(angle: f64) -> Tracks {
        let focal = 960.0 / (FIELD_OF_VIEW_DEG.to_radians() / 2.0).tan();
        let a = angle.to_radians();
        let n = 60;
        let (mut xs, mut ys) = (vec![vec![]; 4], vec![vec![]; 4]);
        for i in 0..n {
            let s = -2.0 + 4.0 * i as f64 / (n - 1) as f64;
            // Lateral X and depth Z of the mid-hip; the line passes 6 m in front of the camera.
            let (x, z) = (0.5 + s * a.sin(), 6.0 - s * a.cos());
            let u = 960.0 + focal * x / z;
            // Hips 0.3 m apart across the image, shoulders 0.5 m above them.
            for (j, (du, dv)) in [(-0.15, 0.0), (0.15, 0.0), (-0.15, -0.5), (0.15, -0.5)]
                .into_iter()
                .enumerate()
            {
                xs[j].push(u + focal * du / z);
                ys[j].push(540.0 + focal * (0.1 + dv) / z);
            }
        }
        Tracks {
            fps: 30.0,
            first_frame: 0,
            names: ["left_hip", "right_hip", "left_shoulder", "right_shoulder"]
                .map(String::from)
                .to_vec(),
            x: xs,
            y: ys,
            likelihood: vec![vec![1.0; n]; 4],
        }
    }

    #[test]
    fn the_walking_direction_comes_from_the_vanishing_point() {
        for angle in [0.0, 10.0, 30.0, 45.0, 60.0, 80.0, 90.0, 120.0, 170.0] {
            let got = estimate(&walk(angle), 1920);
            let want = f64::min(angle, 180.0 - angle);
            assert!((got - want).abs() < 0.5, "{angle}: {got}");
        }
    }

    #[test]
    fn only_walks_beyond_the_tolerance_are_named() {
        assert!(warning(View::Anterior, 10.0).is_none());
        assert!(warning(View::Sagittal, 80.0).is_none());
        assert!(warning(View::Posterior, f64::NAN).is_none());
        let w = warning(View::Anterior, 30.0).unwrap();
        assert!(w.contains("30 deg off the camera's axis"), "{w}");
        let w = warning(View::Sagittal, 45.0).unwrap();
        assert!(w.contains("45 deg from across the camera"), "{w}");
    }
}
