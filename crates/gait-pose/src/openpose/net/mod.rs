//! The OpenPose networks: COCO-18 body model on candle (from `body_pose_model.pth`) and ONNX exports on ort.

mod coco18;
mod ort_net;

use std::collections::HashMap;
use std::path::Path;

use gait_core::checkpoint;
use gait_core::{Backend, StageError};

use super::{OpenposeModel, OpenposeNet};

pub use coco18::{CandleNet, coco18_layout};
pub use ort_net::OrtNet;

/// Why a checkpoint's tensors do not make the network.
#[derive(Debug, thiserror::Error)]
pub enum WeightsError {
    #[error("tensor `{0}` is missing")]
    Missing(String),
    #[error("tensor `{name}` has shape {found:?}, expected {expected:?}")]
    Shape {
        name: String,
        expected: Vec<usize>,
        found: Vec<usize>,
    },
    #[error("unknown tensors {0:?}: not the COCO-18 body_pose_model layout")]
    Unknown(Vec<String>),
    #[error("{0}")]
    Read(String),
}

/// Loads the network in `path` for `model` on `backend`: candle reads the
/// COCO-18 checkpoint (`.pth` or `.safetensors`), ort an ONNX export.
pub fn load(
    path: &Path,
    model: OpenposeModel,
    backend: Backend,
) -> Result<Box<dyn OpenposeNet>, StageError> {
    load_on(path, model, backend, gait_core::Device::Cpu)
}

/// [`load`] on `device` (`[run] device`).
pub fn load_on(
    path: &Path,
    model: OpenposeModel,
    backend: Backend,
    device: gait_core::Device,
) -> Result<Box<dyn OpenposeNet>, StageError> {
    match backend {
        Backend::Ort => Ok(Box::new(OrtNet::load(path, model, device)?)),
        Backend::Candle | Backend::Auto => {
            if model != OpenposeModel::Coco18 {
                return Err(StageError::BadInput(format!(
                    "the candle backend runs the COCO-18 model only; for {model:?} use backend = \"ort\" \
                     with an ONNX export"
                )));
            }
            if !path.is_file() {
                return Err(StageError::MissingModel {
                    path: path.to_path_buf(),
                    hint:
                        "run `gait models fetch openpose` (body_pose_model.pth) or set model_path"
                            .into(),
                });
            }
            let device = device.candle()?;
            let tensors = checkpoint::read_tensors(path)
                .map_err(|e| StageError::bad_model(path, e))?
                .into_iter()
                .map(|(name, t)| Ok((name, t.to_device(&device)?)))
                .collect::<candle_core::Result<HashMap<_, _>>>()
                .map_err(|e| StageError::backend("candle", e))?;
            let net =
                CandleNet::from_tensors(tensors).map_err(|e| StageError::bad_model(path, e))?;
            Ok(Box::new(net))
        }
    }
}

/// The COCO-18 network on candle from tensors already in memory, named as in
/// the checkpoint (see [`coco18_layout`]).
pub fn candle_from_tensors(
    tensors: HashMap<String, candle_core::Tensor>,
) -> Result<CandleNet, WeightsError> {
    CandleNet::from_tensors(tensors)
}

/// Every tensor in a `.pth` (zip or legacy format) or `.safetensors` file, as
/// f32, by name (what [`load`] reads before building the network).
pub fn read_checkpoint(path: &Path) -> Result<HashMap<String, candle_core::Tensor>, StageError> {
    checkpoint::read_tensors(path).map_err(|e| StageError::bad_model(path, e))
}
