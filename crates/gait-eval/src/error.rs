use std::path::PathBuf;

/// Everything that can go wrong while reading, evaluating, plotting or writing.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// A pose file or folder cannot be read or has the wrong layout.
    #[error("{path}: {reason}")]
    Input { path: PathBuf, reason: String },
    /// Ground truth and prediction cannot be put side by side.
    #[error("cannot align ground truth and prediction: {0}")]
    Mismatch(String),
    /// An option has a value that cannot be used.
    #[error("option `{key}`: {reason}")]
    Option { key: &'static str, reason: String },
    /// Joint angles could not be computed by gait-kin.
    #[error("joint angles: {0}")]
    Kinematics(String),
    #[error("plot {name}: {reason}")]
    Plot { name: String, reason: String },
    #[error("{context}: {source}")]
    Io {
        context: String,
        #[source]
        source: std::io::Error,
    },
}

impl EvalError {
    /// A file that could not be read as what it should be.
    pub fn input(path: impl Into<PathBuf>, reason: impl ToString) -> Self {
        Self::Input {
            path: path.into(),
            reason: reason.to_string(),
        }
    }

    /// An I/O failure, with what was being done.
    pub fn io(context: impl Into<String>, source: std::io::Error) -> Self {
        Self::Io {
            context: context.into(),
            source,
        }
    }

    pub(crate) fn plot(name: &str, reason: impl ToString) -> Self {
        Self::Plot {
            name: name.to_string(),
            reason: reason.to_string(),
        }
    }
}

impl From<EvalError> for gait_core::StageError {
    fn from(e: EvalError) -> Self {
        match e {
            EvalError::Io { context, source } => gait_core::StageError::Io { context, source },
            other => gait_core::StageError::BadInput(other.to_string()),
        }
    }
}
