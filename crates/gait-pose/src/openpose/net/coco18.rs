//! The COCO-18 body network of pytorch-openpose / controlnet_aux
//! (`bodypose_model`) on candle, with its checkpoint layout.

use std::collections::HashMap;

use candle_core::{D, Device, Tensor};
use gait_core::StageError;

use super::WeightsError;
use crate::openpose::{NetInput, NetOutput, OpenposeModel, OpenposeNet};

/// One conv layer of the layout: checkpoint name, channels, kernel, ReLU after.
struct ConvSpec {
    name: String,
    cin: usize,
    cout: usize,
    k: usize,
    relu: bool,
}

enum Op {
    Conv(ConvSpec),
    Pool,
}

fn conv(name: impl Into<String>, cin: usize, cout: usize, k: usize, relu: bool) -> Op {
    Op::Conv(ConvSpec {
        name: name.into(),
        cin,
        cout,
        k,
        relu,
    })
}

/// The VGG-19 front end (`model0`): conv1_1 .. conv4_2 plus conv4_3_CPM and
/// conv4_4_CPM, ReLU after every conv, 2x2 max pools: stride 8, 128 channels.
fn front() -> Vec<Op> {
    let c = |name: &str, cin, cout| conv(name, cin, cout, 3, true);
    vec![
        c("conv1_1", 3, 64),
        c("conv1_2", 64, 64),
        Op::Pool,
        c("conv2_1", 64, 128),
        c("conv2_2", 128, 128),
        Op::Pool,
        c("conv3_1", 128, 256),
        c("conv3_2", 256, 256),
        c("conv3_3", 256, 256),
        c("conv3_4", 256, 256),
        Op::Pool,
        c("conv4_1", 256, 512),
        c("conv4_2", 512, 512),
        c("conv4_3_CPM", 512, 256),
        c("conv4_4_CPM", 256, 128),
    ]
}

/// Branch `branch` (1: PAFs, 38 channels; 2: heatmaps, 19) of stage `stage`.
fn stage(stage: usize, branch: usize) -> Vec<Op> {
    let cout = if branch == 1 { 38 } else { 19 };
    if stage == 1 {
        let n = |i| format!("conv5_{i}_CPM_L{branch}");
        return vec![
            conv(n(1), 128, 128, 3, true),
            conv(n(2), 128, 128, 3, true),
            conv(n(3), 128, 128, 3, true),
            conv(n(4), 128, 512, 1, true),
            conv(n(5), 512, cout, 1, false),
        ];
    }
    let n = |i| format!("Mconv{i}_stage{stage}_L{branch}");
    // controlnet_aux's list of layers without ReLU names Mconv7_stage6_L1
    // twice and never Mconv7_stage6_L2, so its final heatmaps do pass a ReLU.
    let last_relu = stage == 6 && branch == 2;
    vec![
        conv(n(1), 185, 128, 7, true),
        conv(n(2), 128, 128, 7, true),
        conv(n(3), 128, 128, 7, true),
        conv(n(4), 128, 128, 7, true),
        conv(n(5), 128, 128, 7, true),
        conv(n(6), 128, 128, 1, true),
        conv(n(7), 128, cout, 1, last_relu),
    ]
}

/// All blocks in the torch model's registration order (model0, model1_1 ..
/// model6_1, model1_2 .. model6_2), which is the state_dict order.
fn blocks() -> Vec<Vec<Op>> {
    let mut b = vec![front()];
    b.extend((1..=6).map(|s| stage(s, 1)));
    b.extend((1..=6).map(|s| stage(s, 2)));
    b
}

/// Every tensor of `body_pose_model.pth` (names without the torch module
/// prefix, as the checkpoint stores them) with its shape, in state_dict order.
pub fn coco18_layout() -> Vec<(String, Vec<usize>)> {
    let mut out = Vec::new();
    for op in blocks().into_iter().flatten() {
        if let Op::Conv(c) = op {
            out.push((format!("{}.weight", c.name), vec![c.cout, c.cin, c.k, c.k]));
            out.push((format!("{}.bias", c.name), vec![c.cout]));
        }
    }
    out
}

struct Conv {
    weight: Tensor,
    /// Shaped 1xCx1x1 to broadcast over the output.
    bias: Tensor,
    pad: usize,
    relu: bool,
}

enum Layer {
    Conv(Conv),
    Pool,
}

/// The COCO-18 network on candle (CPU).
pub struct CandleNet {
    /// Where the weights live; inputs go there too.
    device: Device,
    front: Vec<Layer>,
    /// Stages 1..=6, each (PAF branch, heatmap branch).
    stages: Vec<(Vec<Layer>, Vec<Layer>)>,
}

