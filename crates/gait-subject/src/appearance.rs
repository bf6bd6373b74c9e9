//! Colour statistics of a body, to tell people apart where positions alone
//! are ambiguous (two people crossing, the subject coming back into view).

use gait_core::PersonBox;
use image::RgbImage;
use serde::{Deserialize, Serialize};

/// Mean colour of the torso and of the legs, each as RGB in [0, 1]; `NaN`
/// where the region lies outside the image.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Appearance(#[serde(deserialize_with = "nan_as_null")] pub [f32; 6]);

/// JSON writes `NaN` as `null`; read it back as `NaN`, so that a cached frame
/// with a body part outside the image is not taken for a damaged entry (and
/// detected again on every rerun).
fn nan_as_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[f32; 6], D::Error> {
    let v: [Option<f32>; 6] = Deserialize::deserialize(d)?;
    Ok(v.map(|x| x.unwrap_or(f32::NAN)))
}

/// Samples per region side: enough for a mean colour, cheap on full-HD frames.
const GRID: usize = 8;

impl Appearance {
    /// The appearance of the body in `b` in `image`.
    pub fn of(image: &RgbImage, b: &PersonBox) -> Self {
        let [cx, cy] = b.centre;
        let (ux, uy) = (b.top[0] - cx, b.top[1] - cy);
        let len = ux.hypot(uy).max(1.0);
        let (ux, uy) = (ux / len, uy / len);
        // Across the body axis, a third of the hip-to-top distance each way.
        let (vx, vy) = (-uy * len / 3.0, ux * len / 3.0);
        // Torso: from just above the hips to the shoulders, up the axis.
        let torso = region(
            image,
            [cx, cy],
            [ux * len, uy * len],
            [vx, vy],
            (0.15, 0.85),
        );
        // Legs: the same length down the axis from the hips.
        let legs = region(
            image,
            [cx, cy],
            [-ux * len, -uy * len],
            [vx, vy],
            (0.1, 0.9),
        );
        Appearance([torso[0], torso[1], torso[2], legs[0], legs[1], legs[2]])
    }

    /// Mean absolute colour difference over the regions both have, in
    /// [0, 1]; `None` when they share no region.
    pub fn distance(&self, other: &Appearance) -> Option<f32> {
        let (sum, n) = self
            .0
            .iter()
            .zip(&other.0)
            .filter(|(a, b)| a.is_finite() && b.is_finite())
            .fold((0.0, 0), |(s, n), (a, b)| (s + (a - b).abs(), n + 1));
        (n > 0).then(|| sum / n as f32)
    }

    /// The mean of several appearances, region by region.
    pub fn mean<'a>(all: impl IntoIterator<Item = &'a Appearance>) -> Appearance {
        let mut sum = [0.0f32; 6];
        let mut n = [0usize; 6];
        for a in all {
            for k in 0..6 {
                if a.0[k].is_finite() {
                    sum[k] += a.0[k];
                    n[k] += 1;
                }
            }
        }
        Appearance(std::array::from_fn(|k| {
            if n[k] > 0 {
                sum[k] / n[k] as f32
            } else {
                f32::NAN
            }
        }))
    }
}

/// Mean RGB over the parallelogram `origin + s * along + t * across` for `s`
/// in `span` and `t` in [-1, 1]; NaN when fewer than half the samples fall
/// inside the image.
fn region(
    image: &RgbImage,
    origin: [f32; 2],
    along: [f32; 2],
    across: [f32; 2],
    span: (f32, f32),
) -> [f32; 3] {
    let (w, h) = (image.width() as f32, image.height() as f32);
    let mut sum = [0.0f32; 3];
    let mut n = 0usize;
    for i in 0..GRID {
        let s = span.0 + (span.1 - span.0) * (i as f32 + 0.5) / GRID as f32;
        for j in 0..GRID {
            let t = -1.0 + 2.0 * (j as f32 + 0.5) / GRID as f32;
            let x = origin[0] + s * along[0] + t * across[0];
            let y = origin[1] + s * along[1] + t * across[1];
            if x >= 0.0 && y >= 0.0 && x < w && y < h {
                let p = image.get_pixel(x as u32, y as u32).0;
                for k in 0..3 {
                    sum[k] += p[k] as f32 / 255.0;
                }
                n += 1;
            }
        }
    }
    if n * 2 < GRID * GRID {
        return [f32::NAN; 3];
    }
    sum.map(|v| v / n as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_region_outside_the_image_survives_json() {
        let a = Appearance([0.5, f32::NAN, 0.2, 0.1, 0.3, f32::NAN]);
        let json = serde_json::to_string(&a).unwrap();
        let back: Appearance = serde_json::from_str(&json).unwrap();
        assert_eq!(back.distance(&a), Some(0.0));
        assert!(back.0[1].is_nan() && back.0[5].is_nan());
    }
    use image::Rgb;

    #[test]
    fn torso_and_legs_are_measured_apart() {
        // Red above y = 50, blue below: a body with hips at y = 50.
        let img = RgbImage::from_fn(100, 100, |_, y| {
            if y < 50 {
                Rgb([255, 0, 0])
            } else {
                Rgb([0, 0, 255])
            }
        });
        let a = Appearance::of(&img, &PersonBox::upright(50.0, 50.0, 75.0, 1.0));
        assert!((a.0[0] - 1.0).abs() < 1e-6 && a.0[2].abs() < 1e-6, "{a:?}");
        assert!(a.0[3].abs() < 1e-6 && (a.0[5] - 1.0).abs() < 1e-6, "{a:?}");
        let same = Appearance::of(&img, &PersonBox::upright(40.0, 50.0, 75.0, 1.0));
        assert!(a.distance(&same).unwrap() < 1e-6);
    }

    #[test]
    fn out_of_image_regions_are_skipped() {
        let img = RgbImage::from_pixel(100, 100, Rgb([10, 20, 30]));
        // Hips at the bottom edge: the legs are outside.
        let a = Appearance::of(&img, &PersonBox::upright(50.0, 99.0, 75.0, 1.0));
        assert!(a.0[0].is_finite() && a.0[3].is_nan());
        let b = Appearance::of(&img, &PersonBox::upright(50.0, 50.0, 75.0, 1.0));
        assert!(a.distance(&b).unwrap() < 1e-6);
        let m = Appearance::mean([&a, &b]);
        assert!(m.0.iter().all(|v| v.is_finite()));
    }
}
