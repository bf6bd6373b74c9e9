//! The `[pose]` keys of `kind = "openpose"`.

use std::path::PathBuf;

use gait_core::{Backend, PoseEstimator, StageContext, StageError};
use serde::{Deserialize, Serialize};

use super::OpenposeModel;
use super::decode::SearchParams;
use super::estimator::Openpose;
use crate::PersonChoice;

/// Keys of `[pose]` when `kind = "openpose"`; `[pose.search]` holds the
/// multi-scale search and grouping parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OpenposeConfig {
    /// candle runs `body_pose_model.pth` (COCO-18) directly; ort runs an ONNX
    /// export (tools/openpose/export_onnx.py), COCO-18 or BODY_25.
    pub backend: Backend,
    /// The body model the weights are for.
    pub model: OpenposeModel,
    /// Weights file, relative to the models folder (absolute paths work too).
    /// Default: see [`OpenposeConfig::default_model_path`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub model_path: Option<PathBuf>,
    /// Person to follow when several are in view.
    pub person: PersonChoice,
    pub search: SearchParams,
}

impl Default for OpenposeConfig {
    fn default() -> Self {
        Self {
            backend: Backend::Candle,
            model: OpenposeModel::Coco18,
            model_path: None,
            person: PersonChoice::default(),
            search: SearchParams::default(),
        }
    }
}

impl OpenposeConfig {
    /// Where `gait models fetch openpose` puts the checkpoint.
    pub const FETCHED_CHECKPOINT: &'static str = "openpose/body_pose_model.pth";

    /// The weights file used when `model_path` is not set: the fetched
    /// checkpoint for candle, its ONNX export (or `openpose/body_25.onnx`) for ort.
    pub fn default_model_path(&self) -> PathBuf {
        match (self.backend, self.model) {
            (Backend::Candle | Backend::Auto, _) => PathBuf::from(Self::FETCHED_CHECKPOINT),
            (Backend::Ort, OpenposeModel::Coco18) => PathBuf::from("openpose/body_pose_model.onnx"),
            (Backend::Ort, OpenposeModel::Body25) => PathBuf::from("openpose/body_25.onnx"),
        }
    }

    /// The weights file, resolved against the models folder.
    pub fn weights(&self, ctx: &StageContext) -> PathBuf {
        let p = self
            .model_path
            .clone()
            .unwrap_or_else(|| self.default_model_path());
        ctx.model_path(&p)
    }

    /// The model files the estimator reads (checksummed into `run.json`).
    pub fn model_files(&self, ctx: &StageContext) -> Vec<PathBuf> {
        vec![self.weights(ctx)]
    }

    pub fn build(&self, ctx: &StageContext) -> Result<Box<dyn PoseEstimator>, StageError> {
        Ok(Box::new(Openpose::new(self, ctx)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_and_defaults() {
        let c: OpenposeConfig = toml::from_str(
            "backend = \"ort\"\nmodel = \"body25\"\nperson = \"leftmost\"\n[search]\nscales = [0.5, 1.0]",
        )
        .unwrap();
        assert_eq!(c.model, OpenposeModel::Body25);
        assert_eq!(c.search.scales, vec![0.5, 1.0]);
        assert_eq!(
            c.default_model_path(),
            PathBuf::from("openpose/body_25.onnx")
        );
        let err = toml::from_str::<OpenposeConfig>("modle = \"coco18\"")
            .unwrap_err()
            .to_string();
        assert!(err.contains("modle") && err.contains("model_path"), "{err}");
        let err = toml::from_str::<OpenposeConfig>("model = \"body_21\"")
            .unwrap_err()
            .to_string();
        assert!(err.contains("coco18") && err.contains("body25"), "{err}");
    }

    #[test]
    fn missing_weights_name_the_file_and_the_fetch_command() {
        let ctx = StageContext::new("/nonexistent-models");
        let err = OpenposeConfig::default()
            .build(&ctx)
            .err()
            .unwrap()
            .to_string();
        assert!(
            err.contains("body_pose_model.pth") && err.contains("gait models fetch openpose"),
            "{err}"
        );
    }
}
