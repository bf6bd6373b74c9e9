//! Compiles a TFLite graph's operators into [`Node`]s: weights packed for our kernels,
//! window geometry worked out once, constant-producing operators folded away.

use super::R;
use super::step::{Node, Step};
use crate::kernels::conv::Conv;
use crate::kernels::depthwise::Depthwise;
use crate::kernels::eltwise::{Binary, Unary};
use crate::kernels::pool::Pool;
use crate::kernels::resize::{self, Resize};
use crate::model::{Activation, Graph, Op, OpOptions, Operator, Padding};
use crate::operator_io::{ConvParams, OpIo};
use crate::same;

/// Every tensor's constant value, `None` for activations.
pub(super) type Constants = Vec<Option<Vec<f32>>>;

/// The graph's nodes in order, and every tensor's constant value (those dequantized or
/// densified by an operator included).
pub(super) fn nodes(graph: &Graph) -> R<(Vec<Node>, Constants)> {
    let mut c = Compiler {
        graph,
        values: graph.tensors.iter().map(|t| t.f32s()).collect(),
    };
    let mut nodes = Vec::new();
    for (k, op) in graph.operators.iter().enumerate() {
        let io = OpIo::new(k, op)?;
        if matches!(op.op, Op::Dequantize | Op::Densify) {
            let v = c.constant(&io, io.input(0)?)?;
            graph.tensors[io.out].holds(v.len())?;
            c.values[io.out] = Some(v);
            continue;
        }
        let (step, act) = c.step(&io, op)?;
        nodes.push(Node {
            step,
            inputs: io.ins,
            output: io.out,
            act,
            last_use: Vec::new(),
        });
    }
    Ok((nodes, c.values))
}

/// A convolution's or pooling's stride, dilation and padding rule.
#[derive(Clone, Copy)]
struct Window {
    padding: Padding,
    stride: (usize, usize),
    dilation: (usize, usize),
}

impl Window {
    /// Padding before the first row and column, for an NHWC input of `xs`.
    fn pad_before(&self, xs: [usize; 4], kernel: (usize, usize)) -> R<(usize, usize)> {
        let (s, d, p) = (self.stride, self.dilation, self.padding);
        Ok((
            same::axis(xs[1], kernel.0, s.0, d.0, p)?.1,
            same::axis(xs[2], kernel.1, s.1, d.1, p)?.1,
        ))
    }
}

struct Compiler<'g> {
    graph: &'g Graph,
    values: Constants,
}