impl CandleNet {
    /// Builds the network from checkpoint tensors (names as in
    /// [`coco18_layout`]); every tensor must be there with its shape, and
    /// nothing else.
    pub fn from_tensors(mut tensors: HashMap<String, Tensor>) -> Result<Self, WeightsError> {
        let device = tensors
            .values()
            .next()
            .map_or(Device::Cpu, |t| t.device().clone());
        let mut take = |c: &ConvSpec| -> Result<Layer, WeightsError> {
            let w = take_tensor(
                &mut tensors,
                &format!("{}.weight", c.name),
                &[c.cout, c.cin, c.k, c.k],
            )?;
            let b = take_tensor(&mut tensors, &format!("{}.bias", c.name), &[c.cout])?;
            Ok(Layer::Conv(Conv {
                weight: w,
                bias: b.reshape((1, c.cout, 1, 1)).map_err(cerr)?,
                pad: c.k / 2,
                relu: c.relu,
            }))
        };
        let mut build = |ops: Vec<Op>| -> Result<Vec<Layer>, WeightsError> {
            ops.into_iter()
                .map(|op| match op {
                    Op::Conv(c) => take(&c),
                    Op::Pool => Ok(Layer::Pool),
                })
                .collect()
        };
        let front = build(front())?;
        let mut stages = Vec::with_capacity(6);
        for s in 1..=6 {
            stages.push((build(stage(s, 1))?, build(stage(s, 2))?));
        }
        if !tensors.is_empty() {
            let mut extra: Vec<String> = tensors.into_keys().collect();
            extra.sort();
            return Err(WeightsError::Unknown(extra));
        }
        Ok(Self {
            device,
            front,
            stages,
        })
    }

    fn forward(&self, x: &Tensor) -> candle_core::Result<(Tensor, Tensor)> {
        let features = run_layers(x, &self.front)?;
        let mut input = features.clone();
        let mut out = None;
        for (i, (paf_branch, heat_branch)) in self.stages.iter().enumerate() {
            let paf = run_layers(&input, paf_branch)?;
            let heat = run_layers(&input, heat_branch)?;
            if i + 1 < self.stages.len() {
                input = Tensor::cat(&[&paf, &heat, &features], 1)?;
            }
            out = Some((paf, heat));
        }
        out.ok_or_else(|| candle_core::Error::Msg("network has no stages".into()))
    }
}

fn cerr(e: candle_core::Error) -> WeightsError {
    WeightsError::Read(e.to_string())
}

/// Removes `name` from `tensors`, checking its shape.
fn take_tensor(
    tensors: &mut HashMap<String, Tensor>,
    name: &str,
    shape: &[usize],
) -> Result<Tensor, WeightsError> {
    let t = tensors
        .remove(name)
        .ok_or_else(|| WeightsError::Missing(name.to_string()))?;
    if t.dims() != shape {
        return Err(WeightsError::Shape {
            name: name.to_string(),
            expected: shape.to_vec(),
            found: t.dims().to_vec(),
        });
    }
    t.to_dtype(candle_core::DType::F32)
        .and_then(|t| t.contiguous())
        .map_err(cerr)
}

fn run_layers(x: &Tensor, layers: &[Layer]) -> candle_core::Result<Tensor> {
    let mut x = x.clone();
    for layer in layers {
        x = match layer {
            Layer::Pool => x.max_pool2d(2)?,
            Layer::Conv(c) => {
                let y = x
                    .conv2d(&c.weight, c.pad, 1, 1, 1)?
                    .broadcast_add(&c.bias)?;
                if c.relu { y.relu()? } else { y }
            }
        };
    }
    Ok(x)
}

impl OpenposeNet for CandleNet {
    fn model(&self) -> OpenposeModel {
        OpenposeModel::Coco18
    }

    fn run(&mut self, input: &NetInput) -> Result<NetOutput, StageError> {
        let (h, w) = (input.height, input.width);
        if h == 0 || w == 0 || h % 8 != 0 || w % 8 != 0 || input.data.len() != 3 * h * w {
            return Err(StageError::BadInput(format!(
                "network input must be 1x3xHxW with H, W positive multiples of 8; got {} values for {h}x{w}",
                input.data.len()
            )));
        }
        let err = |e: candle_core::Error| StageError::backend("candle", e);
        let x = Tensor::from_slice(&input.data, (1, 3, h, w), &self.device).map_err(err)?;
        let (paf, heat) = self.forward(&x).map_err(err)?;
        let flat = |t: &Tensor| t.flatten_all().and_then(|t| t.to_vec1::<f32>());
        let (oh, ow) = (
            heat.dim(D::Minus2).map_err(err)?,
            heat.dim(D::Minus1).map_err(err)?,
        );
        Ok(NetOutput {
            heatmaps: flat(&heat).map_err(err)?,
            pafs: flat(&paf).map_err(err)?,
            height: oh,
            width: ow,
        })
    }
}
