//! OpenSim motion file (`.mot`) of the sagittal joint angles.

use std::fmt::Write as _;
use std::path::Path;

use crate::EvalError;
use crate::angles::AngleTable;
use crate::fsutil::write_atomic;

/// Column names, with the table column each comes from. They follow the
/// coordinates of OpenSim's Rajagopal (2016) model, whose signs match ours
/// (hip and knee flexion, ankle dorsiflexion positive).
pub const MOT_COLUMNS: [(&str, &str); 6] = [
    ("hip_flexion_r", "right_hip"),
    ("knee_angle_r", "right_knee"),
    ("ankle_angle_r", "right_ankle"),
    ("hip_flexion_l", "left_hip"),
    ("knee_angle_l", "left_knee"),
    ("ankle_angle_l", "left_ankle"),
];

/// Writes the angles (degrees) with time = frame / `fps`; undefined angles are `NaN`.
pub fn write_mot(angles: &AngleTable, fps: f64, path: &Path) -> Result<(), EvalError> {
    if !(fps.is_finite() && fps > 0.0) {
        return Err(EvalError::Option {
            key: "fps",
            reason: format!("{fps} is not a positive frame rate"),
        });
    }
    let cols: Vec<usize> = MOT_COLUMNS
        .iter()
        .filter_map(|(_, src)| crate::angles::ANGLE_COLUMNS.iter().position(|c| c == src))
        .collect();
    let name = path
        .file_stem()
        .and_then(|n| n.to_str())
        .unwrap_or("angles");
    let mut out = String::new();
    // Writing into a String cannot fail.
    let _ = writeln!(out, "{name}");
    out.push_str("version=1\n");
    let _ = writeln!(out, "nRows={}", angles.frames.len());
    let _ = writeln!(out, "nColumns={}", MOT_COLUMNS.len() + 1);
    out.push_str("inDegrees=yes\nendheader\ntime");
    for (c, _) in MOT_COLUMNS {
        let _ = write!(out, "\t{c}");
    }
    out.push('\n');
    for (frame, v) in angles.frames.iter().zip(&angles.values) {
        let _ = write!(out, "{:.6}", *frame as f64 / fps);
        for &c in &cols {
            if v[c].is_finite() {
                let _ = write!(out, "\t{:.6}", v[c]);
            } else {
                out.push_str("\tNaN");
            }
        }
        out.push('\n');
    }
    write_atomic(path, out.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_and_rows() {
        let t = AngleTable {
            frames: vec![0, 3],
            values: vec![
                [1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
                [f64::NAN, 2.5, 3.0, 4.0, 5.0, 6.0],
            ],
        };
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("walk.mot");
        write_mot(&t, 30.0, &p).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            &lines[..6],
            &[
                "walk",
                "version=1",
                "nRows=2",
                "nColumns=7",
                "inDegrees=yes",
                "endheader"
            ]
        );
        assert_eq!(
            lines[6],
            "time\thip_flexion_r\tknee_angle_r\tankle_angle_r\thip_flexion_l\tknee_angle_l\tankle_angle_l"
        );
        assert_eq!(
            lines[7],
            "0.000000\t2.000000\t4.000000\t6.000000\t1.000000\t3.000000\t5.000000"
        );
        assert_eq!(
            lines[8],
            "0.100000\t2.500000\t4.000000\t6.000000\tNaN\t3.000000\t5.000000"
        );
        assert!(write_mot(&t, 0.0, &p).is_err());
    }
}
