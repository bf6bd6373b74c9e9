//! The data section: for each frame, for each marker, x, y, z and the residual word, all float32
//! (the file's negative POINT:SCALE says so), padded to whole blocks.

use crate::error::C3dError;
use crate::{BLOCK, Marker};

/// Residual word of a missing point: any negative value marks it invalid; -1 is the convention.
const MISSING: f32 = -1.0;
/// Residual word of a present point: camera mask 0, residual 0. Readers take any value >= 0 as
/// valid; we have no reconstruction residual to report for a 2-D keypoint.
const PRESENT: f32 = 0.0;

/// Encodes `frames` frames of `markers` (the validator checked that every marker has that many).
/// Non-finite coordinates count as missing; finite ones beyond the float32 range are an error.
pub(crate) fn encode(markers: &[Marker], frames: usize) -> Result<Vec<u8>, C3dError> {
    let mut out = Vec::with_capacity((frames * markers.len() * 16).div_ceil(BLOCK) * BLOCK);
    for frame in 0..frames {
        for m in markers {
            let sample =
                m.xy.get(frame)
                    .copied()
                    .flatten()
                    .filter(|p| p.iter().all(|v| v.is_finite()));
            let (x, y, residual) = match sample {
                Some([x, y]) => (float32(m, frame, x)?, float32(m, frame, y)?, PRESENT),
                // Coordinates 0 rather than NaN: older readers choke on NaN; the residual says
                // the point is missing.
                None => (0.0, 0.0, MISSING),
            };
            for v in [x, y, 0.0, residual] {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    out.resize(out.len().div_ceil(BLOCK) * BLOCK, 0);
    Ok(out)
}

fn float32(m: &Marker, frame: usize, v: f64) -> Result<f32, C3dError> {
    let f = v as f32;
    if f.is_finite() {
        Ok(f)
    } else {
        Err(C3dError::CoordinateOutOfRange {
            label: m.label.clone(),
            frame,
            value: v,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn floats(b: &[u8]) -> Vec<f32> {
        b.chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect()
    }

    #[test]
    fn frame_major_with_missing_points() {
        let a = Marker {
            label: "A".into(),
            xy: vec![Some([1.5, -2.25]), None],
        };
        let b = Marker {
            label: "B".into(),
            xy: vec![Some([f64::NAN, 1.0]), Some([1234.5678, 0.0])],
        };
        let out = encode(&[a, b], 2).unwrap();
        assert_eq!(out.len(), 512);
        let v = floats(&out[..64]);
        assert_eq!(
            v,
            vec![
                1.5,
                -2.25,
                0.0,
                0.0, // frame 0, A
                0.0,
                0.0,
                0.0,
                -1.0, // frame 0, B: NaN makes it missing
                0.0,
                0.0,
                0.0,
                -1.0, // frame 1, A
                1234.5678f64 as f32,
                0.0,
                0.0,
                0.0, // frame 1, B
            ]
        );
        assert!(out[64..].iter().all(|&b| b == 0));
    }

    #[test]
    fn out_of_range_coordinates_are_errors() {
        let a = Marker {
            label: "A".into(),
            xy: vec![None, Some([0.0, 1e300])],
        };
        let e = encode(&[a], 2).unwrap_err();
        assert!(
            matches!(e, C3dError::CoordinateOutOfRange { frame: 1, .. }),
            "{e}"
        );
    }

    #[test]
    fn whole_blocks() {
        let a = Marker {
            label: "A".into(),
            xy: vec![Some([0.0, 0.0]); 33],
        };
        assert_eq!(encode(&[a], 33).unwrap().len(), 1024); // 33 * 16 = 528 bytes
    }
}
