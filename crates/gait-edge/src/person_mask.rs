//! Optional person mask for edge maps: MediaPipe's selfie segmentation
//! (`selfie_segmentation.tflite`, general model, 256x256 RGB in [0, 1]) run on
//! the working image; edges outside the thresholded, dilated mask are zeroed
//! so background clutter does not reach the regenerator.

use std::path::{Path, PathBuf};

use gait_core::{StageContext, StageError};
use gait_tflite::{CandleGraph, Graph};
use image::{GrayImage, RgbImage, imageops};
use serde::{Deserialize, Serialize};

/// Default model file, relative to the models folder.
pub const SELFIE_MODEL: &str = "blazepose/selfie_segmentation.tflite";
const FETCH_HINT: &str = "get it with `gait models fetch blazepose`";
/// The general selfie model's square input side.
const SIDE: u32 = 256;

/// `mask` key of the edge configs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MaskKind {
    /// Keep every edge.
    #[default]
    None,
    /// MediaPipe selfie segmentation.
    Selfie,
}

/// The mask keys shared by the canny and hed configs.
#[derive(Debug, Clone, PartialEq)]
pub struct MaskSettings {
    pub kind: MaskKind,
    /// Probability above which a pixel is the person.
    pub threshold: f32,
    /// Pixels the mask grows by (square neighbourhood), so outline edges survive.
    pub dilate: u32,
    /// Model file, relative to the models folder unless absolute.
    pub model: Option<PathBuf>,
}

impl MaskSettings {
    /// The model file, resolved in the models folder; `None` when no mask.
    pub fn model_path(&self, ctx: &StageContext) -> Option<PathBuf> {
        (self.kind != MaskKind::None)
            .then(|| ctx.model_path(self.model.as_deref().unwrap_or(Path::new(SELFIE_MODEL))))
    }

    /// Loads the mask network; `Ok(None)` for `mask = "none"`.
    pub fn build(&self, ctx: &StageContext) -> Result<Option<PersonMask>, StageError> {
        let Some(path) = self.model_path(ctx) else {
            return Ok(None);
        };
        if !(0.0..=1.0).contains(&self.threshold) {
            return Err(StageError::BadInput(format!(
                "edge.mask_threshold must be in [0, 1] (got {})",
                self.threshold
            )));
        }
        if !path.is_file() {
            return Err(StageError::MissingModel {
                path,
                hint: FETCH_HINT.to_string(),
            });
        }
        let graph = Graph::load(&path).map_err(|e| StageError::bad_model(&path, e))?;
        let net = CandleGraph::new(&graph).map_err(|e| StageError::bad_model(&path, e))?;
        Ok(Some(PersonMask {
            net,
            threshold: self.threshold,
            dilate: self.dilate,
        }))
    }
}

/// The loaded segmentation network with its threshold and dilation.
pub struct PersonMask {
    net: CandleGraph,
    threshold: f32,
    dilate: u32,
}

impl PersonMask {
    /// Raw person probability at the model's 256x256 resolution (row-major),
    /// for `image` stretched to 256x256 as MediaPipe does.
    pub fn probability(&self, image: &RgbImage) -> Result<Vec<f32>, StageError> {
        let small = if image.dimensions() == (SIDE, SIDE) {
            image.clone()
        } else {
            imageops::resize(image, SIDE, SIDE, imageops::FilterType::Triangle)
        };
        let input: Vec<f32> = small
            .as_raw()
            .iter()
            .map(|&v| f32::from(v) / 255.0)
            .collect();
        let mut out = self
            .net
            .run(&input)
            .map_err(|e| StageError::backend("candle", e))?;
        if out.is_empty() || out[0].len() != (SIDE * SIDE) as usize {
            return Err(StageError::backend(
                "candle",
                "selfie model output has the wrong size",
            ));
        }
        Ok(out.swap_remove(0))
    }

