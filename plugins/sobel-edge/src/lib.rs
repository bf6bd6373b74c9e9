//! Example gait plugin: white where the Sobel gradient magnitude of the gray
//! image exceeds `threshold`, black elsewhere, at the frame's own size.
//!
//! ```toml
//! [edge]
//! kind = "plugin"
//! path = "target/release/libgait_sobel_edge.so"
//! [edge.options]
//! threshold = 100.0
//! ```

mod sobel;

use gait_core::{EdgeDetector, EdgeMap, Frame, Resize, StageContext, StageError};
use gait_plugin::PluginStage;
use serde::Deserialize;

/// `[edge.options]` of this plugin.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SobelOptions {
    /// Gradient magnitude (gray levels 0..255; at most about 1442) above
    /// which a pixel is an edge.
    pub threshold: f32,
}

impl Default for SobelOptions {
    fn default() -> Self {
        Self { threshold: 100.0 }
    }
}

/// The Sobel edge stage.
pub struct SobelEdge {
    threshold: f32,
}

impl PluginStage for SobelEdge {
    type Options = SobelOptions;

    fn create(options: SobelOptions, _ctx: &StageContext) -> Result<Self, StageError> {
        if !(options.threshold.is_finite() && options.threshold >= 0.0) {
            return Err(StageError::BadInput(format!(
                "threshold must be a finite number >= 0, got {}",
                options.threshold
            )));
        }
        Ok(Self {
            threshold: options.threshold,
        })
    }
}

impl EdgeDetector for SobelEdge {
    fn detect(&mut self, frames: &[Frame]) -> Result<Vec<EdgeMap>, StageError> {
        Ok(frames
            .iter()
            .map(|f| EdgeMap {
                index: f.index,
                image: sobel::edges(&f.image, self.threshold),
                resize: Resize::identity(f.width(), f.height()),
            })
            .collect())
    }
}

gait_plugin::export_edge_detector!(SobelEdge);
