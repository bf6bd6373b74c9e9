use std::fmt;

/// A failed command, as the one line the user sees (exit code 2).
#[derive(Debug)]
pub struct CliError(pub String);

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl From<gait_pipeline::PipelineError> for CliError {
    fn from(e: gait_pipeline::PipelineError) -> Self {
        Self(one_line(&e.to_string()))
    }
}

impl From<gait_core::StageError> for CliError {
    fn from(e: gait_core::StageError) -> Self {
        Self(one_line(&e.to_string()))
    }
}

/// Messages from libraries can span lines (e.g. TOML errors); the CLI
/// promises one line, of readable length (shared with the Python package).
pub use gait_pipeline::one_line;
