//! The operations a compiled graph runs, and running one of them on candle tensors.

use candle_core::Tensor;

use super::{R, ce};
use crate::kernels::conv::Conv;
use crate::kernels::depthwise::Depthwise;
use crate::kernels::eltwise::{self, Binary, Unary};
use crate::kernels::pool::Pool;
use crate::kernels::resize::Resize;
use crate::kernels::{act, apply1, apply2, pad};
use crate::model::Activation;

pub(super) enum Step {
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
    pub(super) fn fuses_activation(&self) -> bool {
        matches!(
            self,
            Step::Conv(_) | Step::Depthwise(_) | Step::Pool(_) | Step::Binary(_)
        )
    }
}

pub(super) struct Node {
    pub(super) step: Step,
    pub(super) inputs: Vec<usize>,
    pub(super) output: usize,
    pub(super) act: Activation,
    /// Computed values no later node reads: dropped right after this node, so
    /// the allocator reuses their memory instead of mapping fresh pages.
    pub(super) last_use: Vec<usize>,
}

/// NHWC depth-to-space: [1, h, w, b*b*c] -> [1, h*b, w*b, c].
fn depth_to_space(x: &Tensor, b: usize) -> candle_core::Result<Tensor> {
    let (n, h, w, c) = x.dims4()?;
    let co = c / (b * b);
    x.reshape((n * h, w, b, b * co))?
        .permute((0, 2, 1, 3))?
        .reshape((n, h * b, w * b, co))
}

/// Runs one node on its inputs (`get(j)`: input `j`).
pub(super) fn run<'a>(node: &Node, get: &dyn Fn(usize) -> R<&'a Tensor>) -> R<Tensor> {
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
