use std::path::PathBuf;

/// Why a batch could not be planned, submitted or aggregated.
#[derive(Debug, thiserror::Error)]
pub enum BatchError {
    /// The study file cannot be read or has the wrong layout.
    #[error("{}: {message}", path.display())]
    Study { path: PathBuf, message: String },
    /// Rows that cannot run, every one listed; nothing was started.
    #[error("{}: {} bad row(s), nothing submitted: {}", path.display(), rows.len(), rows.join("; "))]
    BadRows { path: PathBuf, rows: Vec<String> },
    /// A batch folder without its plan (not written by `gait batch`).
    #[error("{}: not a batch folder ({message})", path.display())]
    NotABatch { path: PathBuf, message: String },
    /// Slurm refused or is missing.
    #[error("{0}")]
    Slurm(String),
    #[error("{context}: {source}")]
    Io {
        context: String,
        #[source]
        source: std::io::Error,
    },
}

impl BatchError {
    pub(crate) fn io(context: impl Into<String>, source: std::io::Error) -> Self {
        BatchError::Io {
            context: context.into(),
            source,
        }
    }
}
