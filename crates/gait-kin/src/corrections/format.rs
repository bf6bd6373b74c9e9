//! Reading, writing and checking `corrections.toml`.

use std::fmt::Write as _;
use std::path::Path;

use gait_core::PoseSequence;
use sha2::{Digest, Sha256};

use super::{Corrections, EventAction, EventEdit, FrameRange, KeypointEdit};
use crate::KinError;

/// The file name [`Corrections::validate`] names in its messages.
const DEFAULT_NAME: &str = "corrections.toml";

impl Corrections {
    /// Reads and parses a corrections file. Unknown tables or keys and wrong types are refused
    /// with one line naming the file and the line. Nothing is checked against keypoints here:
    /// see [`Corrections::validate`].
    pub fn read(path: &Path) -> Result<Corrections, KinError> {
        let bytes = read_bytes(path)?;
        parse(&bytes, path)
    }

    /// The corrections as TOML, which [`Corrections::read`] reads back to the same value
    /// (empty tables are left out).
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("corrections are plain tables of numbers and strings")
    }

    /// Checks the corrections against the keypoints they are for: every frame inside the
    /// input's frames (its first..=last frame), `last >= first`, swaps not overlapping, keypoint
    /// names the input has, finite coordinates, no entry repeated, no event added in an
    /// excluded range. The message names `corrections.toml` and the entry, on one line.
    pub fn validate(&self, seq: &PoseSequence) -> Result<(), KinError> {
        self.validate_file(seq, Path::new(DEFAULT_NAME))
    }

    /// [`Corrections::validate`], with messages naming `path`.
    pub fn validate_file(&self, seq: &PoseSequence, path: &Path) -> Result<(), KinError> {
        check(self, seq).map_err(|m| error(path, m))
    }
}

pub(crate) fn error(path: &Path, message: String) -> KinError {
    KinError::Corrections {
        path: path.to_path_buf(),
        message,
    }
}

fn read_bytes(path: &Path) -> Result<Vec<u8>, KinError> {
    std::fs::read(path).map_err(|e| KinError::Io {
        context: format!("reading corrections {}", path.display()),
        source: e,
    })
}

/// Reads, parses and validates the file at `path` for `seq`; also returns the SHA-256 (hex)
/// of its bytes. Messages name `path`.
pub(crate) fn load(path: &Path, seq: &PoseSequence) -> Result<(Corrections, String), KinError> {
    let bytes = read_bytes(path)?;
    let c = parse(&bytes, path)?;
    check(&c, seq).map_err(|m| error(path, m))?;
    Ok((c, sha256_hex(&bytes)))
}

/// SHA-256 of `bytes`, lower-case hex (the checksum run.json records for a corrections file).
pub fn sha256_hex(bytes: &[u8]) -> String {
    let mut sha = String::with_capacity(64);
    for b in Sha256::digest(bytes) {
        write!(sha, "{b:02x}").expect("writing to a String");
    }
    sha
}

/// Parses TOML; serde's message is made one line, with the line it is about.
pub(crate) fn parse(bytes: &[u8], path: &Path) -> Result<Corrections, KinError> {
    let text = std::str::from_utf8(bytes).map_err(|e| error(path, format!("not UTF-8: {e}")))?;
    toml::from_str(text).map_err(|e| {
        let message = e.message().split_whitespace().collect::<Vec<_>>().join(" ");
        let line = e.span().map(|s| {
            1 + bytes[..s.start.min(bytes.len())]
                .iter()
                .filter(|&&b| b == b'\n')
                .count()
        });
        error(
            path,
            match line {
                Some(l) => format!("line {l}: {message}"),
                None => message,
            },
        )
    })
}

/// `[[swap]] #2 (frames 120-131)`: entries count from 1 in the file's order.
pub(crate) fn range_entry(table: &str, k: usize, r: &FrameRange) -> String {
    format!("[[{table}]] #{} (frames {}-{})", k + 1, r.first, r.last)
}

