//! Image regenerators implementing [`gait_core::ImageRegenerator`], chosen in
//! the `[regenerator]` table of a pipeline config by `kind`.

mod passthrough;

use std::path::PathBuf;

use gait_core::{ImageRegenerator, StageContext, StageError};
pub use passthrough::Passthrough;
use serde::{Deserialize, Serialize};

/// The `[regenerator]` table. `kind` picks the regenerator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum RegeneratorConfig {
    /// Original frames go to the pose model unchanged.
    Passthrough,
}

impl RegeneratorConfig {
    pub fn build(&self, _ctx: &StageContext) -> Result<Box<dyn ImageRegenerator>, StageError> {
        match self {
            RegeneratorConfig::Passthrough => Ok(Box::new(Passthrough)),
        }
    }

    /// True when the regenerator needs an edge map (an `[edge]` kind other than "none").
    pub fn needs_edges(&self) -> bool {
        match self {
            RegeneratorConfig::Passthrough => false,
        }
    }

    /// True when the regenerator hands frames on unchanged, so the runner need
    /// not cache its output.
    pub fn is_identity(&self) -> bool {
        matches!(self, RegeneratorConfig::Passthrough)
    }

    /// Model files the regenerator reads (checksummed into `run.json`).
    pub fn model_files(&self, _ctx: &StageContext) -> Vec<PathBuf> {
        Vec::new()
    }
}
