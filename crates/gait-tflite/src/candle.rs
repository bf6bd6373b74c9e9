//! Runs a TFLite graph on candle (CPU), op by op. 4-D activations live in
//! candle as NCHW; TFLite's NHWC semantics (axes, reshapes, paddings) are
//! translated at build time.

use candle_core::{Device, Tensor};

use crate::depthwise::Depthwise;
use crate::model::{Activation, Graph, Op, OpOptions};
use crate::same::{self, nchw_axis};

type R<T> = Result<T, String>;

fn ce(e: candle_core::Error) -> String {
    e.to_string()
}

enum Step {
    Conv1x1 {
        w: Tensor,
        b: Tensor,
    },
    Conv {
        w: Tensor,
        b: Tensor,
        stride: usize,
        dilation: usize,
        pads: [usize; 4],
    },
    Depthwise(Depthwise),
    Add,
    Mul,
    /// Per NCHW axis (before, after).
    Pad(Vec<(usize, usize)>),
    Reshape(Vec<usize>),
    Concat(usize),
    MaxPool {
        k: (usize, usize),
        stride: (usize, usize),
        pads: [usize; 4],
    },
    Resize {
        ry: Tensor,
        rxt: Tensor,
    },
    DepthToSpace(usize),
    /// VALID average pooling (the selfie model's global pools).
    AvgPool {
        k: (usize, usize),
        stride: (usize, usize),
    },
    /// MediaPipe's `Convolution2DTransposeBias` where kernel == stride (no
    /// overlap): a 1x1 conv to `block^2 * o` channels, then depth-to-space.
    TransposeConv {
        w: Tensor,
        b: Tensor,
        block: usize,
    },
    HardSwish,
    Logistic,
    Relu,
    Relu6,
}

struct Node {
    step: Step,
    inputs: Vec<usize>,
    output: usize,
    act: Activation,
}

/// A TFLite graph compiled to candle operations.
pub struct CandleGraph {
    nodes: Vec<Node>,
    consts: Vec<Option<Tensor>>,
    rank: Vec<usize>,
    input: usize,
    input_shape: Vec<usize>,
    outputs: Vec<usize>,
}

fn resize_matrix(input: usize, output: usize, align: bool, half: bool) -> Vec<f32> {
    let scale = if align && output > 1 {
        (input - 1) as f32 / (output - 1) as f32
    } else {
        input as f32 / output as f32
    };
    let mut m = vec![0f32; output * input];
    for o in 0..output {
        let s = if half {
            (o as f32 + 0.5) * scale - 0.5
        } else {
            o as f32 * scale
        };
        let lo = (s.floor().max(0.0) as usize).min(input - 1);
        let hi = (s.ceil().max(0.0) as usize).min(input - 1);
        let f = s - lo as f32;
        m[o * input + lo] += 1.0 - f;
        m[o * input + hi] += f;
    }
    m
}

