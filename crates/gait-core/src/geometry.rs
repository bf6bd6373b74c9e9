//! Axis-aligned resize/letterbox transforms between a frame and the image a
//! stage works on, so keypoints found at a model's input size map back to the
//! frame's own pixels exactly.
//!
//! Coordinates follow [`crate::Keypoint`]: the centre of pixel (i, j) is at
//! (i, j). Resampling with half-pixel centres (OpenCV's `resize`, PyTorch's
//! `align_corners=False`) maps the continuous coordinate `x + 0.5` by a pure
//! scale, which is what [`Resize`] models.

use serde::{Deserialize, Serialize};

/// Maps frame coordinates to the coordinates of a resized (and possibly
/// padded) target image: `target + 0.5 = (source + 0.5) * scale + offset`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Resize {
    pub src_width: u32,
    pub src_height: u32,
    pub dst_width: u32,
    pub dst_height: u32,
    pub scale_x: f64,
    pub scale_y: f64,
    /// Padding on the left/top of the target, in target pixels.
    pub offset_x: f64,
    pub offset_y: f64,
}

impl Resize {
    /// The identity on a `width` x `height` image.
    pub fn identity(width: u32, height: u32) -> Self {
        Self::stretch(width, height, width, height)
    }

    /// Scales each axis independently to the target size (aspect may change).
    pub fn stretch(src_width: u32, src_height: u32, dst_width: u32, dst_height: u32) -> Self {
        Self {
            src_width,
            src_height,
            dst_width,
            dst_height,
            scale_x: f64::from(dst_width) / f64::from(src_width),
            scale_y: f64::from(dst_height) / f64::from(src_height),
            offset_x: 0.0,
            offset_y: 0.0,
        }
    }

    /// Keeps the aspect ratio, fits the frame inside the target and centres it
    /// with equal borders (a letterbox).
    pub fn letterbox(src_width: u32, src_height: u32, dst_width: u32, dst_height: u32) -> Self {
        let scale = (f64::from(dst_width) / f64::from(src_width))
            .min(f64::from(dst_height) / f64::from(src_height));
        Self {
            src_width,
            src_height,
            dst_width,
            dst_height,
            scale_x: scale,
            scale_y: scale,
            offset_x: (f64::from(dst_width) - f64::from(src_width) * scale) / 2.0,
            offset_y: (f64::from(dst_height) - f64::from(src_height) * scale) / 2.0,
        }
    }

    /// The size ControlNet's annotators resize to: the short side becomes
    /// `short_side`, then each side is rounded to a multiple of `multiple`
    /// (512 and 64 for SD 1.5, as `controlnet_aux.util.resize_image`).
    pub fn short_side(src_width: u32, src_height: u32, short_side: u32, multiple: u32) -> Self {
        let k = f64::from(short_side) / f64::from(src_width.min(src_height));
        let round_to = |v: u32| {
            let m = f64::from(multiple);
            // Python's round() is half-to-even; ties cannot occur for the
            // sizes we see often, but keep the same rule.
            let q = (f64::from(v) * k / m).round_ties_even();
            ((q * m) as u32).max(multiple)
        };
        Self::stretch(
            src_width,
            src_height,
            round_to(src_width),
            round_to(src_height),
        )
    }

    /// Frame point -> target point.
    pub fn to_target(&self, x: f64, y: f64) -> (f64, f64) {
        (
            (x + 0.5) * self.scale_x + self.offset_x - 0.5,
            (y + 0.5) * self.scale_y + self.offset_y - 0.5,
        )
    }

    /// Target point -> frame point (the exact inverse of [`Self::to_target`]).
    pub fn to_source(&self, x: f64, y: f64) -> (f64, f64) {
        (
            (x + 0.5 - self.offset_x) / self.scale_x - 0.5,
            (y + 0.5 - self.offset_y) / self.scale_y - 0.5,
        )
    }

    /// Size of the scaled frame inside the target, before padding.
    pub fn scaled_size(&self) -> (u32, u32) {
        (
            (f64::from(self.src_width) * self.scale_x).round() as u32,
            (f64::from(self.src_height) * self.scale_y).round() as u32,
        )
    }

    /// Resamples an RGB frame into the target image (bilinear; padding black).
    pub fn apply_rgb(&self, image: &image::RgbImage) -> image::RgbImage {
        let (w, h) = self.scaled_size();
        let scaled = image::imageops::resize(image, w, h, image::imageops::FilterType::Triangle);
        if (w, h) == (self.dst_width, self.dst_height) {
            return scaled;
        }
        let mut out = image::RgbImage::new(self.dst_width, self.dst_height);
        image::imageops::replace(
            &mut out,
            &scaled,
            self.offset_x.round() as i64,
            self.offset_y.round() as i64,
        );
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_is_exact() {
        for r in [
            Resize::stretch(1768, 994, 512, 512),
            Resize::letterbox(1768, 994, 224, 224),
            Resize::short_side(1768, 994, 512, 64),
        ] {
            for (x, y) in [(0.0, 0.0), (1767.0, 993.0), (321.25, 600.5)] {
                let (tx, ty) = r.to_target(x, y);
                let (sx, sy) = r.to_source(tx, ty);
                assert!((sx - x).abs() < 1e-9 && (sy - y).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn controlnet_size_matches_annotator_rule() {
        // 1768x994: k = 512/994, 1768*k = 910.7 -> 14.23*64 -> 896; 994*k = 512.
        let r = Resize::short_side(1768, 994, 512, 64);
        assert_eq!((r.dst_width, r.dst_height), (896, 512));
        let r = Resize::short_side(1280, 720, 512, 64);
        assert_eq!((r.dst_width, r.dst_height), (896, 512));
    }

    #[test]
    fn letterbox_centres_the_frame() {
        let r = Resize::letterbox(200, 100, 224, 224);
        assert!(r.offset_x.abs() < 1e-9);
        assert!((r.offset_y - 56.0).abs() < 1e-9);
        // The frame's corner pixel edge lands on the padding boundary.
        let (_, y) = r.to_target(0.0, -0.5);
        assert!((y - 55.5).abs() < 1e-9);
    }
}
