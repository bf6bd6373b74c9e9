use std::path::PathBuf;

/// The error every stage returns; the CLI turns it into a one-line message.
#[derive(Debug, thiserror::Error)]
pub enum StageError {
    /// A model file is not where the configuration says.
    #[error("model file {path} not found; {hint}")]
    MissingModel { path: PathBuf, hint: String },
    /// A model file exists but cannot be used (truncated, foreign format, wrong tensor).
    #[error("model file {path}: {reason}")]
    BadModel { path: PathBuf, reason: String },
    /// The input given to the stage cannot be processed.
    #[error("bad input: {0}")]
    BadInput(String),
    /// The inference backend failed.
    #[error("{backend} backend: {reason}")]
    Backend { backend: String, reason: String },
    /// A GPU was asked for (`[run] device`) in a build without CUDA.
    #[error(transparent)]
    NoCuda(#[from] crate::NoCudaSupport),
    /// A stage written outside gait (in Python) failed or returned bad data.
    #[error("{stage}: {reason}")]
    External { stage: String, reason: String },
    #[error("{context}: {source}")]
    Io {
        context: String,
        #[source]
        source: std::io::Error,
    },
}

impl StageError {
    pub fn backend(backend: impl Into<String>, reason: impl ToString) -> Self {
        Self::Backend {
            backend: backend.into(),
            reason: reason.to_string(),
        }
    }

    pub fn bad_model(path: impl Into<PathBuf>, reason: impl ToString) -> Self {
        Self::BadModel {
            path: path.into(),
            reason: reason.to_string(),
        }
    }
}
