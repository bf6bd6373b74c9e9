//! Joint-angle tables and their errors in degrees.
//!
//! Angles are never computed here: they come from gait-kin (see
//! [`crate::kin_angles`], the one place that calls it) or from an
//! `angles.csv` that `gait kin` / `gait run` wrote.

use std::collections::HashMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::EvalError;
use crate::names::Side;
use crate::options::{EvalOptions, Role};
use crate::stats::Stat;

/// Angle columns, in the order of `angles.csv`.
pub const ANGLE_COLUMNS: [&str; 6] = [
    "left_hip",
    "right_hip",
    "left_knee",
    "right_knee",
    "left_ankle",
    "right_ankle",
];

/// Sagittal joint angles in degrees per frame (NaN where undefined).
#[derive(Debug, Clone, PartialEq)]
pub struct AngleTable {
    pub frames: Vec<usize>,
    /// `values[f][c]`: column [`ANGLE_COLUMNS`]`[c]` in frame `frames[f]`.
    pub values: Vec<[f64; 6]>,
}

impl AngleTable {
    /// The series of one column, e.g. "left_knee".
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let c = ANGLE_COLUMNS.iter().position(|n| *n == name)?;
        Some(self.values.iter().map(|v| v[c]).collect())
    }
}

/// Reads an `angles.csv` (`frame,time_s,left_hip,...,right_ankle`, empty cells undefined).
pub fn read_angles_csv(path: &Path) -> Result<AngleTable, EvalError> {
    let mut r = csv::Reader::from_path(path).map_err(|e| EvalError::input(path, e))?;
    let header: Vec<String> = r
        .headers()
        .map_err(|e| EvalError::input(path, e))?
        .iter()
        .map(str::to_string)
        .collect();
    let find = |name: &str| {
        header.iter().position(|h| h == name).ok_or_else(|| {
            EvalError::input(
                path,
                format!(
                    "no `{name}` column; expected frame,time_s,{}",
                    ANGLE_COLUMNS.join(",")
                ),
            )
        })
    };
    let frame_col = find("frame")?;
    let cols: Vec<usize> = ANGLE_COLUMNS
        .iter()
        .map(|n| find(n))
        .collect::<Result<_, _>>()?;
    let mut table = AngleTable {
        frames: Vec::new(),
        values: Vec::new(),
    };
    for (i, rec) in r.records().enumerate() {
        let rec = rec.map_err(|e| EvalError::input(path, e))?;
        let line = i + 2;
        let cell = |c: usize| -> Result<f64, EvalError> {
            let s = rec.get(c).unwrap_or("").trim();
            if s.is_empty() || s.eq_ignore_ascii_case("nan") {
                return Ok(f64::NAN);
            }
            s.parse()
                .map_err(|_| EvalError::input(path, format!("line {line}: `{s}` is not a number")))
        };
        let frame = rec
            .get(frame_col)
            .and_then(|s| s.trim().parse().ok())
            .ok_or_else(|| {
                EvalError::input(
                    path,
                    format!("line {line}: the frame is not a whole number"),
                )
            })?;
        let mut v = [f64::NAN; 6];
        for (slot, &c) in v.iter_mut().zip(&cols) {
            *slot = cell(c)?;
        }
        table.frames.push(frame);
        table.values.push(v);
    }
    Ok(table)
}

/// Absolute angle error of one joint on one side.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JointError {
    /// Column name, e.g. "right_knee".
    pub joint: String,
    pub side: Side,
    pub role: Role,
    pub deg: Stat,
}

/// Kinematics errors: per joint and pooled per leg (hip, knee and ankle).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KinematicsErrors {
    pub joints: Vec<JointError>,
    pub legs: Vec<crate::keypoint_error::LegError>,
}

/// Absolute differences of `pred` and `truth` angles on their common frames
/// where both are defined.
pub fn angle_errors(
    truth: &AngleTable,
    pred: &AngleTable,
    opts: &EvalOptions,
) -> Result<KinematicsErrors, EvalError> {
    let rows: HashMap<usize, usize> = pred
        .frames
        .iter()
        .enumerate()
        .map(|(i, &f)| (f, i))
        .collect();
    let pairs: Vec<(usize, usize)> = truth
        .frames
        .iter()
        .enumerate()
        .filter_map(|(i, f)| Some((i, *rows.get(f)?)))
        .collect();
    if pairs.is_empty() {
        return Err(EvalError::Mismatch(
            "the angle tables of ground truth and prediction share no frame".into(),
        ));
    }
    let diffs = |c: usize| -> Vec<f64> {
        pairs
            .iter()
            .map(|&(t, p)| (pred.values[p][c] - truth.values[t][c]).abs())
            .filter(|d| d.is_finite())
            .collect()
    };
    let side_of = |c: usize| {
        if ANGLE_COLUMNS[c].starts_with("left") {
            Side::Left
        } else {
            Side::Right
        }
    };
    let joints = (0..6)
        .map(|c| JointError {
            joint: ANGLE_COLUMNS[c].to_string(),
            side: side_of(c),
            role: opts.role(side_of(c)),
            deg: Stat::of(&diffs(c)),
        })
        .collect();
    let legs = Side::BOTH
        .iter()
        .map(|&side| {
            let pooled: Vec<f64> = (0..6)
                .filter(|&c| side_of(c) == side)
                .flat_map(diffs)
                .collect();
            crate::keypoint_error::LegError {
                side,
                role: opts.role(side),
                stat: Stat::of(&pooled),
            }
        })
        .collect();
    Ok(KinematicsErrors { joints, legs })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_angles_csv_and_compares() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("angles.csv");
        std::fs::write(&p, "frame,time_s,left_hip,right_hip,left_knee,right_knee,left_ankle,right_ankle\n0,0,1,2,3,4,5,6\n1,0.033,,2,3,4,5,6\n").unwrap();
        let t = read_angles_csv(&p).unwrap();
        assert!(t.values[1][0].is_nan());
        let mut pred = t.clone();
        pred.values[0][3] = 10.0;
        pred.values[1][3] = 1.0;
        let e = angle_errors(&t, &pred, &EvalOptions::default()).unwrap();
        let rk = &e.joints[3];
        assert_eq!(
            (rk.joint.as_str(), rk.role, rk.deg.n, rk.deg.mean),
            ("right_knee", Role::Prosthetic, 2, Some(4.5))
        );
        assert_eq!(e.joints[0].deg.n, 1);
        assert_eq!(e.legs[1].stat.n, 6);
        std::fs::write(&p, "frame,left_hip\n0,1\n").unwrap();
        assert!(
            read_angles_csv(&p)
                .unwrap_err()
                .to_string()
                .contains("right_hip")
        );
    }
}
