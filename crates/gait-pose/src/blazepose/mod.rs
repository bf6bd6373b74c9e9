//! MediaPipe BlazePose (full): person detector + 33-landmark model, run on
//! candle (pure Rust, straight from the `.tflite` files) or on ONNX Runtime.

mod anchors;
mod detection;
mod estimator;
pub mod fetch;
mod landmarks;
mod names;
mod net;
mod ort_net;
mod person;
mod perspective;
mod roi;
mod roi_filter;
mod warp;

use std::path::PathBuf;

use gait_core::{Backend, PoseEstimator, StageContext, StageError};
use serde::{Deserialize, Serialize};

pub use crate::person::PersonChoice;
pub use estimator::Blazepose;
pub use names::NATIVE;
pub use net::{DETECTOR_FILE, LANDMARK_FILE};
pub use roi_filter::{AuxFilter, RoiFilter};
pub use warp::Border;

/// Runs one network (`.tflite` file `model`, or its ONNX export for ort) on
/// one NHWC input; returns its raw outputs flattened, in graph order. For
/// checks and benchmarks; the estimator wraps this.
pub fn raw_outputs(
    model: &std::path::Path,
    backend: Backend,
    input: &[f32],
) -> Result<Vec<Vec<f32>>, StageError> {
    net::load(model, backend, gait_core::Device::Cpu)?.run(input)
}

/// mediapipe's `ImageToTensorCalculator` (CPU) up to the float conversion:
/// the `size` x `size` RGB crop (row-major, HWC) of `roi` = [x_centre,
/// y_centre, width, height, rotation] (a `NormalizedRect`) of `image`, padded
/// to a square as keep_aspect_ratio does. `None` for a degenerate rectangle.
/// For checks against mediapipe; the estimator crops the same way.
pub fn image_to_tensor(
    image: &image::RgbImage,
    roi: [f32; 5],
    size: usize,
    border: Border,
) -> Option<Vec<u8>> {
    warp::crop_roi(image, &roi::Roi::from_array(roi), size, border)
}

/// Keys of `[pose]` when `kind = "blazepose"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BlazeposeConfig {
    pub backend: Backend,
    /// Folder holding the model files, relative to the models folder.
    pub model_dir: PathBuf,
    /// The subject when several people are in view: `"walker"` (default),
    /// `"largest"`, ..., or `{ frame = N, x = X, y = Y }` (see gait-subject).
    pub person: PersonChoice,
    /// Minimum detector score for a person (mediapipe: 0.5).
    pub detection_threshold: f32,
    /// Minimum pose presence to accept landmarks and keep tracking (mediapipe: 0.5).
    pub presence_threshold: f32,
    /// Follow the person from the previous frame's landmarks instead of
    /// detecting in every frame (video mode); re-detects when presence drops.
    pub tracking: bool,
    /// What the landmarks the tracked crop is built from go through first:
    /// `"none"` (default: this frame's landmarks 33/34 as they are) or
    /// `"mediapipe"` (the One-Euro filter mediapipe's video mode always runs
    /// on them, even with `smooth_landmarks = false`: min_cutoff 0.01, beta
    /// 10, derivate_cutoff 1, at the 30 fps clock of its Python API; restarted
    /// with every detection), so tracking gives what `mp.solutions.pose.Pose`
    /// gives. Only the crop is filtered, never the keypoints.
    pub roi_filter: RoiFilter,
}

impl Default for BlazeposeConfig {
    fn default() -> Self {
        Self {
            backend: Backend::Candle,
            model_dir: PathBuf::from("blazepose"),
            person: PersonChoice::default(),
            detection_threshold: 0.5,
            presence_threshold: 0.5,
            tracking: true,
            roi_filter: RoiFilter::None,
        }
    }
}

impl BlazeposeConfig {
    /// The model files the estimator reads, resolved against the models folder.
    pub fn model_files(&self, ctx: &StageContext) -> Vec<PathBuf> {
        let files = self.tflite_files(ctx);
        match self.backend {
            Backend::Candle | Backend::Auto => files.to_vec(),
            Backend::Ort => files
                .iter()
                .flat_map(|f| [f.clone(), net::onnx_path(f)])
                .collect(),
        }
    }

    /// The detector and landmark `.tflite` files.
    fn tflite_files(&self, ctx: &StageContext) -> [PathBuf; 2] {
        let dir = ctx.model_path(&self.model_dir);
        [dir.join(DETECTOR_FILE), dir.join(LANDMARK_FILE)]
    }

    pub fn build(&self, ctx: &StageContext) -> Result<Box<dyn PoseEstimator>, StageError> {
        Ok(Box::new(Blazepose::new(self, ctx)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn config_keys() {
        let c: BlazeposeConfig =
            toml::from_str("person = \"most_central\"\ntracking = false").unwrap();
        assert_eq!(c.person, PersonChoice::Rule(crate::PersonRule::MostCentral));
        assert!(!c.tracking);
        assert_eq!(c.detection_threshold, 0.5);
        assert_eq!(c.roi_filter, RoiFilter::None);
        let c: BlazeposeConfig = toml::from_str("roi_filter = \"mediapipe\"").unwrap();
        assert_eq!(c.roi_filter, RoiFilter::Mediapipe);
        assert!(toml::from_str::<BlazeposeConfig>("roi_filter = \"one_euro\"").is_err());
        let err = toml::from_str::<BlazeposeConfig>("persn = 1")
            .unwrap_err()
            .to_string();
        assert!(err.contains("persn") && err.contains("person"), "{err}");
    }

    #[test]
    fn missing_models_name_the_fetch_command() {
        let ctx = StageContext::new("/nonexistent-models");
        let err = BlazeposeConfig::default()
            .build(&ctx)
            .err()
            .unwrap()
            .to_string();
        assert!(
            err.contains("pose_detection.tflite") && err.contains("gait models fetch blazepose"),
            "{err}"
        );
    }
}