impl Compiler<'_> {
    fn constant(&self, io: &OpIo, i: usize) -> R<Vec<f32>> {
        self.values[i].clone().ok_or(format!(
            "operator {} ({:?}): input {} is not constant",
            io.k, io.op.op, self.graph.tensors[i].name
        ))
    }

    fn shape(&self, i: usize) -> &[usize] {
        &self.graph.tensors[i].shape
    }

    fn four(&self, io: &OpIo, i: usize, what: &str) -> R<[usize; 4]> {
        let v = self.shape(i);
        v.try_into()
            .map_err(|_| format!("operator {}: {what} {v:?} is not 4-D", io.k))
    }

    /// The operator's bias (input 2), zeros when it has none.
    fn bias(&self, io: &OpIo, o: usize) -> R<Vec<f32>> {
        match io.ins.get(2) {
            Some(&bi) => self.constant(io, bi),
            None => Ok(vec![0.0; o]),
        }
    }

    /// The node of one operator, with the activation it is fused with.
    fn step(&self, io: &OpIo, op: &Operator) -> R<(Step, Activation)> {
        let none = Activation::None;
        Ok(match (&op.op, &op.options) {
            (Op::Conv2d | Op::DepthwiseConv2d, o) => {
                let c =
                    ConvParams::of(o).ok_or(format!("operator {}: convolution options", io.k))?;
                let w = Window {
                    padding: c.padding,
                    stride: c.stride,
                    dilation: c.dilation,
                };
                let step = match op.op {
                    Op::Conv2d => Step::Conv(self.conv(io, w, c.activation)?),
                    _ => Step::Depthwise(self.depthwise(io, w, c.multiplier, c.activation)?),
                };
                (step, c.activation)
            }
            (Op::Add, OpOptions::Add { activation }) => (Step::Binary(Binary::Add), *activation),
            (Op::Mul, OpOptions::Add { activation }) => (Step::Binary(Binary::Mul), *activation),
            (Op::Pad, _) => (self.pad(io)?, none),
            (Op::Reshape, _) => (Step::Reshape(self.shape(io.out).to_vec()), none),
            (Op::Concatenation, OpOptions::Concat { axis, activation }) => {
                (self.concat(io, *axis)?, *activation)
            }
            (
                Op::MaxPool2d | Op::AveragePool2d,
                &OpOptions::Pool {
                    padding,
                    stride,
                    filter,
                    activation,
                },
            ) => {
                let w = Window {
                    padding,
                    stride,
                    dilation: (1, 1),
                };
                (
                    Step::Pool(self.pool(io, w, filter, activation)?),
                    activation,
                )
            }
            (
                Op::ResizeBilinear,
                &OpOptions::Resize {
                    align_corners,
                    half_pixel_centers,
                },
            ) => (self.resize(io, align_corners, half_pixel_centers)?, none),
            (Op::DepthToSpace, OpOptions::DepthToSpace { block }) => {
                (Step::DepthToSpace(*block), none)
            }
            (Op::Custom, _) => (self.transpose_conv(io)?, none),
            (Op::HardSwish, _) => (Step::Unary(Unary::HardSwish), none),
            (Op::Logistic, _) => (Step::Unary(Unary::Logistic), none),
            (Op::Relu, _) => (Step::Unary(Unary::Relu), none),
            (Op::Relu6, _) => (Step::Unary(Unary::Relu6), none),
            (other, _) => return Err(format!("operator {}: {other:?} is not supported", io.k)),
        })
    }

    fn conv(&self, io: &OpIo, w: Window, activation: Activation) -> R<Conv> {
        let xs = self.four(io, io.input(0)?, "input")?;
        let ws = self.four(io, io.input(1)?, "weights")?;
        let os = self.four(io, io.out, "output")?;
        let [o, kh, kw, _] = ws;
        let mut conv = Conv::new(
            &self.constant(io, io.input(1)?)?,
            ws,
            self.bias(io, o)?,
            activation,
        )
        .map_err(|e| format!("operator {}: {e}", io.k))?;
        conv.stride = w.stride;
        conv.dilation = w.dilation;
        conv.pad = w.pad_before(xs, (kh, kw))?;
        conv.out_size = (os[1], os[2]);
        Ok(conv)
    }

    fn depthwise(&self, io: &OpIo, w: Window, multiplier: usize, act: Activation) -> R<Depthwise> {
        let xs = self.four(io, io.input(0)?, "input")?;
        let [_, kh, kw, oc] = self.four(io, io.input(1)?, "weights")?;
        let os = self.four(io, io.out, "output")?;
        Ok(Depthwise {
            weights: self.constant(io, io.input(1)?)?,
            bias: self.bias(io, oc)?,
            kernel: (kh, kw),
            stride: w.stride,
            dilation: w.dilation,
            pad: w.pad_before(xs, (kh, kw))?,
            out_size: (os[1], os[2]),
            multiplier,
            act,
        })
    }

    fn pool(&self, io: &OpIo, w: Window, filter: (usize, usize), act: Activation) -> R<Pool> {
        let xs = self.four(io, io.input(0)?, "input")?;
        let os = self.four(io, io.out, "output")?;
        Ok(Pool {
            max: io.op.op == Op::MaxPool2d,
            filter,
            stride: w.stride,
            pad: w.pad_before(xs, filter)?,
            out_size: (os[1], os[2]),
            act,
        })
    }

    fn pad(&self, io: &OpIo) -> R<Step> {
        let p = self.graph.tensors[io.input(1)?]
            .i32s()
            .ok_or(format!("operator {}: paddings not constant", io.k))?;
        let at = |i: usize| p.get(i).copied().unwrap_or(0).max(0) as usize;
        let rank = self.shape(io.input(0)?).len();
        Ok(Step::Pad(
            (0..rank).map(|d| (at(2 * d), at(2 * d + 1))).collect(),
        ))
    }

    fn concat(&self, io: &OpIo, axis: i32) -> R<Step> {
        let r = self.shape(io.out).len() as i64;
        let a = if axis < 0 {
            axis as i64 + r
        } else {
            axis as i64
        };
        if a < 0 || a >= r {
            return Err(format!("operator {}: axis {axis} of a {r}-D output", io.k));
        }
        Ok(Step::Concat(a as usize))
    }

    fn resize(&self, io: &OpIo, a: bool, h: bool) -> R<Step> {
        let xs = self.four(io, io.input(0)?, "input")?;
        let os = self.four(io, io.out, "output")?;
        Ok(Step::Resize(Resize {
            ys: resize::taps(xs[1], os[1], a, h),
            xs: resize::taps(xs[2], os[2], a, h),
        }))
    }

    /// MediaPipe's `Convolution2DTransposeBias`, where kernel == stride: inputs are the
    /// activations, weights [o, kh, kw, i] and bias [o].
    fn transpose_conv(&self, io: &OpIo) -> R<Step> {
        let (xs, ws, os) = (
            self.shape(io.input(0)?),
            self.shape(io.input(1)?),
            self.shape(io.out),
        );
        let [o, kh, kw, i] = ws[..] else {
            return Err(format!("operator {}: custom op weights {ws:?}", io.k));
        };
        if xs.len() != 4
            || os.len() != 4
            || kh != kw
            || Some(os[1]) != xs[1].checked_mul(kh)
            || Some(os[2]) != xs[2].checked_mul(kw)
            || xs[3] != i
        {
            return Err(format!(
                "operator {}: custom op {xs:?} x {ws:?} -> {os:?} is not a \
                 non-overlapping transposed convolution",
                io.k
            ));
        }
        let wv = self.constant(io, io.input(1)?)?;
        let b = self.bias(io, o)?;
        if wv.len() != o * kh * kw * i || b.len() != o {
            return Err(format!("operator {}: custom op weights or bias size", io.k));
        }
        let (m, tiled) = depth_to_space_weights(&wv, &b, [o, kh, kw, i]);
        Ok(Step::TransposeConv(
            Conv::pointwise(m, i, tiled, Activation::None),
            kh,
        ))
    }
}

/// Transposed-convolution weights as a 1x1 convolution's `[i, (dy, dx, o)]` matrix (the
/// channel order depth-to-space reads) and its bias tiled the same way.
fn depth_to_space_weights(
    wv: &[f32],
    b: &[f32],
    [o, kh, kw, i]: [usize; 4],
) -> (Vec<f32>, Vec<f32>) {
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
    (m, tiled)
}
