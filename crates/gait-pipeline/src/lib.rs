//! Everything between the command line and the stages: the TOML pipeline
//! configuration, the stage registry, input decoding, the per-frame cache and
//! the runner that drives frames through the stages.

pub mod atomic;
mod cache;
pub mod config;
mod driver;
pub mod edges;
mod error;
pub mod input;
pub mod interpolate;
pub mod manifest;
pub mod outputs;
mod overlay;
mod passes;
mod plan;
mod redraw;
pub mod registry;
pub mod runner;
pub mod selection;
mod subject;
mod video_decoder;

pub use config::PipelineConfig;
pub use error::PipelineError;
pub use outputs::{OutputOptions, Outputs, write_outputs};
pub use overlay::regenerated_dir;
pub use runner::{RunOptions, RunSummary, regenerate_part, run};
pub use selection::{SelectionConfig, SelectionRecord};