impl CandleGraph {
    /// Compiles `graph`; fails on operators or layouts it cannot run.
    pub fn new(graph: &Graph) -> R<Self> {
        let dev = Device::Cpu;
        let n = graph.tensors.len();
        let mut values: Vec<Option<Vec<f32>>> = graph.tensors.iter().map(|t| t.f32s()).collect();
        let rank: Vec<usize> = graph.tensors.iter().map(|t| t.shape.len()).collect();
        let shape = |i: usize| graph.tensors[i].shape.clone();
        let mut nodes = Vec::new();
        for (k, op) in graph.operators.iter().enumerate() {
            let ins: Vec<usize> = op
                .inputs
                .iter()
                .filter(|&&i| i >= 0)
                .map(|&i| i as usize)
                .collect();
            let out = *op
                .outputs
                .first()
                .ok_or(format!("operator {k} has no output"))? as usize;
            let konst = |i: usize| -> R<Vec<f32>> {
                values[i].clone().ok_or(format!(
                    "operator {k} ({:?}): input {} is not constant",
                    op.op, graph.tensors[i].name
                ))
            };
            let input = |j: usize| -> R<usize> {
                ins.get(j)
                    .copied()
                    .ok_or(format!("operator {k}: missing input {j}"))
            };
            let mut act = Activation::None;
            let step = match (&op.op, &op.options) {
                (Op::Dequantize | Op::Densify, _) => {
                    values[out] = Some(konst(input(0)?)?);
                    continue;
                }
                (
                    Op::Conv2d,
                    OpOptions::Conv {
                        padding,
                        stride,
                        dilation,
                        activation,
                    },
                ) => {
                    act = *activation;
                    let (xs, ws) = (shape(input(0)?), shape(input(1)?));
                    let [o, kh, kw, i] = ws[..] else {
                        return Err(format!("operator {k}: conv weights {ws:?}"));
                    };
                    let w =
                        Tensor::from_vec(konst(input(1)?)?, (o, kh, kw, i), &dev).map_err(ce)?;
                    let b = match ins.get(2) {
                        Some(&bi) => konst(bi)?,
                        None => vec![0.0; o],
                    };
                    if kh == 1 && kw == 1 && *stride == (1, 1) {
                        let w = w.reshape((o, i)).map_err(ce)?;
                        let b = Tensor::from_vec(b, (o, 1), &dev).map_err(ce)?;
                        Step::Conv1x1 { w, b }
                    } else {
                        if stride.0 != stride.1 || dilation.0 != dilation.1 {
                            return Err(format!("operator {k}: non-square stride"));
                        }
                        let (_, pt) = same::axis(xs[1], kh, stride.0, dilation.0, *padding);
                        let (_, pl) = same::axis(xs[2], kw, stride.1, dilation.1, *padding);
                        let os = shape(out);
                        let pb = ((os[1] - 1) * stride.0 + (kh - 1) * dilation.0 + 1)
                            .saturating_sub(xs[1] + pt);
                        let pr = ((os[2] - 1) * stride.1 + (kw - 1) * dilation.1 + 1)
                            .saturating_sub(xs[2] + pl);
                        let w = w
                            .permute((0, 3, 1, 2))
                            .and_then(|t| t.contiguous())
                            .map_err(ce)?;
                        let b = Tensor::from_vec(b, (1, o, 1, 1), &dev).map_err(ce)?;
                        Step::Conv {
                            w,
                            b,
                            stride: stride.0,
                            dilation: dilation.0,
                            pads: [pt, pb, pl, pr],
                        }
                    }
                }
                (
                    Op::DepthwiseConv2d,
                    OpOptions::Depthwise {
                        padding,
                        stride,
                        dilation,
                        multiplier,
                        activation,
                    },
                ) => {
                    act = *activation;
                    let (xs, ws) = (shape(input(0)?), shape(input(1)?));
                    let [1, kh, kw, oc] = ws[..] else {
                        return Err(format!("operator {k}: depthwise weights {ws:?}"));
                    };
                    let hwc = konst(input(1)?)?;
                    let mut weights = vec![0f32; oc * kh * kw];
                    for (j, v) in hwc.iter().enumerate() {
                        let (y, x, c) = (j / (kw * oc), (j / oc) % kw, j % oc);
                        weights[(c * kh + y) * kw + x] = *v;
                    }
                    let (oh, pt) = same::axis(xs[1], kh, stride.0, dilation.0, *padding);
                    let (ow, pl) = same::axis(xs[2], kw, stride.1, dilation.1, *padding);
                    Step::Depthwise(Depthwise {
                        weights,
                        bias: match ins.get(2) {
                            Some(&bi) => konst(bi)?,
                            None => vec![0.0; oc],
                        },
                        kernel: (kh, kw),
                        stride: *stride,
                        dilation: *dilation,
                        pad: (pt, pl),
                        out_size: (oh, ow),
                        multiplier: *multiplier,
                    })
                }
                (Op::Add, OpOptions::Add { activation }) => {
                    act = *activation;
                    Step::Add
                }
                (Op::Mul, OpOptions::Add { activation }) => {
                    act = *activation;
                    Step::Mul
                }
                (Op::Pad, _) => {
                    let p = graph.tensors[input(1)?]
                        .i32s()
                        .ok_or(format!("operator {k}: paddings not constant"))?;
                    let r = rank[input(0)?];
                    let mut pads = vec![(0, 0); r];
                    for d in 0..r {
                        let to = nchw_axis(d, r);
                        let (a, b) = (
                            p.get(2 * d).copied().unwrap_or(0),
                            p.get(2 * d + 1).copied().unwrap_or(0),
                        );
                        pads[to] = (a.max(0) as usize, b.max(0) as usize);
                    }
                    Step::Pad(pads)
                }
                (Op::Reshape, _) => Step::Reshape(shape(out)),
                (Op::Concatenation, OpOptions::Concat { axis, activation }) => {
                    act = *activation;
                    let r = rank[out] as i32;
                    let a = if *axis < 0 { axis + r } else { *axis } as usize;
                    Step::Concat(nchw_axis(a, r as usize))
                }
                (
                    Op::MaxPool2d,
                    OpOptions::Pool {
                        padding,
                        stride,
                        filter,
                        activation,
                    },
                ) => {
                    act = *activation;
                    let (xs, os) = (shape(input(0)?), shape(out));
                    let (_, pt) = same::axis(xs[1], filter.0, stride.0, 1, *padding);
                    let (_, pl) = same::axis(xs[2], filter.1, stride.1, 1, *padding);
                    let pb = ((os[1] - 1) * stride.0 + filter.0).saturating_sub(xs[1] + pt);
                    let pr = ((os[2] - 1) * stride.1 + filter.1).saturating_sub(xs[2] + pl);
                    Step::MaxPool {
                        k: *filter,
                        stride: *stride,
                        pads: [pt, pb, pl, pr],
                    }
                }
                (
                    Op::ResizeBilinear,
                    OpOptions::Resize {
                        align_corners,
                        half_pixel_centers,
                    },
                ) => {
                    let (xs, os) = (shape(input(0)?), shape(out));
                    let ry = resize_matrix(xs[1], os[1], *align_corners, *half_pixel_centers);
                    let rx = resize_matrix(xs[2], os[2], *align_corners, *half_pixel_centers);
                    let ry = Tensor::from_vec(ry, (os[1], xs[1]), &dev).map_err(ce)?;
                    let rxt = Tensor::from_vec(rx, (os[2], xs[2]), &dev)
                        .and_then(|t| t.t())
                        .and_then(|t| t.contiguous())
                        .map_err(ce)?;
                    Step::Resize { ry, rxt }
                }
                (Op::DepthToSpace, OpOptions::DepthToSpace { block }) => Step::DepthToSpace(*block),
                (
                    Op::AveragePool2d,
                    OpOptions::Pool {
                        stride,
                        filter,
                        activation,
                        ..
                    },
                ) => {
                    act = *activation;
                    let (xs, os) = (shape(input(0)?), shape(out));
                    // Only unpadded pools: TFLite's SAME average excludes the
                    // padding from the count, which candle cannot express.
                    if (os[1] - 1) * stride.0 + filter.0 != xs[1]
                        || (os[2] - 1) * stride.1 + filter.1 != xs[2]
                    {
                        return Err(format!("operator {k}: padded average pool"));
                    }
                    Step::AvgPool {
                        k: *filter,
                        stride: *stride,
                    }
                }
                (Op::Custom, _) => {
                    // Inputs: activations, weights [o, kh, kw, i], bias [o].
                    let (xs, ws, os) = (shape(input(0)?), shape(input(1)?), shape(out));
                    let [o, kh, kw, i] = ws[..] else {
                        return Err(format!("operator {k}: custom op weights {ws:?}"));
                    };
                    if kh != kw || os[1] != xs[1] * kh || os[2] != xs[2] * kw || xs[3] != i {
                        return Err(format!(
                            "operator {k}: custom op {xs:?} x {ws:?} -> {os:?} is not a \
                             non-overlapping transposed convolution"
                        ));
                    }
                    let wv = konst(input(1)?)?;
                    // Rows ordered (dy, dx, o), the channel order depth-to-space reads.
                    let mut m = vec![0f32; kh * kw * o * i];
                    for oc in 0..o {
                        for dy in 0..kh {
                            for dx in 0..kw {
                                let row = (dy * kw + dx) * o + oc;
                                let src = ((oc * kh + dy) * kw + dx) * i;
                                m[row * i..(row + 1) * i].copy_from_slice(&wv[src..src + i]);
                            }
                        }
                    }
                    let b = match ins.get(2) {
                        Some(&bi) => konst(bi)?,
                        None => vec![0.0; o],
                    };
                    Step::TransposeConv {
                        w: Tensor::from_vec(m, (kh * kw * o, i), &dev).map_err(ce)?,
                        b: Tensor::from_vec(b, (1, o, 1, 1), &dev).map_err(ce)?,
                        block: kh,
                    }
                }
                (Op::HardSwish, _) => Step::HardSwish,
                (Op::Logistic, _) => Step::Logistic,
                (Op::Relu, _) => Step::Relu,
                (Op::Relu6, _) => Step::Relu6,
                (other, _) => return Err(format!("operator {k}: {other:?} is not supported")),
            };
            nodes.push(Node {
                step,
                inputs: ins,
                output: out,
                act,
            });
        }
        let mut consts = vec![None; n];
        for (i, v) in values.into_iter().enumerate() {
            if let Some(v) = v {
                let s = &graph.tensors[i].shape;
                let t = Tensor::from_vec(v, s.clone(), &dev).map_err(ce)?;
                consts[i] = Some(if s.len() == 4 {
                    t.permute((0, 3, 1, 2)).map_err(ce)?
                } else {
                    t
                });
            }
        }
        let input = *graph.inputs.first().ok_or("graph has no input")?;
        Ok(Self {
            nodes,
            consts,
            rank,
            input,
            input_shape: graph.tensors[input].shape.clone(),
            outputs: graph.outputs.clone(),
        })
    }

