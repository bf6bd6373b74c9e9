use std::fmt;

/// Exit code of bad input: the user has something to fix (the default).
pub const BAD_INPUT: u8 = 2;
/// Exit code of a failure of the machine, not of the input (a full disk).
pub const ENVIRONMENT: u8 = 1;

/// A failed command, as the one line the user sees, and its exit code.
#[derive(Debug)]
pub struct CliError {
    pub message: String,
    pub code: u8,
}

impl CliError {
    /// A failure the user fixes in the input or the command line (exit code 2).
    pub fn new(message: impl Into<String>) -> Self {
        Self {
            message: message.into(),
            code: BAD_INPUT,
        }
    }
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl From<gait_pipeline::PipelineError> for CliError {
    fn from(e: gait_pipeline::PipelineError) -> Self {
        if e.out_of_space() {
            return Self {
                message: one_line(&format!(
                    "{e}; free space on that disk and rerun: the cache keeps the frames done"
                )),
                code: ENVIRONMENT,
            };
        }
        Self::new(one_line(&e.to_string()))
    }
}

impl From<gait_core::StageError> for CliError {
    fn from(e: gait_core::StageError) -> Self {
        Self::new(one_line(&e.to_string()))
    }
}

/// Messages from libraries can span lines (e.g. TOML errors); the CLI
/// promises one line, of readable length (shared with the Python package).
pub use gait_pipeline::one_line;
