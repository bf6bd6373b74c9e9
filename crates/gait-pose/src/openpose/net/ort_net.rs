//! OpenPose networks exported to ONNX, on ONNX Runtime (`ort`, library
//! loaded from `ORT_DYLIB_PATH`).
//!
//! Two output conventions are accepted: our export (tools/openpose/export_onnx.py)
//! with outputs named `paf` and `heatmap`, and OpenPose's caffe models'
//! single output of heatmaps then PAFs concatenated along the channels.

use std::path::Path;

use gait_core::StageError;
use gait_ort::Session;
use ort::value::Tensor;

use crate::openpose::{NetInput, NetOutput, OpenposeModel, OpenposeNet};

fn err(e: impl ToString) -> StageError {
    StageError::backend("ort", e.to_string())
}

enum Outputs {
    /// Two outputs, by name.
    Named,
    /// One output: heatmap channels, then PAF channels.
    Concatenated,
}

/// An ONNX export of an OpenPose network on ONNX Runtime.
pub struct OrtNet {
    session: Session,
    model: OpenposeModel,
    outputs: Outputs,
}

impl OrtNet {
    /// Opens `path` (an ONNX file, external data next to it) for `model`.
    pub fn load(
        path: &Path,
        model: OpenposeModel,
        device: gait_ort::Device,
    ) -> Result<Self, StageError> {
        if !path.is_file() {
            return Err(StageError::MissingModel {
                path: path.to_path_buf(),
                hint: match model {
                    OpenposeModel::Coco18 => "export it with tools/openpose/export_onnx.py from the checkpoint of `gait models fetch openpose`, or set model_path",
                    OpenposeModel::Body25 => "convert OpenPose's own BODY_25 model to ONNX and set model_path",
                }
                .into(),
            });
        }
        let session = gait_ort::session(path, device).map_err(|e| match e {
            gait_ort::SessionError::Runtime(m) => err(m),
            gait_ort::SessionError::Model(m) => StageError::bad_model(path, m),
        })?;
        let names: Vec<&str> = session.outputs().iter().map(|o| o.name()).collect();
        let outputs = if names.contains(&"paf") && names.contains(&"heatmap") {
            Outputs::Named
        } else if names.len() == 1 {
            Outputs::Concatenated
        } else {
            return Err(StageError::bad_model(
                path,
                format!(
                    "outputs {names:?}: expected `paf` and `heatmap`, or one output of heatmaps then PAFs"
                ),
            ));
        };
        if session.inputs().len() != 1 {
            return Err(StageError::bad_model(
                path,
                "expected one input (the image)",
            ));
        }
        Ok(Self {
            session,
            model,
            outputs,
        })
    }
}

/// (channels, height, width) of a 1xCxHxW output.
fn chw(shape: &[i64], what: &str) -> Result<(usize, usize, usize), StageError> {
    match shape {
        [1, c, h, w] if *c > 0 && *h > 0 && *w > 0 => Ok((*c as usize, *h as usize, *w as usize)),
        _ => Err(err(format!(
            "output {what} has shape {shape:?}, expected 1xCxHxW"
        ))),
    }
}

impl OpenposeNet for OrtNet {
    fn model(&self) -> OpenposeModel {
        self.model
    }

    fn run(&mut self, input: &NetInput) -> Result<NetOutput, StageError> {
        let (h, w) = (input.height, input.width);
        if h == 0 || w == 0 || h % 8 != 0 || w % 8 != 0 || input.data.len() != 3 * h * w {
            return Err(StageError::BadInput(format!(
                "network input must be 1x3xHxW with H, W positive multiples of 8; got {} values for {h}x{w}",
                input.data.len()
            )));
        }
        let (nh, np) = (self.model.heatmap_channels(), self.model.paf_channels());
        let model = self.model;
        let shape = vec![1i64, 3, h as i64, w as i64];
        let t = Tensor::from_array((shape, input.data.clone())).map_err(err)?;
        let outs = self.session.run(ort::inputs![t]).map_err(err)?;
        match self.outputs {
            Outputs::Named => {
                let (hs, heat) = outs["heatmap"].try_extract_tensor::<f32>().map_err(err)?;
                let (ps, paf) = outs["paf"].try_extract_tensor::<f32>().map_err(err)?;
                let (hc, oh, ow) = chw(hs, "heatmap")?;
                let (pc, ph, pw) = chw(ps, "paf")?;
                if hc != nh || pc != np || (oh, ow) != (ph, pw) {
                    return Err(err(format!(
                        "the network gives {hc} heatmaps and {pc} PAFs ({oh}x{ow}, {ph}x{pw}); \
                         a {model:?} network has {nh} and {np}: is `model` set right?"
                    )));
                }
                Ok(NetOutput {
                    heatmaps: heat.to_vec(),
                    pafs: paf.to_vec(),
                    height: oh,
                    width: ow,
                })
            }
            Outputs::Concatenated => {
                let (s, data) = outs[0].try_extract_tensor::<f32>().map_err(err)?;
                let (c, oh, ow) = chw(s, "0")?;
                if c != nh + np {
                    return Err(err(format!(
                        "the network's single output has {c} channels; a {model:?} network has \
                         {nh} heatmaps + {np} PAFs = {}: is `model` set right?",
                        nh + np
                    )));
                }
                let split = nh * oh * ow;
                Ok(NetOutput {
                    heatmaps: data[..split].to_vec(),
                    pafs: data[split..].to_vec(),
                    height: oh,
                    width: ow,
                })
            }
        }
    }
}
