use std::path::PathBuf;

use gait_core::StageError;

/// Everything that can stop a pipeline run; each variant says what is wrong
/// and, where possible, what to do about it.
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    #[error("config {origin}: {message}")]
    Config { origin: String, message: String },
    #[error("input {path}: {message}")]
    Input { path: PathBuf, message: String },
    #[error(transparent)]
    Stage(#[from] StageError),
    #[error("{context}: {source}")]
    Io {
        context: String,
        #[source]
        source: std::io::Error,
    },
    #[error("cache {path}: {message}")]
    Cache { path: PathBuf, message: String },
    /// Another process writes into the folder now.
    #[error(
        "{path} is in use by {holder}; wait for it to end or stop it, or choose another folder"
    )]
    Busy { path: PathBuf, holder: String },
    /// The run was asked to stop (Ctrl-C in Python); the caches keep the frames done.
    #[error("interrupted during {step}; the cache keeps the frames done, so a rerun resumes")]
    Interrupted { step: String },
    /// The report, an export or the overlay video could not be written.
    #[error("writing {what}: {message}")]
    Output { what: String, message: String },
}

impl PipelineError {
    /// True when a disk (or quota) was full: the machine's fault, not the input's. Errors of
    /// ffmpeg and Chromium reach us only as their text, so that is read too.
    pub fn out_of_space(&self) -> bool {
        let full = |e: &std::io::Error| {
            matches!(
                e.kind(),
                std::io::ErrorKind::StorageFull | std::io::ErrorKind::QuotaExceeded
            )
        };
        let mut source: Option<&(dyn std::error::Error + 'static)> = Some(self);
        while let Some(e) = source {
            if e.downcast_ref::<std::io::Error>().is_some_and(full) {
                return true;
            }
            source = e.source();
        }
        let text = self.to_string();
        ["No space left on device", "Disk quota exceeded"]
            .iter()
            .any(|s| text.contains(s))
    }

    pub(crate) fn io(context: impl Into<String>, source: std::io::Error) -> Self {
        Self::Io {
            context: context.into(),
            source,
        }
    }

    pub(crate) fn config(origin: impl Into<String>, message: impl ToString) -> Self {
        Self::Config {
            origin: origin.into(),
            message: message.to_string(),
        }
    }

    pub(crate) fn input(path: impl Into<PathBuf>, message: impl ToString) -> Self {
        Self::Input {
            path: path.into(),
            message: message.to_string(),
        }
    }
}
