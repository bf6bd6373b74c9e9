//! The one-line form of an error message, as the `gait` command prints it
//! and the Python package raises it.

/// The longest error line: a parser may quote the offending input, which a hostile file makes
/// arbitrarily long (a TOML line of 200,000 brackets). Long enough for the longest real
/// message (`gait models fetch` listing every file to download by hand).
const MAX_LINE: usize = 8192;

/// Messages from libraries can span lines (e.g. TOML errors); users get
/// one line, of readable length.
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
