use std::path::PathBuf;

use gait_core::StageError;

/// Errors of the diffusion models and pipeline.
#[derive(Debug, thiserror::Error)]
pub enum DiffuseError {
    /// Weight files are missing; `files` lists each with where it belongs.
    #[error("missing model files: {}; {hint}", files.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "))]
    Missing { files: Vec<PathBuf>, hint: String },
    /// A weight or config file cannot be used (wrong checkpoint, missing or misshapen tensor).
    #[error("model file {path}: {reason}")]
    BadModel { path: PathBuf, reason: String },
    /// The configuration asks for something this build cannot do.
    #[error("{0}")]
    Config(String),
    #[error("candle: {0}")]
    Candle(#[from] candle_core::Error),
    /// `[run] device` asks for a GPU and this build has no CUDA.
    #[error(transparent)]
    NoCuda(#[from] gait_core::NoCudaSupport),
    /// ONNX Runtime failed (or is not available: `ORT_DYLIB_PATH` unset).
    #[error("onnx runtime: {0}")]
    Ort(String),
}

impl DiffuseError {
    pub(crate) fn bad_model(path: impl Into<PathBuf>, reason: impl ToString) -> Self {
        Self::BadModel {
            path: path.into(),
            reason: reason.to_string(),
        }
    }
}

impl From<DiffuseError> for StageError {
    fn from(e: DiffuseError) -> Self {
        match e {
            DiffuseError::Missing { files, hint } => StageError::MissingModel {
                path: files.first().cloned().unwrap_or_default(),
                hint: format!(
                    "{hint} (all missing: {})",
                    files
                        .iter()
                        .map(|p| p.display().to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            },
            DiffuseError::BadModel { path, reason } => StageError::BadModel { path, reason },
            DiffuseError::Config(m) => StageError::BadInput(m),
            DiffuseError::Candle(e) => StageError::backend("candle", e),
            DiffuseError::Ort(m) => StageError::backend("ort", m),
            DiffuseError::NoCuda(e) => StageError::NoCuda(e),
        }
    }
}
