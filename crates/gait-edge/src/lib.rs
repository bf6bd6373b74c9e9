//! Edge detectors implementing [`gait_core::EdgeDetector`], chosen in the
//! `[edge]` table of a pipeline config by `kind`.

mod blur;
mod canny;
mod canny_detector;
mod edge_contrast;
mod hed;
mod hed_candle;
mod hed_fuse;
mod hed_net;
mod hed_ort;
mod person_mask;
mod resample;
mod working_size;

use std::path::PathBuf;

use gait_core::{EdgeDetector, StageContext, StageError};
use serde::{Deserialize, Serialize};

pub use blur::{Region, blur_px};
pub use canny::{Canny, CannyParams, edge_f1};
pub use canny_detector::{CannyConfig, CannyDetector};
pub use edge_contrast::edge_contrast;
pub use hed::{CandleHedNet, HedConfig, HedDetector, HedError, HedNetwork, OrtHedNet};
pub use hed_fuse::{SideOutput, fuse};
pub use person_mask::{MaskKind, MaskSettings, PersonMask, SELFIE_MODEL};
pub use resample::resize_for_annotator;
pub use working_size::{DEFAULT_RESOLUTION, to_working_size, working_resize};

/// The `[edge]` table. `kind` picks the detector; the other keys belong to it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum EdgeConfig {
    /// No edge map: the regenerator sees only the frame (the paper's baseline).
    None,
    /// OpenCV-exact Canny, as ControlNet's canny annotator.
    Canny(CannyConfig),
    /// ControlNet's HED soft-edge annotator on candle or ort.
    Hed(HedConfig),
    /// An external detector loaded from a shared library (see docs/adding-a-stage.md).
    Plugin(gait_plugin::PluginConfig),
    /// A detector written in Python (see docs/adding-a-stage.md).
    Python(gait_python::PythonStageConfig),
}

impl EdgeConfig {
    /// Builds the detector; `Ok(None)` for `kind = "none"`.
    pub fn build(&self, ctx: &StageContext) -> Result<Option<Box<dyn EdgeDetector>>, StageError> {
        match self {
            EdgeConfig::None => Ok(None),
            EdgeConfig::Canny(c) => {
                c.validate()?;
                Ok(Some(Box::new(CannyDetector::build(c, ctx)?)))
            }
            EdgeConfig::Hed(c) => Ok(Some(Box::new(c.build(ctx)?))),
            EdgeConfig::Plugin(p) => Ok(Some(gait_plugin::load_edge_detector(p, ctx)?)),
            EdgeConfig::Python(p) => Ok(Some(gait_python::load_edge_detector(p, ctx)?)),
        }
    }

    /// Model files the detector reads (checksummed into `run.json`).
    pub fn model_files(&self, ctx: &StageContext) -> Vec<PathBuf> {
        match self {
            EdgeConfig::None => Vec::new(),
            EdgeConfig::Canny(c) => c.mask_settings().model_path(ctx).into_iter().collect(),
            EdgeConfig::Hed(c) => std::iter::once(c.weights_path(ctx))
                .chain(c.mask_settings().model_path(ctx))
                .collect(),
            EdgeConfig::Plugin(p) => vec![p.resolved_path()],
            EdgeConfig::Python(p) => p.module_file().into_iter().collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<EdgeConfig, toml::de::Error> {
        toml::from_str(text)
    }

    #[test]
    fn canny_keys_and_defaults() {
        let c = parse("kind = \"canny\"").unwrap();
        assert_eq!(c, EdgeConfig::Canny(CannyConfig::default()));
        let c =
            parse("kind = \"canny\"\nlow = 50\nhigh = 120.5\nl2_gradient = true\nresolution = 0")
                .unwrap();
        let EdgeConfig::Canny(c) = c else {
            panic!("not canny: {c:?}")
        };
        assert_eq!(
            (c.low, c.high, c.l2_gradient, c.resolution),
            (50.0, 120.5, true, 0)
        );
    }

    #[test]
    fn unknown_canny_key_is_named() {
        let err = parse("kind = \"canny\"\nthreshold = 3")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("threshold") && err.contains("l2_gradient"),
            "{err}"
        );
    }

    #[test]
    fn negative_threshold_is_rejected_at_build() {
        let c = parse("kind = \"canny\"\nlow = -1").unwrap();
        let err = c
            .build(&StageContext::new("/nonexistent"))
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("edge.low"), "{err}");
    }
}
