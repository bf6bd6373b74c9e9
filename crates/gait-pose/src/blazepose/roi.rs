//! Regions of interest: rotated rectangles in normalised image coordinates,
//! as mediapipe's `NormalizedRect` (f32 like mediapipe, so crops match).

use std::f32::consts::PI;

/// A rotated rectangle; centre and size are fractions of the image size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Roi {
    pub cx: f32,
    pub cy: f32,
    pub w: f32,
    pub h: f32,
    /// Radians, counter-clockwise... as mediapipe: positive turns the crop clockwise on screen.
    pub rotation: f32,
}

/// mediapipe's `NormalizeRadians` into [-pi, pi): f32 in, the arithmetic
/// in f64 (M_PI), so angles past pi wrap to the same f32 as there.
fn normalize_angle(a: f32) -> f32 {
    use std::f64::consts::PI as PI64;
    let a = a as f64;
    (a - 2.0 * PI64 * ((a - (-PI64)) / (2.0 * PI64)).floor()) as f32
}

impl Roi {
    /// The whole image (what mediapipe crops when no ROI is given).
    pub const WHOLE: Roi = Roi {
        cx: 0.5,
        cy: 0.5,
        w: 1.0,
        h: 1.0,
        rotation: 0.0,
    };

    /// From mediapipe's `NormalizedRect` order: [x_centre, y_centre, width,
    /// height, rotation].
    pub fn from_array([cx, cy, w, h, rotation]: [f32; 5]) -> Self {
        Roi {
            cx,
            cy,
            w,
            h,
            rotation,
        }
    }

    /// The landmark-model crop from a centre point and a scale point (detector
    /// kp0/kp1 or landmarks 33/34), normalised, for an image `width` x `height`:
    /// square of side 2 |p1 - p0| scaled by 1.25, rotated so p0 -> p1 points up.
    pub fn from_alignment(p0: (f32, f32), p1: (f32, f32), width: u32, height: u32) -> Self {
        let (wf, hf) = (width as f32, height as f32);
        let (x0, y0) = (p0.0 * wf, p0.1 * hf);
        let (x1, y1) = (p1.0 * wf, p1.1 * hf);
        let size = 2.0 * ((x1 - x0).powi(2) + (y1 - y0).powi(2)).sqrt();
        let rotation = normalize_angle(PI / 2.0 - (-(y1 - y0)).atan2(x1 - x0));
        // Square on the long side (in pixels), then scale by 1.25.
        let long = (size / wf * wf).max(size / hf * hf);
        Roi {
            cx: x0 / wf,
            cy: y0 / hf,
            w: long / wf * 1.25,
            h: long / hf * 1.25,
            rotation,
        }
    }

    /// Centre in pixels (continuous coordinates, 0 = left edge).
    pub fn centre_px(&self, width: u32, height: u32) -> (f32, f32) {
        (self.cx * width as f32, self.cy * height as f32)
    }

    /// Side in pixels (the long one).
    pub fn side_px(&self, width: u32, height: u32) -> f32 {
        (self.w * width as f32).max(self.h * height as f32)
    }

    /// Maps a point of the crop (x, y in [0, 1]) back to normalised image coordinates.
    pub fn project(&self, x: f32, y: f32) -> (f32, f32) {
        let (x, y) = (x - 0.5, y - 0.5);
        let (s, c) = self.rotation.sin_cos();
        (
            (c * x - s * y) * self.w + self.cx,
            (s * x + c * y) * self.h + self.cy,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn upright_body_has_no_rotation() {
        // p1 straight above p0 in a 200 x 100 image, 10 px apart.
        let r = Roi::from_alignment((0.5, 0.6), (0.5, 0.5), 200, 100);
        assert!(r.rotation.abs() < 1e-6);
        assert!((r.side_px(200, 100) - 25.0).abs() < 1e-4);
        let (x, y) = r.project(1.0, 0.5);
        assert!((x * 200.0 - (100.0 + 12.5)).abs() < 1e-3 && (y - 0.6).abs() < 1e-6);
    }

    #[test]
    fn lying_body_is_rotated() {
        // p1 to the right of p0: the body points right, rotation +90 degrees.
        let r = Roi::from_alignment((0.5, 0.5), (0.6, 0.5), 100, 100);
        assert!((r.rotation - PI / 2.0).abs() < 1e-5);
        // The crop's top (head side) maps to the right of the centre.
        let (x, y) = r.project(0.5, 0.0);
        assert!(x > 0.5 && (y - 0.5).abs() < 1e-5);
    }
}
