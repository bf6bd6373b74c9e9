//! Rotated crops resampled exactly as mediapipe's CPU image-to-tensor step:
//! OpenCV 4.10 `boxPoints` + `warpPerspective` (INTER_LINEAR, fixed point,
//! 1/32-pixel grid) on the 8-bit image.

use image::RgbImage;

/// What lies outside the image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Border {
    Zero,
    Replicate,
}

/// A rectangle in pixels: centre, size, rotation in radians.
#[derive(Debug, Clone, Copy)]
pub struct PixelRect {
    pub cx: f32,
    pub cy: f32,
    pub w: f32,
    pub h: f32,
    pub rotation: f32,
}

/// Resamples `rect` of `img` into a `size` x `size` RGB u8 buffer (row-major, HWC).
pub fn crop(img: &RgbImage, rect: PixelRect, size: usize, border: Border) -> Vec<u8> {
    // OpenCV's RotatedRect takes degrees (mediapipe converts in f32) and
    // boxPoints works in f32; keep both so the grid rounds the same way.
    let deg = rect.rotation * 180.0 / std::f32::consts::PI;
    let rad = deg as f64 * std::f64::consts::PI / 180.0;
    let b = rad.cos() as f32 * 0.5;
    let a = rad.sin() as f32 * 0.5;
    let p0 = (
        rect.cx - a * rect.h - b * rect.w,
        rect.cy + b * rect.h - a * rect.w,
    );
    let p1 = (
        rect.cx + a * rect.h - b * rect.w,
        rect.cy - b * rect.h - a * rect.w,
    );
    let p2 = (2.0 * rect.cx - p0.0, 2.0 * rect.cy - p0.1);
    // Destination corners (0, H) <- p0, (0, 0) <- p1, (W, 0) <- p2.
    let n = size as f64;
    let (ox, oy) = (p1.0 as f64, p1.1 as f64);
    let (ux, uy) = ((p2.0 - p1.0) as f64 / n, (p2.1 - p1.1) as f64 / n);
    let (vx, vy) = ((p0.0 - p1.0) as f64 / n, (p0.1 - p1.1) as f64 / n);

    let (w, h) = (img.width() as i64, img.height() as i64);
    let src = img.as_raw();
    let mut out = vec![0u8; size * size * 3];
    for y in 0..size {
        for x in 0..size {
            let sx = ox + ux * x as f64 + vx * y as f64;
            let sy = oy + uy * x as f64 + vy * y as f64;
            // cvRound: round half to even, then split into pixel and 1/32 phase.
            let gx = (sx * 32.0).round_ties_even() as i64;
            let gy = (sy * 32.0).round_ties_even() as i64;
            let (ix, iy) = (gx >> 5, gy >> 5);
            let (fx, fy) = (gx & 31, gy & 31);
            let wts = [
                (32 - fx) * (32 - fy) * 32,
                fx * (32 - fy) * 32,
                (32 - fx) * fy * 32,
                fx * fy * 32,
            ];
            let taps = [(ix, iy), (ix + 1, iy), (ix, iy + 1), (ix + 1, iy + 1)];
            let mut acc = [0i64; 3];
            for (&(tx, ty), &wt) in taps.iter().zip(&wts) {
                let inside = tx >= 0 && ty >= 0 && tx < w && ty < h;
                let (tx, ty) = match (inside, border) {
                    (true, _) => (tx, ty),
                    (false, Border::Zero) => continue,
                    (false, Border::Replicate) => (tx.clamp(0, w - 1), ty.clamp(0, h - 1)),
                };
                let i = ((ty * w + tx) * 3) as usize;
                for c in 0..3 {
                    acc[c] += wt * src[i + c] as i64;
                }
            }
            let o = (y * size + x) * 3;
            for c in 0..3 {
                out[o + c] = ((acc[c] + (1 << 14)) >> 15).clamp(0, 255) as u8;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identity_crop_copies_pixels() {
        let img = RgbImage::from_fn(4, 4, |x, y| image::Rgb([(x * 10 + y) as u8, 0, 255]));
        let rect = PixelRect {
            cx: 2.0,
            cy: 2.0,
            w: 4.0,
            h: 4.0,
            rotation: 0.0,
        };
        let out = crop(&img, rect, 4, Border::Zero);
        for y in 0..4 {
            for x in 0..4 {
                assert_eq!(out[(y * 4 + x) * 3], (x * 10 + y) as u8);
            }
        }
    }

    #[test]
    fn borders() {
        let img = RgbImage::from_pixel(2, 2, image::Rgb([100, 100, 100]));
        let rect = PixelRect {
            cx: 1.0,
            cy: 1.0,
            w: 8.0,
            h: 8.0,
            rotation: 0.5,
        };
        assert_eq!(crop(&img, rect, 8, Border::Zero)[0], 0);
        assert!(
            crop(&img, rect, 8, Border::Replicate)
                .iter()
                .all(|&v| v == 100)
        );
    }
}
