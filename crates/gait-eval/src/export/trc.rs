//! OpenSim marker file (`.trc`, tab-separated, "PathFileType 4").

use std::fmt::Write as _;
use std::path::Path;

use gait_core::PoseSequence;

use crate::EvalError;
use crate::fsutil::write_atomic;

/// How image coordinates become marker coordinates.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TrcOptions {
    /// Metres per pixel (e.g. from a subject height or a known length). With
    /// it the file is in metres; without it the units say `px`, which OpenSim
    /// does not scale, so the file is only useful for viewing.
    pub metres_per_pixel: Option<f64>,
}

/// Writes the keypoints of `seq` as markers: X = x, Y = -y (OpenSim's Y
/// points up, image y down), Z = 0, times `metres_per_pixel` when known.
/// Frames are numbered from 1 as OpenSim expects (input frame + 1); missing
/// keypoints are blank cells.
pub fn write_trc(seq: &PoseSequence, path: &Path, opts: &TrcOptions) -> Result<(), EvalError> {
    if !(seq.fps.is_finite() && seq.fps > 0.0) {
        return Err(EvalError::Option {
            key: "fps",
            reason: format!("{} is not a positive frame rate", seq.fps),
        });
    }
    if let Some(s) = opts.metres_per_pixel
        && !(s.is_finite() && s > 0.0)
    {
        return Err(EvalError::Option {
            key: "metres_per_pixel",
            reason: format!("{s} is not a positive scale"),
        });
    }
    let (scale, units) = match opts.metres_per_pixel {
        Some(s) => (s, "m"),
        None => (1.0, "px"),
    };
    let file_name = path
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or("markers.trc");
    let fps = seq.fps;
    let n = seq.len();
    let m = seq.names.len();
    let first = seq.frames.first().copied().unwrap_or(0) + 1;
    let mut out = String::new();
    // Writing into a String cannot fail.
    let _ = writeln!(out, "PathFileType\t4\t(X/Y/Z)\t{file_name}");
    out.push_str("DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames\n");
    let _ = writeln!(
        out,
        "{fps:.2}\t{fps:.2}\t{n}\t{m}\t{units}\t{fps:.2}\t{first}\t{n}"
    );
    out.push_str("Frame#\tTime");
    for name in &seq.names {
        let _ = write!(out, "\t{name}\t\t");
    }
    out.push_str("\n\t");
    for i in 1..=m {
        let _ = write!(out, "\tX{i}\tY{i}\tZ{i}");
    }
    out.push_str("\n\n");
    for (frame, pose) in seq.frames.iter().zip(&seq.poses) {
        let _ = write!(out, "{}\t{:.6}", frame + 1, *frame as f64 / fps);
        for k in &pose.keypoints {
            if k.is_found() {
                let _ = write!(out, "\t{:.6}\t{:.6}\t{:.6}", k.x * scale, -k.y * scale, 0.0);
            } else {
                out.push_str("\t\t\t");
            }
        }
        out.push('\n');
    }
    write_atomic(path, out.as_bytes())
}

#[cfg(test)]
mod tests {
    use gait_core::{Keypoint, Pose};

    use super::*;

    #[test]
    fn header_and_rows_in_the_opensim_layout() {
        let seq = PoseSequence {
            fps: 30.0,
            names: vec!["left_knee".into(), "right_knee".into()],
            frames: vec![4, 5],
            poses: vec![
                Pose {
                    keypoints: vec![Keypoint::new(100.0, 200.0, 1.0), Keypoint::missing()],
                },
                Pose {
                    keypoints: vec![
                        Keypoint::new(110.0, 210.0, 1.0),
                        Keypoint::new(1.0, 2.0, 1.0),
                    ],
                },
            ],
        };
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("walk.trc");
        write_trc(
            &seq,
            &p,
            &TrcOptions {
                metres_per_pixel: Some(0.003),
            },
        )
        .unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "PathFileType\t4\t(X/Y/Z)\twalk.trc");
        assert_eq!(lines[2], "30.00\t30.00\t2\t2\tm\t30.00\t5\t2");
        assert_eq!(lines[3], "Frame#\tTime\tleft_knee\t\t\tright_knee\t\t");
        assert_eq!(lines[4], "\t\tX1\tY1\tZ1\tX2\tY2\tZ2");
        assert_eq!(lines[5], "");
        assert_eq!(lines[6], "5\t0.133333\t0.300000\t-0.600000\t0.000000\t\t\t");
        assert_eq!(lines[7].split('\t').count(), 2 + 3 * 2);
        write_trc(&seq, &p, &TrcOptions::default()).unwrap();
        assert!(
            std::fs::read_to_string(&p)
                .unwrap()
                .lines()
                .nth(2)
                .unwrap()
                .contains("\tpx\t")
        );
        assert!(
            write_trc(
                &seq,
                &p,
                &TrcOptions {
                    metres_per_pixel: Some(-1.0)
                }
            )
            .is_err()
        );
    }
}
