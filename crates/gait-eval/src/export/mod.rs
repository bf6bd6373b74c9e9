//! Exports for other tools: OpenSim marker (`.trc`) and motion (`.mot`)
//! files. OpenPose JSON is written by [`crate::openpose::write_dir`].

mod mot;
mod trc;

pub use mot::{MOT_COLUMNS, write_mot};
pub use trc::{TrcOptions, write_trc};