/// `[[event]] #1 (add left heel_strike at frame 152)`.
pub(crate) fn event_entry(k: usize, e: &EventEdit) -> String {
    let action = match e.action {
        EventAction::Add => "add",
        EventAction::Remove => "remove",
    };
    format!(
        "[[event]] #{} ({action} {} {} at frame {})",
        k + 1,
        e.side.name(),
        e.kind.name(),
        e.frame
    )
}

/// `[[keypoint]] #1 (right_ankle at frame 140)`.
fn keypoint_entry(k: usize, p: &KeypointEdit) -> String {
    format!("[[keypoint]] #{} ({} at frame {})", k + 1, p.name, p.frame)
}

/// The message of the first problem (see [`Corrections::validate`]), without the file name.
fn check(c: &Corrections, seq: &PoseSequence) -> Result<(), String> {
    let run = seq.frames.iter().min().zip(seq.frames.iter().max());
    let in_run = |what: &str, frame: usize| match run {
        Some((&lo, &hi)) if (lo..=hi).contains(&frame) => Ok(()),
        Some((lo, hi)) => Err(format!(
            "{what}: frame {frame} is outside the run (frames {lo}-{hi})"
        )),
        None => Err(format!(
            "{what}: frame {frame} is outside the run (the input has no frames)"
        )),
    };
    for (table, list) in [("swap", &c.swap), ("exclude", &c.exclude)] {
        for (k, r) in list.iter().enumerate() {
            let what = range_entry(table, k, r);
            if r.last < r.first {
                return Err(format!("{what}: last is before first"));
            }
            in_run(&what, r.first)?;
            in_run(&what, r.last)?;
        }
    }
    for (k, a) in c.swap.iter().enumerate() {
        if let Some((j, b)) = c.swap[..k]
            .iter()
            .enumerate()
            .find(|(_, b)| b.overlaps(a.first, a.last))
        {
            return Err(format!(
                "{} overlaps {}",
                range_entry("swap", k, a),
                range_entry("swap", j, b)
            ));
        }
    }
    for (k, e) in c.event.iter().enumerate() {
        let what = event_entry(k, e);
        in_run(&what, e.frame)?;
        if let Some(j) = c.event[..k].iter().position(|o| o == e) {
            return Err(format!("{what} repeats {}", event_entry(j, &c.event[j])));
        }
        if e.action == EventAction::Add
            && let Some((j, x)) = c
                .exclude
                .iter()
                .enumerate()
                .find(|(_, x)| x.contains(e.frame))
        {
            return Err(format!(
                "{what} lies in {}: excluded frames have no events",
                range_entry("exclude", j, x)
            ));
        }
    }
    for (k, p) in c.keypoint.iter().enumerate() {
        let what = keypoint_entry(k, p);
        in_run(&what, p.frame)?;
        if !seq.names.contains(&p.name) {
            return Err(format!(
                "{what}: the input has no keypoint `{}` (it has {})",
                p.name,
                seq.names.join(", ")
            ));
        }
        for (axis, v) in [("x", p.x), ("y", p.y)] {
            if !v.is_finite() {
                return Err(format!("{what}: {axis} = {v} is not a finite number"));
            }
        }
        if let Some(j) = c.keypoint[..k]
            .iter()
            .position(|o| o.frame == p.frame && o.name == p.name)
        {
            return Err(format!(
                "{what} sets the same keypoint as {}",
                keypoint_entry(j, &c.keypoint[j])
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Side;
    use crate::events::EventKind;
    use crate::testing;

    /// The format as documented in the module docs.
    const EXAMPLE: &str = r#"
[[swap]]          # exchange the left and right leg labels, frames inclusive
first = 120
last = 131

[[event]]
side = "left"     # "left" | "right"
kind = "heel_strike"   # "heel_strike" | "toe_off"
frame = 152
action = "add"    # "add" | "remove"

[[exclude]]       # frames left out of events and cycles
first = 186
last = 229

[[keypoint]]      # set one keypoint in one frame (likelihood 1)
frame = 140
name = "right_ankle"
x = 812.5
y = 901.0
"#;

    fn parse_str(text: &str) -> Result<Corrections, String> {
        parse(text.as_bytes(), Path::new("c.toml")).map_err(|e| e.to_string())
    }

    /// A 300-frame walker numbered from input frame 0, keypoints as in `testing`.
    fn seq() -> PoseSequence {
        testing::walker(30.0, 300, |i| 100.0 + 13.0 * i as f64).to_sequence()
    }

    fn problem(text: &str) -> String {
        let c = parse_str(text).unwrap();
        c.validate(&seq()).unwrap_err().to_string()
    }

    #[test]
    fn parses_the_documented_format() {
        let c = parse_str(EXAMPLE).unwrap();
        assert_eq!(
            c,
            Corrections {
                swap: vec![FrameRange {
                    first: 120,
                    last: 131
                }],
                event: vec![EventEdit {
                    side: Side::Left,
                    kind: EventKind::HeelStrike,
                    frame: 152,
                    action: EventAction::Add
                }],
                exclude: vec![FrameRange {
                    first: 186,
                    last: 229
                }],
                keypoint: vec![KeypointEdit {
                    frame: 140,
                    name: "right_ankle".into(),
                    x: 812.5,
                    y: 901.0
                }],
            }
        );
        assert!(c.validate(&seq()).is_ok());
        // Every table is optional.
        assert_eq!(parse_str("").unwrap(), Corrections::default());
        let only = parse_str("[[exclude]]\nfirst = 1\nlast = 2\n").unwrap();
        assert!(only.swap.is_empty() && only.exclude.len() == 1);
    }

    #[test]
    fn round_trips_through_toml() {
        let mut c = parse_str(EXAMPLE).unwrap();
        c.event.push(EventEdit {
            side: Side::Right,
            kind: EventKind::ToeOff,
            frame: 160,
            action: EventAction::Remove,
        });
        c.swap.push(FrameRange {
            first: 200,
            last: 200,
        });
        let text = c.to_toml();
        assert!(
            text.contains("[[swap]]") && text.contains("action = \"remove\""),
            "{text}"
        );
        assert_eq!(parse_str(&text).unwrap(), c);
        assert_eq!(Corrections::default().to_toml(), "");

        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("corrections.toml");
        std::fs::write(&p, &text).unwrap();
        assert_eq!(Corrections::read(&p).unwrap(), c);
        let (back, sha) = load(&p, &seq()).unwrap();
        assert_eq!(back, c);
        assert_eq!(sha.len(), 64);
        // sha256 of "" is well known.
        std::fs::write(&p, "").unwrap();
        assert_eq!(
            load(&p, &seq()).unwrap().1,
            "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"
        );
        let e = Corrections::read(&dir.path().join("none.toml")).unwrap_err();
        assert!(e.to_string().contains("none.toml"), "{e}");
    }

    #[test]
    fn unknown_tables_keys_and_values_are_one_line_naming_the_file() {
        for (text, want) in [
            (
                "[[swaps]]\nfirst = 1\nlast = 2\n",
                "line 1: unknown field `swaps`",
            ),
            (
                "[[swap]]\nfirst = 1\nend = 2\n",
                "line 3: unknown field `end`",
            ),
            ("[[swap]]\nfirst = 1\n", "line 1: missing field `last`"),
            (
                "[[event]]\nside = \"middle\"\nkind = \"toe_off\"\nframe = 3\naction = \"add\"\n",
                "line 2: unknown variant `middle`",
            ),
            (
                "[[event]]\nside = \"left\"\nkind = \"toe_off\"\nframe = 3\naction = \"move\"\n",
                "line 5: unknown variant `move`",
            ),
            ("[[exclude]]\nfirst = -1\nlast = 2\n", "line 2:"),
        ] {
            let e = parse_str(text).unwrap_err();
            assert!(e.starts_with("c.toml: ") && e.contains(want), "{text}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
        let e = parse_str("[[swaps]]\nfirst = 1\nlast = 2\n").unwrap_err();
        assert!(e.contains("`swap`, `event`, `exclude`, `keypoint`"), "{e}");
    }

    #[test]
    fn each_problem_is_named_on_one_line() {
        for (text, want) in [
            (
                "[[swap]]\nfirst = 125\nlast = 140\n[[swap]]\nfirst = 120\nlast = 131\n",
                "corrections.toml: [[swap]] #2 (frames 120-131) overlaps [[swap]] #1 (frames 125-140)",
            ),
            (
                "[[swap]]\nfirst = 290\nlast = 300\n",
                "corrections.toml: [[swap]] #1 (frames 290-300): frame 300 is outside the run (frames 0-299)",
            ),
            (
                "[[exclude]]\nfirst = 229\nlast = 186\n",
                "corrections.toml: [[exclude]] #1 (frames 229-186): last is before first",
            ),
            (
                "[[event]]\nside = \"left\"\nkind = \"toe_off\"\nframe = 400\naction = \"remove\"\n",
                "corrections.toml: [[event]] #1 (remove left toe_off at frame 400): frame 400 is outside the run (frames 0-299)",
            ),
            (
                "[[keypoint]]\nframe = 10\nname = \"right_elbow\"\nx = 1.0\ny = 2.0\n",
                "corrections.toml: [[keypoint]] #1 (right_elbow at frame 10): the input has no keypoint `right_elbow` (it has mid_hip, left_hip,",
            ),
            (
                "[[keypoint]]\nframe = 10\nname = \"right_knee\"\nx = nan\ny = 2.0\n",
                "corrections.toml: [[keypoint]] #1 (right_knee at frame 10): x = NaN is not a finite number",
            ),
            (
                "[[keypoint]]\nframe = 10\nname = \"right_knee\"\nx = 1.0\ny = -inf\n",
                "corrections.toml: [[keypoint]] #1 (right_knee at frame 10): y = -inf is not a finite number",
            ),
            (
                "[[keypoint]]\nframe = 10\nname = \"right_knee\"\nx = 1.0\ny = 2.0\n\
                 [[keypoint]]\nframe = 10\nname = \"right_knee\"\nx = 3.0\ny = 2.0\n",
                "corrections.toml: [[keypoint]] #2 (right_knee at frame 10) sets the same keypoint as [[keypoint]] #1 (right_knee at frame 10)",
            ),
            (
                "[[event]]\nside = \"left\"\nkind = \"toe_off\"\nframe = 40\naction = \"add\"\n\
                 [[event]]\nside = \"left\"\nkind = \"toe_off\"\nframe = 40\naction = \"add\"\n",
                "corrections.toml: [[event]] #2 (add left toe_off at frame 40) repeats [[event]] #1 (add left toe_off at frame 40)",
            ),
            (
                "[[exclude]]\nfirst = 30\nlast = 50\n\
                 [[event]]\nside = \"right\"\nkind = \"heel_strike\"\nframe = 50\naction = \"add\"\n",
                "corrections.toml: [[event]] #1 (add right heel_strike at frame 50) lies in [[exclude]] #1 (frames 30-50): excluded frames have no events",
            ),
        ] {
            let e = problem(text);
            assert!(e.starts_with(want), "{text}\n{e}");
            assert!(!e.contains('\n'), "{e}");
        }
        // The run is the input's first..=last frame, not 0..
        let mut s = seq();
        s.frames.iter_mut().for_each(|f| *f += 1000);
        let c = parse_str("[[swap]]\nfirst = 10\nlast = 20\n").unwrap();
        let e = c.validate(&s).unwrap_err().to_string();
        assert!(
            e.ends_with("frame 10 is outside the run (frames 1000-1299)"),
            "{e}"
        );
        // Touching swaps do not overlap; removing an event in an excluded range is fine.
        let ok = "[[swap]]\nfirst = 10\nlast = 20\n[[swap]]\nfirst = 21\nlast = 30\n\
                  [[exclude]]\nfirst = 30\nlast = 50\n\
                  [[event]]\nside = \"right\"\nkind = \"heel_strike\"\nframe = 50\naction = \"remove\"\n";
        assert!(parse_str(ok).unwrap().validate(&seq()).is_ok());
    }
}
