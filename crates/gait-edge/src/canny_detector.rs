//! The `kind = "canny"` edge stage: ControlNet's canny annotator.

use std::path::PathBuf;

use gait_core::{EdgeDetector, EdgeMap, Frame, StageContext, StageError};
use serde::{Deserialize, Serialize};

use crate::canny::{Canny, CannyParams};
use crate::person_mask::{MaskKind, MaskSettings, PersonMask};
use crate::working_size::{DEFAULT_RESOLUTION, to_working_size};

/// `[edge] kind = "canny"`: thresholds, gradient norm and working size.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CannyConfig {
    /// Weak-edge threshold (annotator default 100).
    pub low: f64,
    /// Strong-edge threshold (annotator default 200).
    pub high: f64,
    /// L2 gradient magnitude instead of L1 (OpenCV's `L2gradient`).
    pub l2_gradient: bool,
    /// Short side of the working image (sides rounded to multiples of 64);
    /// 0 = the frame's own size.
    pub resolution: u32,
    /// Person mask: `"none"` (default) or `"selfie"` (MediaPipe selfie
    /// segmentation; edges outside the person are removed).
    pub mask: MaskKind,
    /// Person probability threshold of the mask.
    pub mask_threshold: f32,
    /// Pixels the mask is dilated by (at the working size).
    pub mask_dilate: u32,
    /// Mask model, relative to the models folder unless absolute (default
    /// `blazepose/selfie_segmentation.tflite`).
    pub mask_model: Option<PathBuf>,
}

impl Default for CannyConfig {
    fn default() -> Self {
        let p = CannyParams::default();
        Self {
            low: p.low,
            high: p.high,
            l2_gradient: p.l2_gradient,
            resolution: DEFAULT_RESOLUTION,
            mask: MaskKind::None,
            mask_threshold: 0.5,
            mask_dilate: 8,
            mask_model: None,
        }
    }
}

impl CannyConfig {
    pub fn params(&self) -> CannyParams {
        CannyParams {
            low: self.low,
            high: self.high,
            l2_gradient: self.l2_gradient,
        }
    }

    /// The person-mask keys of this config.
    pub fn mask_settings(&self) -> MaskSettings {
        MaskSettings {
            kind: self.mask,
            threshold: self.mask_threshold,
            dilate: self.mask_dilate,
            model: self.mask_model.clone(),
        }
    }

    pub(crate) fn validate(&self) -> Result<(), StageError> {
        if !(self.low.is_finite() && self.high.is_finite() && self.low >= 0.0 && self.high >= 0.0) {
            return Err(StageError::BadInput(format!(
                "edge.low and edge.high must be finite and >= 0 (got {} and {})",
                self.low, self.high
            )));
        }
        Ok(())
    }
}

/// Resizes each frame to the working size and runs [`Canny`] on its RGB pixels.
pub struct CannyDetector {
    canny: Canny,
    resolution: u32,
    mask: Option<PersonMask>,
}

impl CannyDetector {
    pub fn new(config: &CannyConfig) -> Self {
        Self {
            canny: Canny::new(config.params()),
            resolution: config.resolution,
            mask: None,
        }
    }

    /// As [`CannyDetector::new`], with the person mask the config asks for.
    pub fn build(config: &CannyConfig, ctx: &StageContext) -> Result<Self, StageError> {
        let mut d = Self::new(config);
        d.mask = config.mask_settings().build(ctx)?;
        Ok(d)
    }
}

impl EdgeDetector for CannyDetector {
    fn detect(&mut self, frames: &[Frame]) -> Result<Vec<EdgeMap>, StageError> {
        frames
            .iter()
            .map(|frame| {
                if frame.width() == 0 || frame.height() == 0 {
                    return Err(StageError::BadInput(format!(
                        "frame {} is empty ({}x{})",
                        frame.index,
                        frame.width(),
                        frame.height()
                    )));
                }
                let (image, resize) = to_working_size(frame, self.resolution);
                let mut edges = self.canny.rgb(&image);
                if let Some(mask) = &self.mask {
                    mask.apply(&image, &mut edges)?;
                }
                Ok(EdgeMap {
                    index: frame.index,
                    image: edges,
                    resize,
                })
            })
            .collect()
    }
}
