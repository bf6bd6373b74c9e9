//! Exports for other tools: c3d (`keypoints.c3d`), OpenSim marker (`.trc`)
//! and motion (`.mot`) files. OpenPose JSON is written by [`crate::openpose::write_dir`].

mod c3d;
mod mot;
mod run;
mod trc;

pub use mot::{MOT_COLUMNS, write_mot};
pub use run::{RunFacts, export_run};
pub use trc::{TrcOptions, write_trc};
