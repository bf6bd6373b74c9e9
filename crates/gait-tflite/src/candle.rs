//! Runs a TFLite graph on candle (CPU), op by op, in TFLite's own NHWC layout
//! (no transposes). The heavy operators are our kernels on contiguous
//! slices (`kernels`), run as candle custom ops with their weights packed
//! once here and their activations fused.

use candle_core::{Device, Tensor};

use crate::kernels::conv::Conv;
use crate::kernels::depthwise::Depthwise;
use crate::kernels::eltwise::{self, Binary, Unary};
use crate::kernels::pool::Pool;
use crate::kernels::resize::{self, Resize};
use crate::kernels::{act, apply1, apply2, pad};
use crate::model::{Activation, Graph, Op, OpOptions};
use crate::same;

type R<T> = Result<T, String>;

fn ce(e: candle_core::Error) -> String {
    e.to_string()
}

enum Step {
    Conv(Conv),
    Depthwise(Depthwise),
    Binary(Binary),
    /// Per axis (before, after).
    Pad(Vec<(usize, usize)>),
    Reshape(Vec<usize>),
    Concat(usize),
    Pool(Pool),
    Resize(Resize),
    DepthToSpace(usize),
    /// MediaPipe's `Convolution2DTransposeBias` where kernel == stride (no
    /// overlap): a 1x1 conv to `block^2 * o` channels, then depth-to-space.
    TransposeConv(Conv, usize),
    Unary(Unary),
}

impl Step {
    /// Whether the step applies the node's activation itself.
    fn fuses_activation(&self) -> bool {
        matches!(
            self,
            Step::Conv(_) | Step::Depthwise(_) | Step::Pool(_) | Step::Binary(_)
        )
    }
}

struct Node {
    step: Step,
    inputs: Vec<usize>,
    output: usize,
    act: Activation,
    /// Computed values no later node reads: dropped right after this node, so
    /// the allocator reuses their memory instead of mapping fresh pages.
    last_use: Vec<usize>,
}

/// A TFLite graph compiled to candle operations.
pub struct CandleGraph {
    nodes: Vec<Node>,
    consts: Vec<Option<Tensor>>,
    input: usize,
    input_shape: Vec<usize>,
    outputs: Vec<usize>,
}

/// Padding before the first row/column of a SAME/VALID window.
fn pad_before(input: usize, k: usize, s: usize, d: usize, p: crate::Padding) -> usize {
    same::axis(input, k, s, d, p).1
}

