//! The networks on ONNX Runtime (`ort`, library loaded from `ORT_DYLIB_PATH`),
//! from the ONNX exports written by [`crate::blazepose::export_onnx`].

use std::path::Path;

use gait_core::StageError;
use gait_ort::Session;
use ort::value::Tensor;

use super::net::{Net, onnx_path};
use gait_tflite::Graph;

fn err(e: impl ToString) -> StageError {
    StageError::backend("ort", e.to_string())
}

struct OrtNet {
    session: Session,
    shape: Vec<i64>,
}

impl Net for OrtNet {
    fn run(&mut self, input: &[f32]) -> Result<Vec<Vec<f32>>, StageError> {
        let t = Tensor::from_array((self.shape.clone(), input.to_vec())).map_err(err)?;
        let outs = self.session.run(ort::inputs![t]).map_err(err)?;
        (0..outs.len())
            .map(|i| {
                let (_, data) = outs[i].try_extract_tensor::<f32>().map_err(err)?;
                Ok(data.to_vec())
            })
            .collect()
    }
}

/// Opens the ONNX file next to the `.tflite` file `tflite` (parsed as `graph`).
pub(crate) fn load(
    tflite: &Path,
    graph: &Graph,
    device: gait_ort::Device,
) -> Result<Box<dyn Net>, StageError> {
    let onnx = onnx_path(tflite);
    if !onnx.is_file() {
        return Err(StageError::MissingModel {
            path: onnx,
            hint: "run `gait models fetch blazepose` (it also writes the ONNX exports)".into(),
        });
    }
    let session = gait_ort::session(&onnx, device).map_err(|e| match e {
        gait_ort::SessionError::Runtime(m) => err(m),
        gait_ort::SessionError::Model(m) => StageError::bad_model(&onnx, m),
    })?;
    let input = graph
        .inputs
        .first()
        .ok_or_else(|| err("graph has no input"))?;
    let shape = graph.tensors[*input]
        .shape
        .iter()
        .map(|&d| d as i64)
        .collect();
    Ok(Box::new(OrtNet { session, shape }))
}