    /// Runs the graph on an NHWC input; returns every graph output flattened
    /// in TFLite (NHWC) order.
    pub fn run(&self, input: &[f32]) -> R<Vec<Vec<f32>>> {
        let mut vals: Vec<Option<Tensor>> = self.consts.clone();
        let x = Tensor::from_slice(input, self.input_shape.clone(), &Device::Cpu).map_err(ce)?;
        vals[self.input] = Some(
            x.permute((0, 3, 1, 2))
                .and_then(|t| t.contiguous())
                .map_err(ce)?,
        );
        for (k, node) in self.nodes.iter().enumerate() {
            let get = |j: usize| -> R<&Tensor> {
                node.inputs
                    .get(j)
                    .and_then(|&i| vals[i].as_ref())
                    .ok_or(format!("node {k}: input {j} not computed"))
            };
            let y = self
                .step(node, &get, k)
                .map_err(|e| format!("node {k}: {e}"))?;
            let y = match node.act {
                Activation::None => y,
                Activation::Relu => y.relu().map_err(ce)?,
                Activation::Relu6 => y.clamp(0f32, 6f32).map_err(ce)?,
                Activation::ReluN1To1 => y.clamp(-1f32, 1f32).map_err(ce)?,
                Activation::Tanh => y.tanh().map_err(ce)?,
            };
            vals[node.output] = Some(y);
        }
        self.outputs
            .iter()
            .map(|&o| {
                let t = vals[o].as_ref().ok_or("output not computed")?;
                let t = if self.rank[o] == 4 {
                    t.permute((0, 2, 3, 1)).map_err(ce)?
                } else {
                    t.clone()
                };
                t.flatten_all().and_then(|t| t.to_vec1::<f32>()).map_err(ce)
            })
            .collect()
    }