impl CandleGraph {
    /// Compiles `graph`; fails on operators or layouts it cannot run.
    pub fn new(graph: &Graph) -> R<Self> {
        let dev = Device::Cpu;
        let n = graph.tensors.len();
        let mut values: Vec<Option<Vec<f32>>> = graph.tensors.iter().map(|t| t.f32s()).collect();
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
            let bias = |o: usize| -> R<Vec<f32>> {
                match ins.get(2) {
                    Some(&bi) => konst(bi),
                    None => Ok(vec![0.0; o]),
                }
            };
            let four = |v: Vec<usize>, what: &str| -> R<[usize; 4]> {
                v.clone()
                    .try_into()
                    .map_err(|_| format!("operator {k}: {what} {v:?} is not 4-D"))
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
                    let xs = four(shape(input(0)?), "input")?;
                    let ws = four(shape(input(1)?), "weights")?;
                    let os = four(shape(out), "output")?;
                    let [o, kh, kw, _] = ws;
                    let mut conv = Conv::new(&konst(input(1)?)?, ws, bias(o)?, act)
                        .map_err(|e| format!("operator {k}: {e}"))?;
                    conv.stride = *stride;
                    conv.dilation = *dilation;
                    conv.pad = (
                        pad_before(xs[1], kh, stride.0, dilation.0, *padding),
                        pad_before(xs[2], kw, stride.1, dilation.1, *padding),
                    );
                    conv.out_size = (os[1], os[2]);
                    Step::Conv(conv)
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
                    let xs = four(shape(input(0)?), "input")?;
                    let [_, kh, kw, oc] = four(shape(input(1)?), "weights")?;
                    let os = four(shape(out), "output")?;
                    Step::Depthwise(Depthwise {
                        weights: konst(input(1)?)?,
                        bias: bias(oc)?,
                        kernel: (kh, kw),
                        stride: *stride,
                        dilation: *dilation,
                        pad: (
                            pad_before(xs[1], kh, stride.0, dilation.0, *padding),
                            pad_before(xs[2], kw, stride.1, dilation.1, *padding),
                        ),
                        out_size: (os[1], os[2]),
                        multiplier: *multiplier,
                        act,
                    })
                }
                (Op::Add, OpOptions::Add { activation }) => {
                    act = *activation;
                    Step::Binary(Binary::Add)
                }
                (Op::Mul, OpOptions::Add { activation }) => {
                    act = *activation;
                    Step::Binary(Binary::Mul)
                }
                (Op::Pad, _) => {
                    let p = graph.tensors[input(1)?]
                        .i32s()
                        .ok_or(format!("operator {k}: paddings not constant"))?;
                    let pads = (0..graph.tensors[input(0)?].shape.len())
                        .map(|d| {
                            let at = |i: usize| p.get(i).copied().unwrap_or(0).max(0) as usize;
                            (at(2 * d), at(2 * d + 1))
                        })
                        .collect();
                    Step::Pad(pads)
                }
                (Op::Reshape, _) => Step::Reshape(shape(out)),
                (Op::Concatenation, OpOptions::Concat { axis, activation }) => {
                    act = *activation;
                    let r = shape(out).len() as i32;
                    Step::Concat(if *axis < 0 { axis + r } else { *axis } as usize)
                }
                (
                    Op::MaxPool2d | Op::AveragePool2d,
                    OpOptions::Pool {
                        padding,
                        stride,
                        filter,
                        activation,
                    },
                ) => {
                    act = *activation;
                    let xs = four(shape(input(0)?), "input")?;
                    let os = four(shape(out), "output")?;
                    Step::Pool(Pool {
                        max: op.op == Op::MaxPool2d,
                        filter: *filter,
                        stride: *stride,
                        pad: (
                            pad_before(xs[1], filter.0, stride.0, 1, *padding),
                            pad_before(xs[2], filter.1, stride.1, 1, *padding),
                        ),
                        out_size: (os[1], os[2]),
                        act,
                    })
                }
                (
                    Op::ResizeBilinear,
                    OpOptions::Resize {
                        align_corners,
                        half_pixel_centers,
                    },
                ) => {
                    let xs = four(shape(input(0)?), "input")?;
                    let os = four(shape(out), "output")?;
                    let (a, h) = (*align_corners, *half_pixel_centers);
                    Step::Resize(Resize {
                        ys: resize::taps(xs[1], os[1], a, h),
                        xs: resize::taps(xs[2], os[2], a, h),
                    })
                }
                (Op::DepthToSpace, OpOptions::DepthToSpace { block }) => Step::DepthToSpace(*block),
                (Op::Custom, _) => {
                    // Inputs: activations, weights [o, kh, kw, i], bias [o].
                    let (xs, ws, os) = (shape(input(0)?), shape(input(1)?), shape(out));
                    let [o, kh, kw, i] = ws[..] else {
                        return Err(format!("operator {k}: custom op weights {ws:?}"));
                    };
                    if xs.len() != 4
                        || os.len() != 4
                        || kh != kw
                        || os[1] != xs[1] * kh
                        || os[2] != xs[2] * kw
                        || xs[3] != i
                    {
                        return Err(format!(
                            "operator {k}: custom op {xs:?} x {ws:?} -> {os:?} is not a \
                             non-overlapping transposed convolution"
                        ));
                    }
                    let wv = konst(input(1)?)?;
                    let b = bias(o)?;
                    if wv.len() != o * kh * kw * i || b.len() != o {
                        return Err(format!("operator {k}: custom op weights or bias size"));
                    }
                    // [i, (dy, dx, o)]: the channel order depth-to-space reads.
                    let cols = kh * kw * o;
                    let mut m = vec![0f32; i * cols];
                    let mut tiled = vec![0f32; cols];
                    for (oc, &bo) in b.iter().enumerate() {
                        for dy in 0..kh {
                            for dx in 0..kw {
                                let col = (dy * kw + dx) * o + oc;
                                let src = ((oc * kh + dy) * kw + dx) * i;
                                for (ic, v) in wv[src..src + i].iter().enumerate() {
                                    m[ic * cols + col] = *v;
                                }
                                tiled[col] = bo;
                            }
                        }
                    }
                    Step::TransposeConv(Conv::pointwise(m, i, tiled, Activation::None), kh)
                }
                (Op::HardSwish, _) => Step::Unary(Unary::HardSwish),
                (Op::Logistic, _) => Step::Unary(Unary::Logistic),
                (Op::Relu, _) => Step::Unary(Unary::Relu),
                (Op::Relu6, _) => Step::Unary(Unary::Relu6),
                (other, _) => return Err(format!("operator {k}: {other:?} is not supported")),
            };
            nodes.push(Node {
                step,
                inputs: ins,
                output: out,
                act,
                last_use: Vec::new(),
            });
        }
        let mut consts = vec![None; n];
        for (i, v) in values.into_iter().enumerate() {
            if let Some(v) = v {
                let s = &graph.tensors[i].shape;
                consts[i] = Some(Tensor::from_vec(v, s.clone(), &dev).map_err(ce)?);
            }
        }
        let input = *graph.inputs.first().ok_or("graph has no input")?;
        let mut seen = vec![false; n];
        for &o in &graph.outputs {
            seen[o] = true;
        }
        for node in nodes.iter_mut().rev() {
            for &i in &node.inputs {
                if consts[i].is_none() && !seen[i] {
                    seen[i] = true;
                    node.last_use.push(i);
                }
            }
        }
        Ok(Self {
            nodes,
            consts,
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
        vals[self.input] = Some(x);
        for (k, node) in self.nodes.iter().enumerate() {
            let get = |j: usize| -> R<&Tensor> {
                node.inputs
                    .get(j)
                    .and_then(|&i| vals[i].as_ref())
                    .ok_or(format!("node {k}: input {j} not computed"))
            };
            let mut y = step(node, &get).map_err(|e| format!("node {k}: {e}"))?;
            if node.act != Activation::None && !node.step.fuses_activation() {
                let a = node.act;
                y = apply1(&y, "activation", &|v, d| {
                    let mut v = v.to_vec();
                    act::apply(a, &mut v);
                    Ok((v, d.into()))
                })
                .map_err(ce)?;
            }
            vals[node.output] = Some(y);
            for &i in &node.last_use {
                vals[i] = None;
            }
        }
        self.outputs
            .iter()
            .map(|&o| {
                let t = vals[o].as_ref().ok_or("output not computed")?;
                t.flatten_all().and_then(|t| t.to_vec1::<f32>()).map_err(ce)
            })
            .collect()
    }
}

