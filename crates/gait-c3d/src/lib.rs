//! C3D export of 2-D keypoints and gait events.
//!
//! Each keypoint becomes a marker (x, y from the image, z = 0; units "mm" when a scale is known,
//! "px" otherwise), each gait event a Vicon-style event (context "Left"/"Right", label
//! "Foot Strike"/"Foot Off"). There are no analog channels. The file is Intel byte order with
//! float32 data: header block, parameter section (POINT, ANALOG, TRIAL, EVENT, MANUFACTURER),
//! then the frames. It is checked against ezc3d in `tests/ezc3d.rs`.

mod atomic;
mod error;
mod groups;
mod header;
mod parameters;
mod points;
mod validate;

use std::path::Path;

pub use error::C3dError;

/// Size of a C3D block; every section starts on a block boundary.
const BLOCK: usize = 512;

/// One keypoint track: its label and one sample per frame; `None` = missing (written as
/// residual -1, coordinates 0). Non-finite coordinates are treated as missing too.
#[derive(Debug, Clone, PartialEq)]
pub struct Marker {
    pub label: String,
    pub xy: Vec<Option<[f64; 2]>>,
}

/// Which side an event belongs to (EVENT:CONTEXTS).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Context {
    Left,
    Right,
}

/// What happened (EVENT:LABELS).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EventKind {
    /// Heel strike, initial contact.
    FootStrike,
    /// Toe off.
    FootOff,
}

/// A gait event. `time_s` counts from the start of the recording, i.e. C3D frame `f` (1-based)
/// is at `(f - 1) / rate_hz`, whatever `first_frame` the file starts at.
#[derive(Debug, Clone, PartialEq)]
pub struct Event {
    pub context: Context,
    pub kind: EventKind,
    pub time_s: f64,
}

/// Everything one C3D file holds.
#[derive(Debug, Clone, PartialEq)]
pub struct C3dData {
    /// Frames per second.
    pub rate_hz: f64,
    /// 1-based frame number of the first written frame, as C3D counts.
    pub first_frame: usize,
    /// POINT:UNITS, "mm" or "px".
    pub units: String,
    /// All markers have the same number of frames.
    pub markers: Vec<Marker>,
    pub events: Vec<Event>,
}

impl Context {
    /// The EVENT:CONTEXTS string: "Left" or "Right".
    pub fn label(self) -> &'static str {
        match self {
            Context::Left => "Left",
            Context::Right => "Right",
        }
    }
}

impl EventKind {
    /// The EVENT:LABELS string: "Foot Strike" or "Foot Off".
    pub fn label(self) -> &'static str {
        match self {
            EventKind::FootStrike => "Foot Strike",
            EventKind::FootOff => "Foot Off",
        }
    }
}

/// Encodes `data` as the bytes of a C3D file, after checking it fits the format.
pub fn to_bytes(data: &C3dData) -> Result<Vec<u8>, C3dError> {
    let checked = validate::check(data)?;
    // POINT:DATA_START depends on the parameter section's length, which does not depend on its
    // value (a fixed-size integer): encode once to measure, then again with the real value.
    let probe = parameters::encode_section(&groups::groups(data, &checked, 0)?)?;
    let data_start = header::PARAMETER_BLOCK as usize + probe.len() / BLOCK;
    let data_start =
        u16::try_from(data_start).map_err(|_| C3dError::ParametersTooLarge(data_start))?;
    let params = parameters::encode_section(&groups::groups(data, &checked, data_start)?)?;
    let frames = points::encode(&data.markers, checked.frames)?;
    let head = header::Header {
        points: data.markers.len() as u16,
        first_frame: checked.first_frame,
        last_frame: checked.last_frame,
        scale: groups::SCALE,
        data_start_block: data_start,
        rate_hz: checked.rate_hz,
    };
    let mut out = Vec::with_capacity(BLOCK + params.len() + frames.len());
    out.extend_from_slice(&head.encode());
    out.extend_from_slice(&params);
    out.extend_from_slice(&frames);
    Ok(out)
}

/// Writes `data` to `path` as a C3D file, atomically (temporary file in the same folder, then
/// rename): an existing file is replaced only once the new one is complete.
pub fn write(path: &Path, data: &C3dData) -> Result<(), C3dError> {
    atomic::write(path, &to_bytes(data)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data() -> C3dData {
        C3dData {
            rate_hz: 30.0,
            first_frame: 5,
            units: "px".into(),
            markers: vec![
                Marker {
                    label: "LHeel".into(),
                    xy: vec![Some([1.0, 2.0]), None, Some([3.0, 4.0])],
                },
                Marker {
                    label: "RHeel".into(),
                    xy: vec![None, Some([5.0, 6.0]), None],
                },
            ],
            events: vec![Event {
                context: Context::Left,
                kind: EventKind::FootStrike,
                time_s: 0.2,
            }],
        }
    }

    #[test]
    fn sections_line_up() {
        let b = to_bytes(&data()).unwrap();
        assert_eq!(b.len() % BLOCK, 0);
        // Parameter section at block 2, its block count, Intel.
        assert_eq!(&b[512..514], &[1, 0x50]);
        assert_eq!(b[515], 84);
        let param_blocks = usize::from(b[514]);
        let data_start = u16::from_le_bytes([b[16], b[17]]) as usize;
        assert_eq!(data_start, 2 + param_blocks);
        // 3 frames x 2 markers x 16 bytes fit in one block.
        assert_eq!(b.len(), (data_start - 1) * BLOCK + BLOCK);
        let at = (data_start - 1) * BLOCK;
        let first = f32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]);
        assert_eq!(first, 1.0);
        // Header: 2 points, frames 5..=7.
        assert_eq!(&b[2..4], &[2, 0]);
        assert_eq!(&b[6..10], &[5, 0, 7, 0]);
    }

    #[test]
    fn errors_come_before_encoding() {
        let mut d = data();
        d.markers[1].label = "LHeel".into();
        assert!(matches!(to_bytes(&d), Err(C3dError::DuplicateLabel(_))));
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.c3d");
        assert!(write(&path, &d).is_err());
        assert!(!path.exists());
    }

    #[test]
    fn write_matches_to_bytes() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("keypoints.c3d");
        write(&path, &data()).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), to_bytes(&data()).unwrap());
    }

    #[test]
    fn labels() {
        assert_eq!(Context::Right.label(), "Right");
        assert_eq!(EventKind::FootOff.label(), "Foot Off");
    }
}
