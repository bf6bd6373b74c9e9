//! The `kind = "canny"` edge stage: ControlNet's canny annotator.

use gait_core::{EdgeDetector, EdgeMap, Frame, StageError};
use serde::{Deserialize, Serialize};

use crate::canny::{Canny, CannyParams};
use crate::working_size::{DEFAULT_RESOLUTION, to_working_size};

/// `[edge] kind = "canny"`: thresholds, gradient norm and working size.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
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
}

impl Default for CannyConfig {
    fn default() -> Self {
        let p = CannyParams::default();
        Self {
            low: p.low,
            high: p.high,
            l2_gradient: p.l2_gradient,
            resolution: DEFAULT_RESOLUTION,
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
#[derive(Debug)]
pub struct CannyDetector {
    canny: Canny,
    resolution: u32,
}

impl CannyDetector {
    pub fn new(config: &CannyConfig) -> Self {
        Self {
            canny: Canny::new(config.params()),
            resolution: config.resolution,
        }
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
                Ok(EdgeMap {
                    index: frame.index,
                    image: self.canny.rgb(&image),
                    resize,
                })
            })
            .collect()
    }
}
