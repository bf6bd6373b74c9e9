//! Regression inputs kept as edits of a seed file (`.patch`), so that a crash found in a
//! 3 MB model is a few lines in the repository rather than another copy of the model:
//!
//! ```text
//! # what it did, and the fix
//! seed target/models/blazepose/pose_detection.tflite
//! length 2959046
//! at 1234 0a0b0c
//! ```
//! The input is the seed cut or zero-padded to `length`, then each `at OFFSET HEX` written.

use std::path::Path;

/// The most changed bytes a patch may hold; an input further from its seed is kept whole.
const MAX_EDITED: usize = 4096;

/// The input a `.patch` file describes (the seed named from the repository root).
pub fn read(path: &Path) -> Result<Vec<u8>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let bad = |line: &str| format!("{}: cannot read line {line:?}", path.display());
    let mut out: Option<Vec<u8>> = None;
    for line in text.lines().map(str::trim) {
        let mut words = line.split_whitespace();
        match (words.next(), words.next(), words.next()) {
            (None, ..) | (Some("#"), ..) => {}
            (Some(w), ..) if w.starts_with('#') => {}
            (Some("seed"), Some(seed), None) => {
                let p = crate::repo().join(seed);
                out = Some(std::fs::read(&p).map_err(|e| format!("{}: {e}", p.display()))?);
            }
            (Some("length"), Some(n), None) => {
                let n: usize = n.parse().map_err(|_| bad(line))?;
                out.as_mut().ok_or_else(|| bad(line))?.resize(n, 0);
            }
            (Some("at"), Some(at), Some(hex)) => {
                let at: usize = at.parse().map_err(|_| bad(line))?;
                let bytes = unhex(hex).ok_or_else(|| bad(line))?;
                let data = out.as_mut().ok_or_else(|| bad(line))?;
                data.get_mut(at..at + bytes.len())
                    .ok_or_else(|| bad(line))?
                    .copy_from_slice(&bytes);
            }
            _ => return Err(bad(line)),
        }
    }
    out.ok_or_else(|| format!("{}: no seed line", path.display()))
}

/// The `.patch` text turning `seed` (named `seed_name` from the repository root) into `input`;
/// `None` when they differ in more than [`MAX_EDITED`] bytes.
pub fn write(seed_name: &str, seed: &[u8], input: &[u8]) -> Option<String> {
    let byte = |d: &[u8], i: usize| d.get(i).copied().unwrap_or(0);
    let changed: Vec<usize> = (0..input.len())
        .filter(|&i| byte(seed, i) != input[i] || i >= seed.len())
        .collect();
    if changed.len() > MAX_EDITED {
        return None;
    }
    let mut text = format!("seed {seed_name}\nlength {}\n", input.len());
    // Runs of consecutive changed bytes, one line each.
    let mut k = 0;
    while k < changed.len() {
        let start = changed[k];
        let mut end = start + 1;
        while k + 1 < changed.len() && changed[k + 1] == end {
            k += 1;
            end += 1;
        }
        let hex: String = input[start..end]
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        text.push_str(&format!("at {start} {hex}\n"));
        k += 1;
    }
    Some(text)
}

fn unhex(s: &str) -> Option<Vec<u8>> {
    if !s.len().is_multiple_of(2) {
        return None;
    }
    (0..s.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(s.get(i..i + 2)?, 16).ok())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_patch_gives_back_the_input() {
        let dir = tempfile::tempdir().unwrap();
        let seed_name = "crates/gait-fuzz/src/patch.rs";
        let seed = std::fs::read(crate::repo().join(seed_name)).unwrap();
        for input in [
            {
                let mut v = seed.clone();
                v[10] ^= 0xff;
                v[11] = 0;
                v[500] = 7;
                v
            },
            seed[..300].to_vec(),
            [seed.as_slice(), b"tail"].concat(),
        ] {
            let text = write(seed_name, &seed, &input).unwrap();
            let p = dir.path().join("x.patch");
            std::fs::write(&p, format!("# a comment\n{text}")).unwrap();
            assert_eq!(read(&p).unwrap(), input);
        }
        assert!(write(seed_name, &seed, &vec![1u8; 10_000]).is_none());
    }
}
