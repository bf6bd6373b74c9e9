//! Keypoints in DeepLabCut's CSV layout, the toolkit's interchange format.
//!
//! Single-animal files have three header rows (`scorer`, `bodyparts`,
//! `coords`); multi-animal files add an `individuals` row after `scorer`.
//! The first column is the frame index (or, in labelled-data files, an image
//! path, in which case rows are numbered in order). Empty or `NaN` cells mean
//! "not found".

use std::io::{Read, Write};

use crate::{Keypoint, Pose, PoseSequence};

#[derive(Debug, thiserror::Error)]
pub enum DlcError {
    #[error("not a DeepLabCut CSV: {0}")]
    Layout(String),
    #[error("row {row}: {reason}")]
    Row { row: usize, reason: String },
    #[error(transparent)]
    Csv(#[from] csv::Error),
}

/// Writes `seq` with the given scorer name (e.g. the pose model).
pub fn write<W: Write>(out: W, scorer: &str, seq: &PoseSequence) -> Result<(), DlcError> {
    let mut w = csv::WriterBuilder::new().flexible(false).from_writer(out);
    let n = seq.names.len();
    let header = |first: &str, cell: &dyn Fn(usize, usize) -> String| {
        let mut row = vec![first.to_string()];
        for i in 0..n {
            for c in 0..3 {
                row.push(cell(i, c));
            }
        }
        row
    };
    w.write_record(header("scorer", &|_, _| scorer.to_string()))?;
    w.write_record(header("bodyparts", &|i, _| seq.names[i].clone()))?;
    w.write_record(header("coords", &|_, c| {
        ["x", "y", "likelihood"][c].to_string()
    }))?;
    for (frame, pose) in seq.frames.iter().zip(&seq.poses) {
        let mut row = Vec::with_capacity(1 + 3 * n);
        row.push(frame.to_string());
        for k in &pose.keypoints {
            if k.is_found() {
                row.push(format!("{}", k.x));
                row.push(format!("{}", k.y));
                row.push(format!("{}", k.likelihood));
            } else {
                row.extend([String::new(), String::new(), String::new()]);
            }
        }
        w.write_record(&row)?;
    }
    w.flush().map_err(|e| DlcError::Csv(e.into()))?;
    Ok(())
}

/// Reads a DeepLabCut CSV. For multi-animal files, `individual` picks one
/// (the first when `None`). `fps` is not stored in the file.
pub fn read<R: Read>(
    input: R,
    individual: Option<&str>,
    fps: f64,
) -> Result<PoseSequence, DlcError> {
    let mut r = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(input);
    let mut records = r.records();
    let mut next_header = |want: &str| -> Result<Vec<String>, DlcError> {
        let rec = records
            .next()
            .ok_or_else(|| DlcError::Layout(format!("missing the `{want}` header row")))??;
        Ok(rec.iter().map(str::to_string).collect())
    };
    let scorer = next_header("scorer")?;
    if scorer.first().map(String::as_str) != Some("scorer") {
        return Err(DlcError::Layout(
            "the first row must start with `scorer`".into(),
        ));
    }
    let mut row = next_header("bodyparts")?;
    let individuals = if row.first().map(String::as_str) == Some("individuals") {
        let ind = row;
        row = next_header("bodyparts")?;
        Some(ind)
    } else {
        None
    };
    let bodyparts = row;
    let coords = next_header("coords")?;
    if bodyparts.first().map(String::as_str) != Some("bodyparts")
        || coords.first().map(String::as_str) != Some("coords")
    {
        return Err(DlcError::Layout(
            "expected header rows `bodyparts` and `coords`".into(),
        ));
    }
    let chosen = match (&individuals, individual) {
        (Some(ind), Some(name)) => {
            if !ind.iter().skip(1).any(|i| i == name) {
                return Err(DlcError::Layout(format!(
                    "no individual `{name}` in the file"
                )));
            }
            Some(name.to_string())
        }
        (Some(ind), None) => ind.get(1).cloned(),
        (None, _) => None,
    };
    // Column triples (x, y, likelihood) per body part, in file order.
    let mut names: Vec<String> = Vec::new();
    let mut columns: Vec<[Option<usize>; 3]> = Vec::new();
    for (col, part) in bodyparts.iter().enumerate().skip(1) {
        if let (Some(ind), Some(want)) = (&individuals, &chosen)
            && ind.get(col) != Some(want)
        {
            continue;
        }
        let slot = match coords.get(col).map(String::as_str) {
            Some("x") => 0,
            Some("y") => 1,
            Some("likelihood") => 2,
            other => {
                return Err(DlcError::Layout(format!(
                    "column {col}: coord `{}` is not x, y or likelihood",
                    other.unwrap_or("")
                )));
            }
        };
        let idx = match names.iter().position(|n| n == part) {
            Some(i) => i,
            None => {
                names.push(part.clone());
                columns.push([None; 3]);
                names.len() - 1
            }
        };
        columns[idx][slot] = Some(col);
    }
    if let Some(i) = columns
        .iter()
        .position(|c| c[0].is_none() || c[1].is_none())
    {
        return Err(DlcError::Layout(format!(
            "body part `{}` lacks an x or y column",
            names[i]
        )));
    }
    let mut frames = Vec::new();
    let mut poses = Vec::new();
    for (row_no, rec) in records.enumerate() {
        let rec = rec?;
        let line = row_no + 4 + usize::from(individuals.is_some());
        let cell = |c: Option<usize>| -> Result<f64, DlcError> {
            let Some(c) = c else { return Ok(f64::NAN) };
            let s = rec.get(c).unwrap_or("").trim();
            if s.is_empty() || s.eq_ignore_ascii_case("nan") {
                return Ok(f64::NAN);
            }
            s.parse().map_err(|_| DlcError::Row {
                row: line,
                reason: format!("`{s}` in column {c} is not a number"),
            })
        };
        let frame = rec
            .get(0)
            .and_then(|s| s.trim().parse::<usize>().ok())
            .unwrap_or(row_no);
        let mut keypoints = Vec::with_capacity(names.len());
        for c in &columns {
            let (x, y) = (cell(c[0])?, cell(c[1])?);
            // Files without a likelihood column (e.g. manual labels) are certain.
            let l = if c[2].is_some() { cell(c[2])? } else { 1.0 };
            keypoints.push(if x.is_finite() && y.is_finite() {
                Keypoint::new(x, y, if l.is_finite() { l } else { 0.0 })
            } else {
                Keypoint::missing()
            });
        }
        frames.push(frame);
        poses.push(Pose { keypoints });
    }
    Ok(PoseSequence {
        fps,
        names,
        frames,
        poses,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seq() -> PoseSequence {
        PoseSequence {
            fps: 30.0,
            names: vec!["left_knee".into(), "right_knee".into()],
            frames: vec![0, 1],
            poses: vec![
                Pose {
                    keypoints: vec![Keypoint::new(1.5, 2.25, 0.9), Keypoint::missing()],
                },
                Pose {
                    keypoints: vec![Keypoint::new(3.0, 4.0, 1.0), Keypoint::new(5.0, 6.0, 0.5)],
                },
            ],
        }
    }

    #[test]
    fn round_trip() {
        let mut buf = Vec::new();
        write(&mut buf, "gait", &seq()).unwrap();
        let text = String::from_utf8(buf.clone()).unwrap();
        assert!(text.starts_with("scorer,gait,gait,gait,gait,gait,gait\nbodyparts,left_knee,"));
        assert!(text.contains("\ncoords,x,y,likelihood,x,y,likelihood\n"));
        assert!(text.contains("\n0,1.5,2.25,0.9,,,\n"));
        let back = read(buf.as_slice(), None, 30.0).unwrap();
        assert_eq!(back.names, seq().names);
        assert_eq!(back.poses[1], seq().poses[1]);
        assert!(!back.poses[0].keypoints[1].is_found());
    }

    #[test]
    fn reads_multi_animal_files() {
        let text = "scorer,s,s,s,s,s,s\nindividuals,a,a,a,b,b,b\nbodyparts,knee,knee,knee,knee,knee,knee\ncoords,x,y,likelihood,x,y,likelihood\n0,1,2,0.5,10,20,0.7\n";
        let a = read(text.as_bytes(), None, 30.0).unwrap();
        assert_eq!(a.poses[0].keypoints[0], Keypoint::new(1.0, 2.0, 0.5));
        let b = read(text.as_bytes(), Some("b"), 30.0).unwrap();
        assert_eq!(b.poses[0].keypoints[0], Keypoint::new(10.0, 20.0, 0.7));
        assert!(read(text.as_bytes(), Some("c"), 30.0).is_err());
    }

    #[test]
    fn labelled_data_paths_are_numbered() {
        let text = "scorer,s,s\nbodyparts,knee,knee\ncoords,x,y\nlabeled-data/v/img001.png,1,2\nlabeled-data/v/img002.png,NaN,NaN\n";
        let s = read(text.as_bytes(), None, 30.0).unwrap();
        assert_eq!(s.frames, vec![0, 1]);
        assert_eq!(s.poses[0].keypoints[0].likelihood, 1.0);
        assert!(!s.poses[1].keypoints[0].is_found());
    }

    #[test]
    fn rejects_other_files() {
        assert!(read("a,b\n1,2\n".as_bytes(), None, 30.0).is_err());
        let bad = "scorer,s,s,s\nbodyparts,k,k,k\ncoords,x,y,likelihood\n0,1,oops,1\n";
        let e = read(bad.as_bytes(), None, 30.0).unwrap_err().to_string();
        assert!(e.contains("row 4") && e.contains("oops"), "{e}");
    }
}
