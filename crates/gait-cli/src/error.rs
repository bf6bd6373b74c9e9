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

/// The longest error line: a parser may quote the offending input, which a hostile file makes
/// arbitrarily long (a TOML line of 200,000 brackets). Long enough for the longest real
/// message (`gait models fetch` listing every file to download by hand).
const MAX_LINE: usize = 8192;

/// Messages from libraries can span lines (e.g. TOML errors); the CLI
/// promises one line, of readable length.
pub fn one_line(s: &str) -> String {
    let line = s.split_whitespace().collect::<Vec<_>>().join(" ");
    if line.len() <= MAX_LINE {
        return line;
    }
    let cut = (0..=MAX_LINE)
        .rev()
        .find(|&i| line.is_char_boundary(i))
        .unwrap_or(0);
    format!("{} … (message cut at {MAX_LINE} characters)", &line[..cut])
}
