//! The transform arithmetic of OpenCV 3.4.20, the OpenCV built into the
//! mediapipe 0.10.14 wheel: `RotatedRect::points`, `getPerspectiveTransform`
//! (8 x 8 LU, partial pivoting) and the 3 x 3 `invert`, operation for
//! operation. A crop's sampling grid is rounded to 1/32 pixel, so a last-bit
//! difference in the matrix moves a few samples to the neighbouring phase;
//! that alone shifts unrefined foot landmarks by up to ~0.2 px on some crops
//! (issue 22). Checked bit for bit against mediapipe's own crops
//! (tests/blazepose_imagetotensor.rs).

/// A point as OpenCV's `Point2f`.
pub type Point = (f32, f32);

/// `cv::RotatedRect(centre, size, degrees).points()`: for `degrees` 0 the
/// corners bottom-left, top-left, top-right, bottom-right (y down).
pub fn box_points(cx: f32, cy: f32, w: f32, h: f32, degrees: f32) -> [Point; 4] {
    let rad = degrees as f64 * std::f64::consts::PI / 180.0;
    let b = rad.cos() as f32 * 0.5;
    let a = rad.sin() as f32 * 0.5;
    let p0 = (cx - a * h - b * w, cy + b * h - a * w);
    let p1 = (cx + a * h - b * w, cy - b * h - a * w);
    let p2 = (2.0 * cx - p0.0, 2.0 * cy - p0.1);
    let p3 = (2.0 * cx - p1.0, 2.0 * cy - p1.1);
    [p0, p1, p2, p3]
}

/// mediapipe's angle for `RotatedRect`: `rotation * 180.f / M_PI`, the
/// product in f32 and the division in f64.
pub fn degrees(radians: f32) -> f32 {
    ((radians * 180.0) as f64 / std::f64::consts::PI) as f32
}

/// `cv::getPerspectiveTransform(src, dst)`: the 3 x 3 matrix (row-major)
/// mapping each `src[i]` to `dst[i]`; `None` when the points are degenerate.
pub fn perspective_transform(src: &[Point; 4], dst: &[Point; 4]) -> Option<[f64; 9]> {
    let mut a = [[0f64; 8]; 8];
    let mut b = [0f64; 8];
    for i in 0..4 {
        let ((sx, sy), (dx, dy)) = (src[i], dst[i]);
        (a[i][0], a[i][1], a[i][2]) = (sx as f64, sy as f64, 1.0);
        (a[i + 4][3], a[i + 4][4], a[i + 4][5]) = (sx as f64, sy as f64, 1.0);
        // The products are Point2f * float in OpenCV: f32, then widened.
        a[i][6] = (-sx * dx) as f64;
        a[i][7] = (-sy * dx) as f64;
        a[i + 4][6] = (-sx * dy) as f64;
        a[i + 4][7] = (-sy * dy) as f64;
        b[i] = dx as f64;
        b[i + 4] = dy as f64;
    }
    let x = lu_solve(a, b)?;
    let mut m = [1f64; 9];
    m[..8].copy_from_slice(&x);
    Some(m)
}

/// OpenCV 3.4's `LUImpl` on one right-hand side (eps `DBL_EPSILON * 100`).
fn lu_solve(mut a: [[f64; 8]; 8], mut b: [f64; 8]) -> Option<[f64; 8]> {
    const N: usize = 8;
    for i in 0..N {
        let mut k = i;
        for j in i + 1..N {
            if a[j][i].abs() > a[k][i].abs() {
                k = j;
            }
        }
        let pivot = a[k][i].abs();
        // OpenCV goes on with garbage after a NaN; nothing sensible comes of it.
        if pivot.is_nan() || pivot < f64::EPSILON * 100.0 {
            return None;
        }
        if k != i {
            a.swap(i, k);
            b.swap(i, k);
        }
        let d = -1.0 / a[i][i];
        for j in i + 1..N {
            let (upper, lower) = a.split_at_mut(j);
            let (pivot_row, row) = (&upper[i], &mut lower[0]);
            let alpha = row[i] * d;
            for (v, p) in row[i + 1..].iter_mut().zip(&pivot_row[i + 1..]) {
                *v += alpha * p;
            }
            b[j] += alpha * b[i];
        }
    }
    // Back substitution dividing by the pivot, as 3.4 does: later OpenCV
    // multiplies by a stored reciprocal instead, a different last bit that
    // put 6 of 300 random crops a sample off mediapipe's; this put none.
    for i in (0..N).rev() {
        let mut s = b[i];
        for c in i + 1..N {
            s -= a[i][c] * b[c];
        }
        b[i] = s / a[i][i];
    }
    Some(b)
}

