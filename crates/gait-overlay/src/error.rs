//! The one error type of the crate; every message fits on one line.

use std::path::PathBuf;

/// What can go wrong while planning or encoding an overlay.
#[derive(Debug, thiserror::Error)]
pub enum OverlayError {
    /// The `ffmpeg` program cannot be started.
    #[error(
        "cannot run ffmpeg ({0}); install it (Debian: apt-get install ffmpeg) or put it on PATH"
    )]
    FfmpegMissing(String),
    /// ffmpeg ran but failed; the text is its last lines of stderr, joined.
    #[error("ffmpeg: {0}")]
    Ffmpeg(String),
    /// The caller gave something unusable (size, frame rate, frame of the wrong size...).
    #[error("bad input: {0}")]
    BadInput(String),
    /// A run output (CSV, run.json) cannot be read as expected.
    #[error("{}: {reason}", path.display())]
    RunFile { path: PathBuf, reason: String },
    #[error("{context}: {source}")]
    Io {
        context: String,
        #[source]
        source: std::io::Error,
    },
}

impl OverlayError {
    pub(crate) fn run_file(path: impl Into<PathBuf>, reason: impl ToString) -> Self {
        Self::RunFile {
            path: path.into(),
            reason: reason.to_string(),
        }
    }

    pub(crate) fn io(context: impl Into<String>) -> impl FnOnce(std::io::Error) -> Self {
        let context = context.into();
        move |source| Self::Io { context, source }
    }
}
