//! How blurred a region of a frame is, in pixels: the standard deviation of the Gaussian that
//! would blur a sharp edge into the edges found there. A walker out of focus gives the pose
//! model limbs it draws elsewhere while its likelihoods stay high (the sample blurred by sigma
//! 8 px: curves 9-14 deg RMS off, likelihoods 0.87-0.98), so the run measures the blur itself.
//! Motion blur, one-directional and mostly on the swinging foot, reads little here (the sample
//! with a 1/30 s shutter: 1.9-2.2 px against 1.5-1.8 sharp; BENCHMARKS.md).
//!
//! The estimate is the re-blur gradient ratio (Zhuo and Sim, "Defocus map estimation from a
//! single image", Pattern Recognition 2011): at an edge blurred by `s`, blurring again by `r`
//! divides the gradient's peak by `sqrt(s^2 + r^2) / s`, so the ratio of the two gradients gives
//! `s`. It is read where the edges are strongest (the top 2 % of the re-blurred gradient) and
//! the median taken, so flat background and noise do not count. A sharp frame reads about
//! 1.4-1.8 px (the sensor's and the encoder's own softness); the estimate compresses large
//! blurs (sigma 8 reads about 5) but keeps their order.

use image::RgbImage;

/// The blur of the first, small Gaussian: it takes the pixel grid's aliasing off both
/// gradients, and is part of the blur read.
const PRE_BLUR: f32 = 0.5;
/// The re-blur: wide enough that the ratio changes clearly between 1 and 8 px.
const RE_BLUR: f32 = 4.0;
/// The share of the region's pixels, those with the strongest re-blurred gradient, read.
const STRONGEST: f64 = 0.02;
/// Fewer edge pixels than this, or a re-blurred gradient weaker than this (grey levels per
/// pixel) at the strongest edges: too little structure to say.
const MIN_EDGE_PIXELS: usize = 32;
const MIN_GRADIENT: f32 = 1.0;

/// A rectangle of a frame, in pixels: `x0 <= x < x1`, `y0 <= y < y1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Region {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

/// The blur of `region` of `image` in pixels (see the module docs); `None` when the region
/// is empty after clipping to the image or has too little structure to measure.
pub fn blur_px(image: &RgbImage, region: Region) -> Option<f64> {
    let pad = (3.0 * total(RE_BLUR)).ceil() as u32 + 1;
    let outer = Region {
        x0: region.x0.saturating_sub(pad),
        y0: region.y0.saturating_sub(pad),
        x1: (region.x1.saturating_add(pad)).min(image.width()),
        y1: (region.y1.saturating_add(pad)).min(image.height()),
    };
    let (w, h) = (
        outer.x1.checked_sub(outer.x0)? as usize,
        outer.y1.checked_sub(outer.y0)? as usize,
    );
    if w < 3 || h < 3 {
        return None;
    }
    let grey = grey(image, outer);
    let sharp = gradient(&blurred(&grey, w, h, PRE_BLUR), w, h);
    let soft = gradient(&blurred(&grey, w, h, total(RE_BLUR)), w, h);
    // The region itself, clipped, less the one-pixel rim the gradient does not reach.
    let xs = (region.x0.max(outer.x0 + 1) - outer.x0) as usize
        ..(region.x1.min(outer.x1 - 1).saturating_sub(outer.x0)) as usize;
    let ys = (region.y0.max(outer.y0 + 1) - outer.y0) as usize
        ..(region.y1.min(outer.y1 - 1).saturating_sub(outer.y0)) as usize;
    let inside: Vec<usize> = ys
        .flat_map(|y| xs.clone().map(move |x| y * w + x))
        .collect();
    read_blur(&sharp, &soft, &inside)
}

