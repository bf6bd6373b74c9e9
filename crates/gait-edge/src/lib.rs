//! Edge detectors implementing [`gait_core::EdgeDetector`], chosen in the
//! `[edge]` table of a pipeline config by `kind`.

use std::path::PathBuf;

use gait_core::{EdgeDetector, StageContext, StageError};
use serde::{Deserialize, Serialize};

/// The `[edge]` table. `kind` picks the detector; the other keys belong to it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum EdgeConfig {
    /// No edge map: the regenerator sees only the frame (the paper's baseline).
    None,
}

impl EdgeConfig {
    /// Builds the detector; `Ok(None)` for `kind = "none"`.
    pub fn build(&self, _ctx: &StageContext) -> Result<Option<Box<dyn EdgeDetector>>, StageError> {
        match self {
            EdgeConfig::None => Ok(None),
        }
    }

    /// Model files the detector reads (checksummed into `run.json`).
    pub fn model_files(&self, _ctx: &StageContext) -> Vec<PathBuf> {
        match self {
            EdgeConfig::None => Vec::new(),
        }
    }
}
