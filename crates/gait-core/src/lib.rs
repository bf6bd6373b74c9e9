//! Shared types and stage traits of the `gait` toolkit.
//!
//! Data flows one way through the stages defined here:
//! [`Frame`]s -> the subject ([`PersonBox`] per frame) -> [`EdgeMap`]s -> regenerated [`Frame`]s -> [`Pose`]s -> [`PoseSequence`].
//! Stage crates implement [`EdgeDetector`], [`ImageRegenerator`] and [`PoseEstimator`];
//! they never depend on each other, only on this crate.

pub mod atomic;
mod backend;
#[cfg(feature = "candle")]
pub mod checkpoint;
mod context;
mod crop;
mod device;
pub mod dlc;
mod edge;
mod error;
mod frame;
pub mod geometry;
pub mod guard;
pub mod keypoint;
pub mod openpose_layout;
mod person;
pub mod pickle_guard;
mod pose;
pub mod pose_layout;
mod stage;
pub mod table;

pub use backend::Backend;
pub use context::StageContext;
pub use crop::{CropSpec, SubjectCrop};
pub use device::{Device, NoCudaSupport};
pub use edge::EdgeMap;
pub use error::StageError;
pub use frame::{Frame, ranges};
pub use geometry::Resize;
pub use keypoint::{CANONICAL, Keypoint};
pub use person::{PersonAt, PersonBox, PersonChoice, PersonRule};
pub use pose::{Pose, PoseSequence};
pub use stage::{EdgeDetector, ImageRegenerator, PoseEstimator};
