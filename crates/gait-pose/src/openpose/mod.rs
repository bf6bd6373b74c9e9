//! OpenPose body estimator (the paper's pose model): the CMU network
//! (VGG-19 front end + refinement stages of part-affinity fields and
//! heatmaps) on candle or ONNX Runtime, then OpenPose's decoding into people.
//!
//! `net` runs a network on one prepared image; `decode` does everything
//! around it (scales, padding, upsampling, peaks, PAF assembly).

mod config;
pub mod decode;
mod estimator;
mod names;
pub mod net;

pub use config::OpenposeConfig;
pub use estimator::Openpose;
pub use names::keypoint_names;

use gait_core::StageError;
use serde::{Deserialize, Serialize};

/// Which body model a network is: decides the keypoint order and the limbs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OpenposeModel {
    /// 18 keypoints, `body_pose_model.pth` of pytorch-openpose / controlnet_aux.
    #[default]
    Coco18,
    /// 25 keypoints with heels and toes (OpenPose's default model).
    Body25,
}

impl OpenposeModel {
    /// Keypoint names in the network's order (canonical where one exists).
    pub fn keypoints(self) -> &'static [&'static str] {
        match self {
            OpenposeModel::Coco18 => &gait_core::openpose_layout::COCO_18,
            OpenposeModel::Body25 => &gait_core::openpose_layout::BODY_25,
        }
    }

    /// Heatmap channels: one per keypoint plus the background.
    pub fn heatmap_channels(self) -> usize {
        self.keypoints().len() + 1
    }

    /// PAF channels: an x and a y field per limb.
    pub fn paf_channels(self) -> usize {
        match self {
            OpenposeModel::Coco18 => 38,
            OpenposeModel::Body25 => 52,
        }
    }
}

/// One image prepared for the network: 1x3xHxW, BGR channel order, values
/// `pixel / 256 - 0.5` (OpenPose's Python preprocessing), H and W multiples of 8.
#[derive(Debug, Clone, PartialEq)]
pub struct NetInput {
    pub data: Vec<f32>,
    pub height: usize,
    pub width: usize,
}

/// The network's last-stage maps at stride 8 (`height` x `width` each, CHW).
#[derive(Debug, Clone, PartialEq)]
pub struct NetOutput {
    /// `model.heatmap_channels()` maps, the background last.
    pub heatmaps: Vec<f32>,
    /// `model.paf_channels()` maps.
    pub pafs: Vec<f32>,
    pub height: usize,
    pub width: usize,
}

/// A loaded OpenPose network, on whichever backend.
pub trait OpenposeNet: Send {
    /// The body model the network was trained for.
    fn model(&self) -> OpenposeModel;
    /// Runs the network on one prepared image.
    fn run(&mut self, input: &NetInput) -> Result<NetOutput, StageError>;
}
