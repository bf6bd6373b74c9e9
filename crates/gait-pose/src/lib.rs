//! Pose estimators implementing [`gait_core::PoseEstimator`], chosen in the
//! `[pose]` table of a pipeline config by `kind`.

pub mod blazepose;
pub mod openpose;
mod person;

pub use person::{PersonAt, PersonChoice, PersonRule};

use std::path::PathBuf;

use gait_core::{PoseEstimator, StageContext, StageError};
use serde::{Deserialize, Serialize};

/// The `[pose]` table. `kind` picks the estimator; the other keys belong to it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum PoseConfig {
    /// MediaPipe BlazePose (full), the default model.
    Blazepose(blazepose::BlazeposeConfig),
    /// The OpenPose body model (COCO-18 or BODY_25), the paper's estimator.
    Openpose(openpose::OpenposeConfig),
    /// An external estimator loaded from a shared library (see docs/adding-a-stage.md).
    Plugin(gait_plugin::PluginConfig),
    /// An estimator written in Python (see docs/adding-a-stage.md).
    Python(gait_python::PythonStageConfig),
}

impl PoseConfig {
    pub fn build(&self, ctx: &StageContext) -> Result<Box<dyn PoseEstimator>, StageError> {
        match self {
            PoseConfig::Blazepose(c) => c.build(ctx),
            PoseConfig::Openpose(c) => c.build(ctx),
            PoseConfig::Plugin(p) => gait_plugin::load_pose_estimator(p, ctx),
            PoseConfig::Python(p) => gait_python::load_pose_estimator(p, ctx),
        }
    }

    /// Whom the run follows (`person`); plugins follow the default, the walker.
    pub fn person(&self) -> PersonChoice {
        match self {
            PoseConfig::Blazepose(c) => c.person,
            PoseConfig::Openpose(c) => c.person,
            PoseConfig::Plugin(_) | PoseConfig::Python(_) => PersonChoice::default(),
        }
    }

    /// The estimator the subject pass lists the people of each frame with, when it is not this
    /// one: a Python stage cannot list people, so for one that takes the subject's boxes
    /// (`estimate(self, frames, boxes)`, a top-down model) the built-in BlazePose detector (the
    /// default run's) finds them. A Python stage without boxes picks its person itself, as before.
    pub fn people_finder(&self) -> Option<PoseConfig> {
        match self {
            PoseConfig::Python(p) if gait_python::class_takes_boxes(p) => {
                Some(PoseConfig::Blazepose(Default::default()))
            }
            _ => None,
        }
    }

    /// Model files the estimator reads (checksummed into `run.json`).
    pub fn model_files(&self, ctx: &StageContext) -> Vec<PathBuf> {
        match self {
            PoseConfig::Blazepose(c) => c.model_files(ctx),
            PoseConfig::Openpose(c) => c.model_files(ctx),
            PoseConfig::Plugin(p) => vec![p.resolved_path()],
            PoseConfig::Python(p) => p.module_file().into_iter().collect(),
        }
    }
}
