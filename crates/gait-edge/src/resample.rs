//! Resampling a frame to the size an annotator works on, the way
//! `controlnet_aux.util.resize_image` does it: OpenCV's `INTER_AREA` when the
//! frame shrinks, a Lanczos filter when it grows.
//!
//! The area filter restates OpenCV's rule: every target pixel is the
//! coverage-weighted mean of the source pixels under its footprint (separable,
//! f32 weights, rounded to nearest). Enlarging uses the `image` crate's
//! Lanczos3, close to but not identical with OpenCV's `INTER_LANCZOS4`; the rare
//! mixed case (the short side shrinks while the other side grows slightly
//! through the rounding to multiples of 64) uses bilinear filtering.

use image::RgbImage;
use image::imageops::{self, FilterType};

/// Resizes `image` to `width` x `height` as ControlNet's annotators do.
pub fn resize_for_annotator(image: &RgbImage, width: u32, height: u32) -> RgbImage {
    let (sw, sh) = image.dimensions();
    if (sw, sh) == (width, height) {
        return image.clone();
    }
    if width == 0 || height == 0 || sw == 0 || sh == 0 {
        return RgbImage::new(width, height);
    }
    if width <= sw && height <= sh {
        area(image, width, height)
    } else if width >= sw && height >= sh {
        imageops::resize(image, width, height, FilterType::Lanczos3)
    } else {
        imageops::resize(image, width, height, FilterType::Triangle)
    }
}

/// One target pixel's source taps along an axis: (source index, weight).
fn area_taps(src: u32, dst: u32) -> Vec<Vec<(usize, f32)>> {
    let scale = f64::from(src) / f64::from(dst);
    let ssize = f64::from(src);
    (0..dst)
        .map(|d| {
            let f1 = f64::from(d) * scale;
            let f2 = f1 + scale;
            let cell = scale.min(ssize - f1);
            let last = (f2.floor()).min(ssize - 1.0);
            let first = f1.ceil().min(last);
            let mut taps = Vec::new();
            // A partial source pixel on the left, full ones, a partial one on the right;
            // slivers under 1e-3 pixel are ignored, as OpenCV does.
            if first - f1 > 1e-3 {
                taps.push(((first - 1.0) as usize, ((first - f1) / cell) as f32));
            }
            let mut s = first;
            while s < last {
                taps.push((s as usize, (1.0 / cell) as f32));
                s += 1.0;
            }
            if f2 - last > 1e-3 {
                let wgt = (f2 - last).min(1.0).min(cell) / cell;
                taps.push((last as usize, wgt as f32));
            }
            taps
        })
        .collect()
}

/// OpenCV `INTER_AREA` for shrinking (both target sides <= source sides).
fn area(image: &RgbImage, width: u32, height: u32) -> RgbImage {
    let (sw, sh) = image.dimensions();
    let int_x = sw % width == 0;
    let int_y = sh % height == 0;
    if int_x && int_y && sw / width == 2 && sh / height == 2 {
        return halve(image);
    }
    let xt = area_taps(sw, width);
    let yt = area_taps(sh, height);
    let src = image.as_raw();
    let srow = sw as usize * 3;
    // Horizontal pass of every source row into f32, then the vertical sums.
    let mut horiz = vec![0f32; sh as usize * width as usize * 3];
    for (y, hrow) in horiz.chunks_exact_mut(width as usize * 3).enumerate() {
        let row = &src[y * srow..(y + 1) * srow];
        for (x, taps) in xt.iter().enumerate() {
            let mut acc = [0f32; 3];
            for &(s, wgt) in taps {
                for c in 0..3 {
                    acc[c] += f32::from(row[s * 3 + c]) * wgt;
                }
            }
            hrow[x * 3..x * 3 + 3].copy_from_slice(&acc);
        }
    }
    let mut out = RgbImage::new(width, height);
    let orow = width as usize * 3;
    for (y, taps) in yt.iter().enumerate() {
        let dst = &mut out.as_mut()[y * orow..(y + 1) * orow];
        let mut acc = vec![0f32; orow];
        for &(s, wgt) in taps {
            for (a, &v) in acc.iter_mut().zip(&horiz[s * orow..(s + 1) * orow]) {
                *a += v * wgt;
            }
        }
        for (d, a) in dst.iter_mut().zip(acc) {
            *d = a.round_ties_even().clamp(0.0, 255.0) as u8;
        }
    }
    out
}

/// Exact 2x2 mean with OpenCV's rounding `(a + b + c + d + 2) >> 2`.
fn halve(image: &RgbImage) -> RgbImage {
    let (sw, sh) = image.dimensions();
    RgbImage::from_fn(sw / 2, sh / 2, |x, y| {
        let mut px = [0u8; 3];
        for (c, v) in px.iter_mut().enumerate() {
            let sum: u32 = [(0, 0), (1, 0), (0, 1), (1, 1)]
                .iter()
                .map(|&(dx, dy)| u32::from(image.get_pixel(2 * x + dx, 2 * y + dy)[c]))
                .sum();
            *v = ((sum + 2) >> 2) as u8;
        }
        image::Rgb(px)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn area_weights_sum_to_one() {
        for (s, d) in [(1280, 896), (720, 512), (600, 576), (7, 3), (10, 5)] {
            for taps in area_taps(s, d) {
                let sum: f32 = taps.iter().map(|t| t.1).sum();
                assert!((sum - 1.0).abs() < 1e-5, "{s}->{d}: {taps:?}");
                assert!(taps.iter().all(|t| t.0 < s as usize));
            }
        }
    }

    #[test]
    fn area_of_constant_image_is_constant() {
        let img = RgbImage::from_pixel(37, 23, image::Rgb([10, 128, 251]));
        let out = resize_for_annotator(&img, 19, 11);
        assert!(out.pixels().all(|p| p.0 == [10, 128, 251]));
        let out = resize_for_annotator(&img, 64, 64);
        assert_eq!(out.dimensions(), (64, 64));
    }

    #[test]
    fn halving_rounds_half_up() {
        let img = RgbImage::from_fn(2, 2, |x, y| image::Rgb([(x + y) as u8, 0, 1]));
        // (0 + 1 + 1 + 2 + 2) >> 2 = 1; (0 + 0 + 0 + 0 + 2) >> 2 = 0; (4 + 2) >> 2 = 1.
        assert_eq!(
            resize_for_annotator(&img, 1, 1).get_pixel(0, 0).0,
            [1, 0, 1]
        );
    }
}
