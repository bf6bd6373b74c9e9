//! HED on ONNX Runtime, from an ONNX export of the same network
//! (`tools/edge/export_hed_onnx.py`): input `image` [1, 3, H, W] in 0..255,
//! outputs `side1`..`side5`.

use std::path::Path;

use gait_ort::Session;
use ort::value::TensorRef;

use crate::HedError;
use crate::hed_fuse::SideOutput;

pub(crate) struct OrtHed {
    session: Session,
}

impl OrtHed {
    pub(crate) fn load(path: &Path, device: gait_ort::Device) -> Result<Self, HedError> {
        let session = gait_ort::session(path, device).map_err(|e| match e {
            gait_ort::SessionError::Runtime(m) => HedError::Inference(m),
            gait_ort::SessionError::Model(m) => HedError::Format(m),
        })?;
        let names: Vec<&str> = session.outputs().iter().map(|o| o.name()).collect();
        for i in 1..=5 {
            let want = format!("side{i}");
            if !names.contains(&want.as_str()) {
                return Err(HedError::Format(format!(
                    "ONNX model has no output `{want}` (outputs: {names:?}); export it with tools/edge/export_hed_onnx.py"
                )));
            }
        }
        Ok(Self { session })
    }

    pub(crate) fn forward(
        &mut self,
        chw: &[f32],
        h: usize,
        w: usize,
    ) -> Result<Vec<SideOutput>, HedError> {
        let err = |e: ort::Error| HedError::Inference(e.to_string());
        let input = TensorRef::from_array_view(([1usize, 3, h, w], chw)).map_err(err)?;
        let outputs = self
            .session
            .run(ort::inputs!["image" => input])
            .map_err(err)?;
        (1..=5)
            .map(|i| {
                let name = format!("side{i}");
                let value = outputs
                    .get(&name)
                    .ok_or_else(|| HedError::Inference(format!("no output `{name}`")))?;
                let (shape, data) = value.try_extract_tensor::<f32>().map_err(err)?;
                let dims: &[i64] = shape;
                let [_, _, oh, ow] = dims else {
                    return Err(HedError::Inference(format!(
                        "`{name}` has shape {dims:?}, expected 4-D"
                    )));
                };
                Ok(SideOutput {
                    width: *ow as usize,
                    height: *oh as usize,
                    data: data.to_vec(),
                })
            })
            .collect()
    }
}
