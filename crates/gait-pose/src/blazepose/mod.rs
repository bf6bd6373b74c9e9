//! MediaPipe BlazePose (full): person detector + 33-landmark model.

use std::path::PathBuf;

use gait_core::{Backend, PoseEstimator, StageContext, StageError};
use serde::{Deserialize, Serialize};

/// Keys of `[pose]` when `kind = "blazepose"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BlazeposeConfig {
    pub backend: Backend,
    /// Folder holding the model files, relative to the models folder.
    pub model_dir: PathBuf,
}

impl Default for BlazeposeConfig {
    fn default() -> Self {
        Self {
            backend: Backend::Candle,
            model_dir: PathBuf::from("blazepose"),
        }
    }
}

/// Model files, relative to `model_dir`.
const FILES: [&str; 2] = ["pose_detection.tflite", "pose_landmark_full.tflite"];

impl BlazeposeConfig {
    pub fn model_files(&self, ctx: &StageContext) -> Vec<PathBuf> {
        let dir = ctx.model_path(&self.model_dir);
        FILES.iter().map(|f| dir.join(f)).collect()
    }

    pub fn build(&self, ctx: &StageContext) -> Result<Box<dyn PoseEstimator>, StageError> {
        for path in self.model_files(ctx) {
            if !path.is_file() {
                return Err(StageError::MissingModel {
                    path,
                    hint: "run `gait models fetch blazepose`".into(),
                });
            }
        }
        // The networks land with the BlazePose issue; until then the model
        // files are checked and the run stops here with a clear message.
        Err(StageError::backend(
            self.backend.to_string(),
            "the BlazePose networks are not implemented yet",
        ))
    }
}
