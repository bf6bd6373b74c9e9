//! Why a Python stage could not be loaded, or misbehaved.

use gait_core::StageError;

/// A Python stage failed; every message names the stage and, for a call,
/// the first frame of the call.
#[derive(Debug, thiserror::Error)]
pub enum PythonStageError {
    #[error(
        "cannot import module `{module}` ({reason}); put its folder on PYTHONPATH or install it into the active virtual environment"
    )]
    Import { module: String, reason: String },
    #[error("module `{module}` has no class `{class}`")]
    NoClass { module: String, class: String },
    #[error("{class}(options) raised {reason}")]
    Construct { class: String, reason: String },
    #[error("the class has no method `{method}`; a Python {family} stage defines {wanted}")]
    NoMethod {
        method: &'static str,
        family: &'static str,
        wanted: &'static str,
    },
    #[error(
        "keypoints = {found:?} is not a known layout; declare one of {known} as the class attribute `keypoints`"
    )]
    Layout { found: String, known: String },
    #[error("{method} raised on frame {frame}: {reason}")]
    Raised {
        method: &'static str,
        frame: usize,
        reason: String,
    },
    #[error("{method} returned bad data for frame {frame}: {reason}")]
    Malformed {
        method: &'static str,
        frame: usize,
        reason: String,
    },
    #[error(
        "{method} kept a frame array after returning (frame {frame}); frames view gait's memory only during the call, so keep `frame.copy()` instead"
    )]
    KeptFrame { method: &'static str, frame: usize },
    #[error("Python stages need numpy in the interpreter ({reason}); pip install numpy")]
    NoNumpy { reason: String },
}

impl PythonStageError {
    /// The stage error naming `label` ("module.Class").
    pub(crate) fn at(self, label: &str) -> StageError {
        StageError::External {
            stage: format!("python stage {label}"),
            reason: self.to_string(),
        }
    }
}
