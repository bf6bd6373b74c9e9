use std::path::PathBuf;

/// Why a review could not start.
#[derive(Debug, thiserror::Error)]
pub enum ReviewError {
    /// A file of the run is missing or unreadable; `what` says which and what to do.
    #[error("{}: {what}", path.display())]
    Run { path: PathBuf, what: String },
    /// The corrections already saved do not fit the keypoints.
    #[error(transparent)]
    Corrections(#[from] gait_kin::KinError),
    #[error(transparent)]
    Pipeline(#[from] gait_pipeline::PipelineError),
    #[error("{context}: {source}")]
    Io {
        context: String,
        #[source]
        source: std::io::Error,
    },
}

impl ReviewError {
    pub(crate) fn run(path: impl Into<PathBuf>, what: impl Into<String>) -> Self {
        ReviewError::Run {
            path: path.into(),
            what: what.into(),
        }
    }
}