/// `cv::invert` of a 3 x 3 f64 matrix (cofactors times 1 / det3).
pub fn invert(m: &[f64; 9]) -> Option<[f64; 9]> {
    let e = |r: usize, c: usize| m[r * 3 + c];
    let det = e(0, 0) * (e(1, 1) * e(2, 2) - e(1, 2) * e(2, 1))
        - e(0, 1) * (e(1, 0) * e(2, 2) - e(1, 2) * e(2, 0))
        + e(0, 2) * (e(1, 0) * e(2, 1) - e(1, 1) * e(2, 0));
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let d = 1.0 / det;
    Some([
        (e(1, 1) * e(2, 2) - e(1, 2) * e(2, 1)) * d,
        (e(0, 2) * e(2, 1) - e(0, 1) * e(2, 2)) * d,
        (e(0, 1) * e(1, 2) - e(0, 2) * e(1, 1)) * d,
        (e(1, 2) * e(2, 0) - e(1, 0) * e(2, 2)) * d,
        (e(0, 0) * e(2, 2) - e(0, 2) * e(2, 0)) * d,
        (e(0, 2) * e(1, 0) - e(0, 0) * e(1, 2)) * d,
        (e(1, 0) * e(2, 1) - e(1, 1) * e(2, 0)) * d,
        (e(0, 1) * e(2, 0) - e(0, 0) * e(2, 1)) * d,
        (e(0, 0) * e(1, 1) - e(0, 1) * e(1, 0)) * d,
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn upright_square_maps_corners() {
        let src = box_points(50.0, 40.0, 20.0, 20.0, 0.0);
        assert_eq!(
            src,
            [(40.0, 50.0), (40.0, 30.0), (60.0, 30.0), (60.0, 50.0)]
        );
        let dst = [(0.0, 8.0), (0.0, 0.0), (8.0, 0.0), (8.0, 8.0)];
        let m = perspective_transform(&src, &dst).unwrap();
        let inv = invert(&m).unwrap();
        // Crop pixel (4, 4) samples the centre; (0, 0) the top-left corner.
        let map = |x: f64, y: f64| {
            let w = inv[6] * x + inv[7] * y + inv[8];
            (
                (inv[0] * x + inv[1] * y + inv[2]) / w,
                (inv[3] * x + inv[4] * y + inv[5]) / w,
            )
        };
        let (x, y) = map(4.0, 4.0);
        assert!((x - 50.0).abs() < 1e-9 && (y - 40.0).abs() < 1e-9);
        let (x, y) = map(0.0, 0.0);
        assert!((x - 40.0).abs() < 1e-9 && (y - 30.0).abs() < 1e-9);
    }

    #[test]
    fn degenerate_points_have_no_transform() {
        let src = [(1.0, 1.0); 4];
        let dst = [(0.0, 8.0), (0.0, 0.0), (8.0, 0.0), (8.0, 8.0)];
        assert!(perspective_transform(&src, &dst).is_none());
        let nan = [(f32::NAN, 0.0); 4];
        assert!(perspective_transform(&nan, &dst).is_none());
        assert!(invert(&[0.0; 9]).is_none());
    }

    #[test]
    fn angle_is_converted_like_mediapipe() {
        // f32 product, f64 division: one f32 step off an all-f32 conversion.
        assert_eq!(degrees(1.0), 57.295_78);
        assert_ne!(degrees(1.0), 1.0f32 * 180.0 / std::f32::consts::PI);
        assert!((degrees(std::f32::consts::FRAC_PI_2) - 90.0).abs() < 1e-5);
    }
}