    fn step<'a>(&self, node: &Node, get: &dyn Fn(usize) -> R<&'a Tensor>, _k: usize) -> R<Tensor> {
        let x = get(0)?;
        let r = match &node.step {
            Step::Conv1x1 { w, b } => {
                let (_, c, h, wd) = x.dims4().map_err(ce)?;
                let y = w.matmul(&x.reshape((c, h * wd)).map_err(ce)?).map_err(ce)?;
                let o = w.dim(0).map_err(ce)?;
                y.broadcast_add(b).and_then(|y| y.reshape((1, o, h, wd)))
            }
            Step::Conv {
                w,
                b,
                stride,
                dilation,
                pads,
            } => x
                .pad_with_zeros(2, pads[0], pads[1])
                .and_then(|x| x.pad_with_zeros(3, pads[2], pads[3]))
                .and_then(|x| x.conv2d(w, 0, *stride, *dilation, 1))
                .and_then(|y| y.broadcast_add(b)),
            Step::Depthwise(op) => x.contiguous().and_then(|x| x.apply_op1_no_bwd(op)),
            Step::Add => x.broadcast_add(get(1)?),
            Step::Mul => x.broadcast_mul(get(1)?),
            Step::Pad(pads) => {
                let mut y = x.clone();
                for (d, &(a, b)) in pads.iter().enumerate() {
                    if a + b > 0 {
                        y = y.pad_with_zeros(d, a, b).map_err(ce)?;
                    }
                }
                Ok(y)
            }
            Step::Reshape(shape) => {
                let src = if x.rank() == 4 {
                    x.permute((0, 2, 3, 1))
                        .and_then(|t| t.contiguous())
                        .map_err(ce)?
                } else {
                    x.clone()
                };
                let y = src.reshape(shape.clone()).map_err(ce)?;
                if shape.len() == 4 {
                    y.permute((0, 3, 1, 2))
                } else {
                    Ok(y)
                }
            }
            Step::Concat(axis) => {
                let xs: Vec<&Tensor> = (0..node.inputs.len()).map(get).collect::<R<_>>()?;
                Tensor::cat(&xs, *axis)
            }
            Step::MaxPool { k, stride, pads } => x
                .pad_with_same(2, pads[0], pads[1])
                .and_then(|x| x.pad_with_same(3, pads[2], pads[3]))
                .and_then(|x| x.max_pool2d_with_stride(*k, *stride)),
            Step::Resize { ry, rxt } => x
                .broadcast_matmul(rxt)
                .and_then(|y| ry.broadcast_matmul(&y)),
            Step::DepthToSpace(b) => {
                let (n, c, h, w) = x.dims4().map_err(ce)?;
                let co = c / (b * b);
                x.reshape((n, *b, *b, co, h, w))
                    .and_then(|t| t.permute((0, 3, 4, 1, 5, 2)))
                    .and_then(|t| t.reshape((n, co, h * b, w * b)))
            }
            Step::AvgPool { k, stride } => x.avg_pool2d_with_stride(*k, *stride),
            Step::TransposeConv { w, b, block } => {
                let (n, c, h, wd) = x.dims4().map_err(ce)?;
                let y = w.matmul(&x.reshape((c, h * wd)).map_err(ce)?).map_err(ce)?;
                let co = w.dim(0).map_err(ce)? / (block * block);
                y.reshape((n, *block, *block, co, h, wd))
                    .and_then(|t| t.permute((0, 3, 4, 1, 5, 2)))
                    .and_then(|t| t.reshape((n, co, h * block, wd * block)))
                    .and_then(|t| t.broadcast_add(b))
            }
            // x * relu6(x + 3) / 6
            Step::HardSwish => (x + 3.0)
                .and_then(|t| t.clamp(0f32, 6f32))
                .and_then(|t| t * (1.0 / 6.0))
                .and_then(|t| t.mul(x)),
            Step::Logistic => x
                .neg()
                .and_then(|t| t.exp())
                .and_then(|t| t + 1.0)
                .and_then(|t| t.recip()),
            Step::Relu => x.relu(),
            Step::Relu6 => x.clamp(0f32, 6f32),
        };
        r.map_err(ce)
    }
}
