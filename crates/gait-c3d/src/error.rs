//! What can go wrong when building or writing a C3D file.

use std::path::PathBuf;

/// Why [`crate::to_bytes`] or [`crate::write`] refused the data or failed to write it.
#[derive(Debug, thiserror::Error)]
pub enum C3dError {
    #[error("no markers: a C3D file needs at least one marker")]
    NoMarkers,
    #[error("no frames: the markers have no samples")]
    NoFrames,
    #[error("marker {label:?} has {got} frames but marker {first:?} has {expected}")]
    FrameCountMismatch {
        label: String,
        got: usize,
        first: String,
        expected: usize,
    },
    #[error("frame rate {0} Hz is not a finite number > 0 that float32 can hold")]
    InvalidRate(f64),
    #[error("first frame {0} is invalid: C3D frame numbers start at 1")]
    InvalidFirstFrame(usize),
    #[error(
        "too many frames: frames {first}..={last} do not fit the C3D header's 16-bit frame numbers \
         (the last frame must be <= 65535); split the recording"
    )]
    TooManyFrames { first: usize, last: usize },
    #[error("too many markers: {0} (a C3D parameter array holds at most 255 labels)")]
    TooManyMarkers(usize),
    #[error("too many events: {0} (a C3D parameter array holds at most 255 events)")]
    TooManyEvents(usize),
    #[error("invalid marker label {label:?}: {reason}")]
    InvalidLabel { label: String, reason: &'static str },
    #[error("duplicate marker label {0:?}: labels must be unique")]
    DuplicateLabel(String),
    #[error("invalid units {units:?}: {reason}")]
    InvalidUnits { units: String, reason: &'static str },
    #[error("event {index}: time {time_s} s is not a finite number >= 0 that float32 can hold")]
    InvalidEventTime { index: usize, time_s: f64 },
    #[error(
        "marker {label:?}, frame index {frame}: coordinate {value} is beyond the float32 range"
    )]
    CoordinateOutOfRange {
        label: String,
        frame: usize,
        value: f64,
    },
    #[error("parameter {name}: dimension {len} exceeds the C3D limit of 255")]
    DimensionTooLarge { name: String, len: usize },
    #[error(
        "the parameter section needs {0} blocks of 512 bytes; at most 255 fit (the count is one byte)"
    )]
    ParametersTooLarge(usize),
    #[error("writing {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}
