//! The `kind = "hed"` edge stage: ControlNet's HED soft-edge annotator
//! (controlnet_aux `HEDdetector` with the Apache-2.0 `ControlNetHED` network)
//! on the candle or the ort backend.

use std::path::{Path, PathBuf};

use gait_core::{Backend, Device, EdgeDetector, EdgeMap, Frame, StageContext, StageError};
use image::RgbImage;
use serde::{Deserialize, Serialize};

use crate::hed_candle::CandleHed;
use crate::hed_fuse::{SideOutput, fuse};
use crate::hed_ort::OrtHed;
use crate::person_mask::{MaskKind, MaskSettings, PersonMask};
use crate::working_size::{DEFAULT_RESOLUTION, to_working_size};

/// How to obtain the weights; part of every missing-file message.
const FETCH_HINT: &str = "get it with `gait models fetch hed`";

/// `[edge] kind = "hed"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HedConfig {
    pub backend: Backend,
    /// Weights file, relative to the models folder unless absolute. Default:
    /// `ControlNetHED.pth` (candle; `.safetensors` also read) or
    /// `ControlNetHED.onnx` (ort).
    pub weights: Option<PathBuf>,
    /// controlnet_aux's `safe=True` (the "softedge_hedsafe" preprocessor):
    /// quantise the soft map to `safe_steps + 1` levels. `false` keeps the
    /// continuous soft edges ("softedge_hed").
    pub safe: bool,
    /// Steps of the safe quantisation (controlnet_aux uses 2).
    pub safe_steps: u32,
    /// Short side of the working image (sides rounded to multiples of 64);
    /// 0 = the frame's own size.
    pub resolution: u32,
    /// Person mask: `"none"` (default) or `"selfie"` (MediaPipe selfie
    /// segmentation; edges outside the person are removed).
    pub mask: MaskKind,
    /// Person probability threshold of the mask.
    pub mask_threshold: f32,
    /// Pixels the mask is dilated by (at the working size).
    pub mask_dilate: u32,
    /// Mask model, relative to the models folder unless absolute (default
    /// `blazepose/selfie_segmentation.tflite`).
    pub mask_model: Option<PathBuf>,
}

impl Default for HedConfig {
    fn default() -> Self {
        Self {
            backend: Backend::Candle,
            weights: None,
            safe: false,
            safe_steps: 2,
            resolution: DEFAULT_RESOLUTION,
            mask: MaskKind::None,
            mask_threshold: 0.5,
            mask_dilate: 8,
            mask_model: None,
        }
    }
}

impl HedConfig {
    /// The weights file this config reads, resolved in the models folder.
    pub fn weights_path(&self, ctx: &StageContext) -> PathBuf {
        let default = match self.backend {
            Backend::Candle | Backend::Auto => "ControlNetHED.pth",
            Backend::Ort => "ControlNetHED.onnx",
        };
        ctx.model_path(self.weights.as_deref().unwrap_or(Path::new(default)))
    }

    /// The person-mask keys of this config.
    pub fn mask_settings(&self) -> MaskSettings {
        MaskSettings {
            kind: self.mask,
            threshold: self.mask_threshold,
            dilate: self.mask_dilate,
            model: self.mask_model.clone(),
        }
    }

    pub fn build(&self, ctx: &StageContext) -> Result<HedDetector, StageError> {
        if self.safe && self.safe_steps == 0 {
            return Err(StageError::BadInput("edge.safe_steps must be >= 1".into()));
        }
        let path = self.weights_path(ctx);
        let network = HedNetwork::load_on(self.backend, &path, ctx.device)
            .map_err(|e| e.into_stage_error(self.backend, &path))?;
        Ok(HedDetector {
            network,
            backend: self.backend,
            safe_steps: self.safe.then_some(self.safe_steps),
            resolution: self.resolution,
            mask: self.mask_settings().build(ctx)?,
        })
    }
}