/// The median blur over the strongest edges among the pixels `inside`.
fn read_blur(sharp: &[f32], soft: &[f32], inside: &[usize]) -> Option<f64> {
    let mut strength: Vec<f32> = inside.iter().map(|&i| soft[i]).collect();
    let keep = ((strength.len() as f64 * STRONGEST).ceil() as usize).max(1);
    if strength.len() < MIN_EDGE_PIXELS {
        return None;
    }
    let cut = strength.len() - keep;
    let (_, threshold, _) = strength.select_nth_unstable_by(cut, f32::total_cmp);
    let threshold = *threshold;
    if threshold < MIN_GRADIENT {
        return None;
    }
    let mut blur: Vec<f64> = inside
        .iter()
        .filter(|&&i| soft[i] >= threshold)
        .filter_map(|&i| {
            let ratio = f64::from(sharp[i]) / f64::from(soft[i]);
            // The ratio of the blurs' sizes: sqrt(s^2 + p^2 + r^2) / sqrt(s^2 + p^2).
            (ratio > 1.0001).then(|| f64::from(RE_BLUR) / (ratio * ratio - 1.0).sqrt())
        })
        .collect();
    if blur.len() < MIN_EDGE_PIXELS.min(keep) {
        return None;
    }
    let mid = blur.len() / 2;
    let (_, median, _) = blur.select_nth_unstable_by(mid, f64::total_cmp);
    Some(*median)
}

/// The re-blur on top of the pre-blur, as one Gaussian.
fn total(re: f32) -> f32 {
    (PRE_BLUR * PRE_BLUR + re * re).sqrt()
}

/// The luma (BT.601) of `r`, row by row.
pub(crate) fn grey(image: &RgbImage, r: Region) -> Vec<f32> {
    let (w, raw) = (image.width() as usize, image.as_raw());
    let mut out = Vec::with_capacity(((r.x1 - r.x0) * (r.y1 - r.y0)) as usize);
    for y in r.y0 as usize..r.y1 as usize {
        let row = &raw[3 * (y * w + r.x0 as usize)..3 * (y * w + r.x1 as usize)];
        out.extend(
            row.chunks_exact(3).map(|p| {
                0.299 * f32::from(p[0]) + 0.587 * f32::from(p[1]) + 0.114 * f32::from(p[2])
            }),
        );
    }
    out
}

/// `grey` convolved with a Gaussian of standard deviation `sigma`, edges repeated. Each pass
/// adds whole rows scaled by a tap, so the inner loops run over contiguous memory.
fn blurred(grey: &[f32], w: usize, h: usize, sigma: f32) -> Vec<f32> {
    let kernel = gaussian(sigma);
    let r = kernel.len() / 2;
    let mut rows = vec![0.0f32; grey.len()];
    let mut padded = vec![0.0f32; w + 2 * r];
    for (src, dst) in grey.chunks_exact(w).zip(rows.chunks_exact_mut(w)) {
        padded[..r].fill(src[0]);
        padded[r..r + w].copy_from_slice(src);
        padded[r + w..].fill(src[w - 1]);
        for (j, k) in kernel.iter().enumerate() {
            for (d, v) in dst.iter_mut().zip(&padded[j..j + w]) {
                *d += k * v;
            }
        }
    }
    let mut out = vec![0.0f32; grey.len()];
    for (y, dst) in out.chunks_exact_mut(w).enumerate() {
        for (j, k) in kernel.iter().enumerate() {
            let from = (y + j).saturating_sub(r).min(h - 1);
            for (d, v) in dst.iter_mut().zip(&rows[from * w..(from + 1) * w]) {
                *d += k * v;
            }
        }
    }
    out
}

/// A normalised Gaussian kernel reaching 3 standard deviations.
fn gaussian(sigma: f32) -> Vec<f32> {
    let r = (3.0 * sigma).ceil() as i32;
    let k: Vec<f32> = (-r..=r)
        .map(|x| (-(x * x) as f32 / (2.0 * sigma * sigma)).exp())
        .collect();
    let sum: f32 = k.iter().sum();
    k.into_iter().map(|v| v / sum).collect()
}

/// The gradient's magnitude by central differences (0 on the rim).
fn gradient(img: &[f32], w: usize, h: usize) -> Vec<f32> {
    let mut out = vec![0.0; img.len()];
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let i = y * w + x;
            let gx = (img[i + 1] - img[i - 1]) * 0.5;
            let gy = (img[i + w] - img[i - w]) * 0.5;
            out[i] = (gx * gx + gy * gy).sqrt();
        }
    }
    out
}

#[cfg(test)]
mod tests;
