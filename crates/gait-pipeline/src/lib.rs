//! Everything between the command line and the stages: the TOML pipeline
//! configuration, the stage registry, input decoding, the per-frame cache and
//! the runner that drives frames through the stages.

pub use gait_core::atomic;
mod backend_choice;
mod beside;
mod cache;
pub mod config;
mod config_origin;
mod driver;
pub mod edges;
mod error;
pub mod folder_lock;
mod frame_reader;
mod frame_spool;
pub mod frame_timing;
pub mod input;
pub mod interpolate;
mod kin_manifest;
pub mod manifest;
mod message;
pub mod outputs;
mod overlay;
mod passes;
mod picture;
mod plan;
mod probe;
mod progress;
mod redraw;
pub mod registry;
pub mod runner;
pub mod selection;
mod sharpness;
pub mod still;
mod subject;
pub mod timings;
mod tracker;
mod video_decoder;
mod yuv;

pub use beside::RunBeside;
pub use cache::{entry_bytes as cache_entry_bytes, read_entry as read_cache_entry};
pub use config::PipelineConfig;
pub use error::PipelineError;
pub use folder_lock::FolderLock;
pub use kin_manifest::{KinSource, write_kin_keypoints, write_kin_manifest};
pub use message::one_line;
pub use outputs::{OutputOptions, Outputs, write_outputs};
pub use overlay::regenerated_dir;
pub use progress::RunHandle;
pub use runner::{
    RunOptions, RunSummary, default_models_dir, kin_and_write, regenerate_part, run, run_and_write,
};
pub use selection::{SelectionConfig, SelectionRecord};