/// NHWC depth-to-space: [1, h, w, b*b*c] -> [1, h*b, w*b, c].
fn depth_to_space(x: &Tensor, b: usize) -> candle_core::Result<Tensor> {
    let (n, h, w, c) = x.dims4()?;
    let co = c / (b * b);
    x.reshape((n * h, w, b, b * co))?
        .permute((0, 2, 1, 3))?
        .reshape((n, h * b, w * b, co))
}

fn step<'a>(node: &Node, get: &dyn Fn(usize) -> R<&'a Tensor>) -> R<Tensor> {
    let x = get(0)?;
    let act = node.act;
    let r = match &node.step {
        Step::Conv(c) => apply1(x, "conv2d", &|v, d| c.run(v, d)),
        Step::Depthwise(c) => apply1(x, "depthwise-conv2d", &|v, d| c.run(v, d)),
        Step::Pool(p) => apply1(x, "pool", &|v, d| p.run(v, d)),
        Step::Resize(r) => apply1(x, "resize-bilinear", &|v, d| r.run(v, d)),
        Step::Unary(u) => apply1(x, "activation", &|v, d| eltwise::unary(*u, v, d)),
        Step::Binary(op) => {
            let (mut a, mut b) = (x, get(1)?);
            if !eltwise::fits(a.dims(), b.dims()) {
                (a, b) = (b, a);
            }
            if eltwise::fits(a.dims(), b.dims()) {
                apply2(a, b, "binary", &|av, ad, bv, bd| {
                    eltwise::binary(*op, act, av, ad, bv, bd)
                })
            } else {
                // General broadcasting: candle's op, then the activation.
                let y = match op {
                    Binary::Add => a.broadcast_add(b),
                    Binary::Mul => a.broadcast_mul(b),
                }
                .map_err(ce)?;
                apply1(&y, "activation", &|v, d| {
                    let mut v = v.to_vec();
                    act::apply(act, &mut v);
                    Ok((v, d.into()))
                })
            }
        }
        Step::Pad(pads) => apply1(x, "pad", &|v, d| pad::pad(v, d, pads)),
        Step::Reshape(shape) => x.reshape(shape.clone()),
        Step::Concat(axis) => {
            let xs: Vec<&Tensor> = (0..node.inputs.len()).map(get).collect::<R<_>>()?;
            Tensor::cat(&xs, *axis)
        }
        Step::DepthToSpace(b) => depth_to_space(x, *b),
        Step::TransposeConv(c, block) => apply1(x, "transpose-conv", &|v, d| c.run(v, d))
            .and_then(|y| depth_to_space(&y, *block)),
    };
    r.map_err(ce)
}
