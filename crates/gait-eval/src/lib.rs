//! Evaluation of keypoints and joint angles against ground truth (the paper's
//! Table 1 and failure modes), the normative data and scores (GPS, GVS, MAP), the figures, and
//! exports to OpenSim (`.trc`, `.mot`), c3d and OpenPose JSON. The report that lays them out
//! for a clinician is `gait-report`.

mod align;
pub mod angles;
mod cycle_traces;
mod error;
mod evaluation;
pub mod export;
pub mod failure;
pub mod fsutil;
mod input;
pub mod keypoint_error;
pub mod kin;
pub mod names;
pub mod normative;
mod normative_data;
pub mod normative_frontal;
pub mod openpose;
mod options;
pub mod plot;
pub mod reliability;
pub mod report_config;
pub mod scores;
mod stats;
mod table;

pub use align::{Aligned, align, canonicalize};
pub use angles::{ANGLE_COLUMNS, AngleTable, read_angles_csv};
pub use cycle_traces::{CycleTrace, read_cycles_all_csv};
pub use error::EvalError;
pub use evaluation::{Evaluation, evaluate_with_angles};
pub use export::{TrcOptions, write_mot, write_trc};
pub use input::read_poses;
pub use kin::evaluate;
pub use names::Side;
pub use normative::Normative;
pub use options::{EvalOptions, Role};
pub use plot::{
    CycleCurve, FailureEntry, Figure, GraphContext, StripOptions, comparison_plot,
    consistency_plot, failure_bars, gait_graphs, map_bars, read_cycles_csv, skeleton_strip,
};
pub use scores::Scores;
pub use stats::Stat;
pub use table::{metrics_csv, table_markdown, write_eval};
