//! Stages written in Python (`kind = "python"` in the `[edge]`, `[regenerator]`
//! or `[pose]` table): a class in an importable module, handed numpy views of
//! gait's frames without a copy, whose results are checked before use.
//!
//! The same code runs inside the `gait` command (which then embeds an
//! interpreter) and inside the `gait` Python package (where the interpreter
//! is the user's). The stage protocol is in docs/adding-a-stage.md.

mod boxes;
mod config;
mod error;
mod frames;
mod interpreter;
mod output;
mod stages;

pub use boxes::class_takes_boxes;
pub use config::PythonStageConfig;
pub use error::PythonStageError;
pub use stages::{load_edge_detector, load_pose_estimator, load_regenerator};