/// Why the HED network could not be loaded or run.
#[derive(Debug, thiserror::Error)]
pub enum HedError {
    #[error("file not found")]
    Missing,
    #[error("checkpoint has no tensor `{name}` (expected shape {shape:?})")]
    MissingTensor { name: String, shape: Vec<usize> },
    #[error("tensor `{name}` has shape {found:?}, expected {expected:?}")]
    WrongShape {
        name: String,
        expected: Vec<usize>,
        found: Vec<usize>,
    },
    #[error("cannot read: {0}")]
    Format(String),
    #[error("{0}")]
    Inference(String),
    /// `[run] device` cannot be used (e.g. CUDA in a build without it).
    #[error(transparent)]
    Device(StageError),
}

impl HedError {
    fn into_stage_error(self, backend: Backend, path: &Path) -> StageError {
        match self {
            HedError::Missing => StageError::MissingModel {
                path: path.to_path_buf(),
                hint: FETCH_HINT.to_string(),
            },
            HedError::Inference(reason) => StageError::backend(backend.to_string(), reason),
            HedError::Device(e) => e,
            other => StageError::bad_model(path, other),
        }
    }
}

/// The HED network on one backend; yields the five raw side outputs.
pub enum HedNetwork {
    Candle(Box<CandleHedNet>),
    Ort(Box<OrtHedNet>),
}

/// Opaque candle network (see [`HedNetwork`]).
pub struct CandleHedNet(CandleHed);
/// Opaque ort session (see [`HedNetwork`]).
pub struct OrtHedNet(OrtHed);

impl HedNetwork {
    /// Loads weights: a torch checkpoint or safetensors (candle), or an ONNX export (ort).
    pub fn load(backend: Backend, path: &Path) -> Result<Self, HedError> {
        Self::load_on(backend, path, Device::Cpu)
    }

    /// [`HedNetwork::load`] on `device` (`[run] device`).
    pub fn load_on(backend: Backend, path: &Path, device: Device) -> Result<Self, HedError> {
        if !path.is_file() {
            return Err(HedError::Missing);
        }
        Ok(match backend {
            Backend::Candle | Backend::Auto => {
                let device = device.candle().map_err(HedError::Device)?;
                Self::Candle(Box::new(CandleHedNet(CandleHed::load(path, &device)?)))
            }
            Backend::Ort => Self::Ort(Box::new(OrtHedNet(OrtHed::load(path, device)?))),
        })
    }

    /// Side outputs 1..5 (full, 1/2, 1/4, 1/8, 1/16 size) of an RGB image.
    pub fn side_outputs(&mut self, image: &RgbImage) -> Result<Vec<SideOutput>, HedError> {
        let (w, h) = (image.width() as usize, image.height() as usize);
        let mut chw = vec![0f32; 3 * w * h];
        for (i, px) in image.pixels().enumerate() {
            for c in 0..3 {
                chw[c * w * h + i] = f32::from(px[c]);
            }
        }
        match self {
            Self::Candle(net) => net.0.forward(chw, h, w),
            Self::Ort(net) => net.0.forward(&chw, h, w),
        }
    }
}

/// Resizes each frame to the working size, runs the network and fuses its
/// side outputs into a soft edge map (white edges on black).
pub struct HedDetector {
    network: HedNetwork,
    backend: Backend,
    safe_steps: Option<u32>,
    resolution: u32,
    mask: Option<PersonMask>,
}

impl HedDetector {
    /// The soft edge map of an image already at its working size.
    pub fn edges_of(&mut self, image: &RgbImage) -> Result<image::GrayImage, HedError> {
        let sides = self.network.side_outputs(image)?;
        Ok(fuse(
            &sides,
            image.width() as usize,
            image.height() as usize,
            self.safe_steps,
        ))
    }
}

impl EdgeDetector for HedDetector {
    fn detect(&mut self, frames: &[Frame]) -> Result<Vec<EdgeMap>, StageError> {
        frames
            .iter()
            .map(|frame| {
                if frame.width() == 0 || frame.height() == 0 {
                    return Err(StageError::BadInput(format!(
                        "frame {} is empty",
                        frame.index
                    )));
                }
                let (image, resize) = to_working_size(frame, self.resolution);
                let mut edges = self
                    .edges_of(&image)
                    .map_err(|e| StageError::backend(self.backend.to_string(), e))?;
                if let Some(mask) = &self.mask {
                    mask.apply(&image, &mut edges)?;
                }
                Ok(EdgeMap {
                    index: frame.index,
                    image: edges,
                    resize,
                })
            })
            .collect()
    }
}
