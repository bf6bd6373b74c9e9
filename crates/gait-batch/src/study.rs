//! The study file: one row per video, as CSV (header
//! `video,subject,session,view,prosthetic_side,config,set[,date]`) or TOML (`[[row]]` tables
//! with the same keys). Relative paths are relative to the study file.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::BatchError;

/// The CSV header, in this order.
pub const HEADER: [&str; 7] = [
    "video",
    "subject",
    "session",
    "view",
    "prosthetic_side",
    "config",
    "set",
];

/// Whether `s` is an ISO 8601 date (`YYYY-MM-DD`), optionally followed by `T` and a time.
pub fn is_iso_date(s: &str) -> bool {
    let (date, time) = s.split_once('T').map_or((s, None), |(d, t)| (d, Some(t)));
    let p: Vec<&str> = date.split('-').collect();
    let num = |x: &str, n: usize, lo: u32, hi: u32| {
        x.len() == n
            && x.bytes().all(|b| b.is_ascii_digit())
            && x.parse::<u32>().is_ok_and(|v| (lo..=hi).contains(&v))
    };
    p.len() == 3
        && num(p[0], 4, 1900, 2999)
        && num(p[1], 2, 1, 12)
        && num(p[2], 2, 1, 31)
        && time.is_none_or(|t| {
            t.len() >= 5
                && t.as_bytes()[2] == b':'
                && num(&t[..2], 2, 0, 23)
                && num(&t[3..5], 2, 0, 59)
        })
}

/// Camera views a row may name.
pub const VIEWS: [&str; 4] = ["left", "right", "anterior", "posterior"];

/// One row: a video and how to analyse it.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyRow {
    /// The video (relative to the study file).
    pub video: String,
    #[serde(default)]
    pub subject: String,
    #[serde(default)]
    pub session: String,
    /// left | right | anterior | posterior.
    #[serde(default)]
    pub view: String,
    /// left | right | empty (sets `kinematics.prosthetic_side`).
    #[serde(default)]
    pub prosthetic_side: String,
    /// A pipeline TOML (relative to the study file); empty: the built-in default.
    #[serde(default)]
    pub config: String,
    /// `table.key=value` overrides separated by `;`.
    #[serde(default)]
    pub set: String,
    /// The visit's date, ISO 8601 (`2026-12-04`); optional, a last CSV column: orders a
    /// subject's visits for `gait progress`.
    #[serde(default)]
    pub date: String,
}

/// A study file's rows, in file order.
#[derive(Debug, Clone)]
pub struct Study {
    pub path: PathBuf,
    pub rows: Vec<StudyRow>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TomlStudy {
    #[serde(default)]
    row: Vec<StudyRow>,
}

fn bad(path: &Path, message: impl Into<String>) -> BatchError {
    BatchError::Study {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

impl Study {
    /// Reads a `.csv` or `.toml` study file.
    pub fn read(path: &Path) -> Result<Study, BatchError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| bad(path, format!("cannot read the study file ({e})")))?;
        let rows = match path.extension().and_then(|e| e.to_str()) {
            Some("toml") => {
                let t: TomlStudy = toml::from_str(&text).map_err(|e| {
                    bad(
                        path,
                        e.message().split_whitespace().collect::<Vec<_>>().join(" "),
                    )
                })?;
                t.row
            }
            Some("csv") => read_csv(path, &text)?,
            _ => return Err(bad(path, "a study file is .csv or .toml")),
        };
        if rows.is_empty() {
            return Err(bad(path, "the study has no rows"));
        }
        Ok(Study {
            path: path.to_path_buf(),
            rows,
        })
    }

    /// `p` resolved against the study file's folder.
    pub fn resolve(&self, p: &str) -> PathBuf {
        let p = Path::new(p);
        if p.is_absolute() {
            return p.to_path_buf();
        }
        self.path.parent().unwrap_or(Path::new(".")).join(p)
    }
}

fn read_csv(path: &Path, text: &str) -> Result<Vec<StudyRow>, BatchError> {
    let mut r = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let header: Vec<String> = r
        .headers()
        .map_err(|e| bad(path, e.to_string()))?
        .iter()
        .map(str::to_string)
        .collect();
    // `date` may follow as an eighth column.
    let with_date = header.len() == HEADER.len() + 1
        && header[..HEADER.len()] == HEADER
        && header[HEADER.len()] == "date";
    if header != HEADER && !with_date {
        return Err(bad(
            path,
            format!(
                "the header is `{}`; expected `{}` (and optionally `,date`)",
                header.join(","),
                HEADER.join(",")
            ),
        ));
    }
    r.deserialize()
        .enumerate()
        .map(|(i, row)| row.map_err(|e| bad(path, format!("line {}: {e}", i + 2))))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn csv_and_toml_give_the_same_rows() {
        let dir = tempfile::tempdir().unwrap();
        let csv = write(
            dir.path(),
            "s.csv",
            "video,subject,session,view,prosthetic_side,config,set\n\
             a.mp4,S1,1,left,right,,pose.backend=\"ort\";input.last_frame=9\n",
        );
        let toml = write(
            dir.path(),
            "s.toml",
            "[[row]]\nvideo = \"a.mp4\"\nsubject = \"S1\"\nsession = \"1\"\nview = \"left\"\n\
             prosthetic_side = \"right\"\nset = 'pose.backend=\"ort\";input.last_frame=9'\n",
        );
        let a = Study::read(&csv).unwrap();
        let b = Study::read(&toml).unwrap();
        assert_eq!(a.rows, b.rows);
        assert_eq!(a.rows[0].set, "pose.backend=\"ort\";input.last_frame=9");
        assert_eq!(a.resolve("a.mp4"), dir.path().join("a.mp4"));
    }

    #[test]
    fn a_wrong_header_or_key_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let csv = write(dir.path(), "s.csv", "video,subject\na.mp4,S1\n");
        let e = Study::read(&csv).unwrap_err().to_string();
        assert!(e.contains("expected `video,subject,session"), "{e}");
        let toml = write(
            dir.path(),
            "s.toml",
            "[[row]]\nvideo = \"a.mp4\"\ncolour = 1\n",
        );
        let e = Study::read(&toml).unwrap_err().to_string();
        assert!(e.contains("colour"), "{e}");
        let empty = write(dir.path(), "e.csv", &(HEADER.join(",") + "\n"));
        assert!(
            Study::read(&empty)
                .unwrap_err()
                .to_string()
                .contains("no rows")
        );
    }
}
