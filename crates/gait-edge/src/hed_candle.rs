//! HED on candle: loads `ControlNetHED.pth` (torch pickle) or a safetensors
//! file with the same tensor names, checks every tensor's shape, runs on the
//! CPU or (CUDA builds) a GPU.

use std::collections::HashMap;
use std::path::Path;

use candle_core::{DType, Device, Tensor};

use crate::HedError;
use crate::hed_fuse::SideOutput;
use crate::hed_net::{BLOCKS, NORM, conv_name, projection_name, tensor_specs};

struct Conv {
    weight: Tensor,
    /// Shaped [1, C, 1, 1] for broadcasting over the feature map.
    bias: Tensor,
}

/// The network with its weights, ready to run.
pub(crate) struct CandleHed {
    device: Device,
    norm: Tensor,
    blocks: Vec<(Vec<Conv>, Conv)>,
}

impl CandleHed {
    pub(crate) fn load(path: &Path, device: &Device) -> Result<Self, HedError> {
        let bad = |e: candle_core::Error| HedError::Format(e.to_string());
        // The shared reader checks a .pth's declared lengths and shapes before candle
        // allocates them (a truncated or hostile file is an error, not gigabytes).
        let tensors: HashMap<String, Tensor> = gait_core::checkpoint::read_tensors(path)
            .map_err(|e| HedError::Format(e.to_string()))?;
        let mut checked = HashMap::new();
        for (name, shape) in tensor_specs() {
            let t = tensors.get(&name).ok_or_else(|| HedError::MissingTensor {
                name: name.clone(),
                shape: shape.clone(),
            })?;
            if t.dims() != shape.as_slice() {
                return Err(HedError::WrongShape {
                    name,
                    expected: shape,
                    found: t.dims().to_vec(),
                });
            }
            checked.insert(
                name,
                t.to_dtype(DType::F32)
                    .and_then(|t| t.to_device(device))
                    .map_err(bad)?,
            );
        }
        let take = |name: &str| checked[name].clone();
        let conv = |name: String| -> Result<Conv, HedError> {
            let bias = take(&format!("{name}.bias"));
            let c = bias.dims()[0];
            Ok(Conv {
                weight: take(&format!("{name}.weight")),
                bias: bias.reshape((1, c, 1, 1)).map_err(bad)?,
            })
        };
        let mut blocks = Vec::new();
        for (b, &(_, _, layers)) in BLOCKS.iter().enumerate() {
            let convs = (0..layers)
                .map(|l| conv(conv_name(b, l)))
                .collect::<Result<Vec<_>, _>>()?;
            blocks.push((convs, conv(projection_name(b))?));
        }
        Ok(Self {
            device: device.clone(),
            norm: take(NORM),
            blocks,
        })
    }

    /// Side outputs for one RGB image given as planar [3, h, w] floats in 0..255.
    pub(crate) fn forward(
        &self,
        chw: Vec<f32>,
        h: usize,
        w: usize,
    ) -> Result<Vec<SideOutput>, HedError> {
        let run = || -> candle_core::Result<Vec<SideOutput>> {
            let x = Tensor::from_vec(chw, (1, 3, h, w), &self.device)?;
            let mut x = x.broadcast_sub(&self.norm)?;
            let mut sides = Vec::with_capacity(self.blocks.len());
            for (b, (convs, projection)) in self.blocks.iter().enumerate() {
                if b > 0 {
                    x = x.max_pool2d(2)?;
                }
                for c in convs {
                    x = x
                        .conv2d(&c.weight, 1, 1, 1, 1)?
                        .broadcast_add(&c.bias)?
                        .relu()?;
                }
                let p = x
                    .conv2d(&projection.weight, 0, 1, 1, 1)?
                    .broadcast_add(&projection.bias)?;
                let (_, _, ph, pw) = p.dims4()?;
                sides.push(SideOutput {
                    width: pw,
                    height: ph,
                    data: p.flatten_all()?.to_vec1::<f32>()?,
                });
            }
            Ok(sides)
        };
        run().map_err(|e| HedError::Inference(e.to_string()))
    }
}