    /// The binary person mask (255 = person) at `image`'s size.
    pub fn mask(&self, image: &RgbImage) -> Result<GrayImage, StageError> {
        let p = self.probability(image)?;
        let (w, h) = image.dimensions();
        let mut m = GrayImage::new(w, h);
        // Bilinear upsampling with half-pixel centres, then threshold.
        let sx = SIDE as f32 / w as f32;
        let sy = SIDE as f32 / h as f32;
        let last = (SIDE - 1) as f32;
        for y in 0..h {
            let fy = ((y as f32 + 0.5) * sy - 0.5).clamp(0.0, last);
            let (y0, ty) = (fy.floor() as usize, fy.fract());
            let y1 = (y0 + 1).min(SIDE as usize - 1);
            for x in 0..w {
                let fx = ((x as f32 + 0.5) * sx - 0.5).clamp(0.0, last);
                let (x0, tx) = (fx.floor() as usize, fx.fract());
                let x1 = (x0 + 1).min(SIDE as usize - 1);
                let at = |yy: usize, xx: usize| p[yy * SIDE as usize + xx];
                let top = at(y0, x0) * (1.0 - tx) + at(y0, x1) * tx;
                let bottom = at(y1, x0) * (1.0 - tx) + at(y1, x1) * tx;
                if top * (1.0 - ty) + bottom * ty > self.threshold {
                    m.put_pixel(x, y, image::Luma([255]));
                }
            }
        }
        Ok(dilate(&m, self.dilate))
    }

    /// Zeroes the edges of `edges` (same size as `image`) outside the mask.
    pub fn apply(&self, image: &RgbImage, edges: &mut GrayImage) -> Result<(), StageError> {
        if edges.dimensions() != image.dimensions() {
            return Err(StageError::BadInput(format!(
                "edge map {:?} and image {:?} differ in size",
                edges.dimensions(),
                image.dimensions()
            )));
        }
        let m = self.mask(image)?;
        for (e, k) in edges.pixels_mut().zip(m.pixels()) {
            if k[0] == 0 {
                e[0] = 0;
            }
        }
        Ok(())
    }
}

/// Square (Chebyshev) dilation by `r` pixels, separable: rows then columns.
fn dilate(m: &GrayImage, r: u32) -> GrayImage {
    if r == 0 {
        return m.clone();
    }
    let (w, h) = (m.width() as usize, m.height() as usize);
    let r = r as usize;
    let src = m.as_raw();
    let mut rows = vec![0u8; w * h];
    for y in 0..h {
        let line = &src[y * w..(y + 1) * w];
        for x in 0..w {
            let (a, b) = (x.saturating_sub(r), (x + r).min(w - 1));
            rows[y * w + x] = line[a..=b].iter().copied().max().unwrap_or(0);
        }
    }
    let mut out = vec![0u8; w * h];
    for x in 0..w {
        for y in 0..h {
            let (a, b) = (y.saturating_sub(r), (y + r).min(h - 1));
            out[y * w + x] = (a..=b).map(|yy| rows[yy * w + x]).max().unwrap_or(0);
        }
    }
    GrayImage::from_raw(w as u32, h as u32, out).unwrap_or_else(|| m.clone())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dilation_grows_a_point_to_a_square() {
        let mut m = GrayImage::new(9, 9);
        m.put_pixel(4, 4, image::Luma([255]));
        let d = dilate(&m, 2);
        let on: Vec<(u32, u32)> = d
            .enumerate_pixels()
            .filter(|p| p.2[0] == 255)
            .map(|p| (p.0, p.1))
            .collect();
        assert_eq!(on.len(), 25);
        assert!(
            on.iter()
                .all(|&(x, y)| (2..=6).contains(&x) && (2..=6).contains(&y))
        );
    }

    #[test]
    fn missing_model_names_file_and_fetch_command() {
        let s = MaskSettings {
            kind: MaskKind::Selfie,
            threshold: 0.5,
            dilate: 8,
            model: None,
        };
        let err = s
            .build(&StageContext::new("/nonexistent"))
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            err.contains("selfie_segmentation.tflite")
                && err.contains("gait models fetch blazepose"),
            "{err}"
        );
    }
}
