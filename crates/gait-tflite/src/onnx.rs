//! Writes a TFLite graph as an ONNX model (opset 13), encoding the protobuf
//! by hand. Activations are NCHW inside; the input is taken NHWC and 4-D
//! outputs are given back NHWC, like the TFLite model.

mod builder;
mod proto;

use builder::Builder;
use proto::{Attr, Pb, f32_tensor, i64_tensor, value_info};

use crate::model::{Activation, Graph, Op, OpOptions, Operator, Padding, Tensor};
use crate::operator_io::{ConvParams, OpIo};
use crate::same::{self, nchw_axis};

type R<T> = Result<T, String>;

/// The ONNX model bytes of `graph`.
pub fn to_onnx(graph: &Graph) -> R<Vec<u8>> {
    let mut e = Exporter {
        b: Builder::new(),
        t: &graph.tensors,
        konst: graph.tensors.iter().map(|t| t.f32s()).collect(),
    };
    e.input(graph)?;
    for (k, op) in graph.operators.iter().enumerate() {
        let io = Io {
            op: OpIo::new(k, op)?,
            pre: e.b.fresh("pre"),
        };
        e.operator(&io, op)?;
    }
    e.outputs(graph);
    Ok(e.model())
}

/// One operator's tensors, and the name of its value before the fused activation.
struct Io<'o> {
    op: OpIo<'o>,
    pre: String,
}

impl<'o> std::ops::Deref for Io<'o> {
    type Target = OpIo<'o>;
    fn deref(&self) -> &OpIo<'o> {
        &self.op
    }
}

/// The ONNX name of TFLite tensor `i`.
fn name(i: usize) -> String {
    format!("t{i}")
}

/// A 2-D convolution's or pooling's window.
struct Window {
    kernel: (usize, usize),
    stride: (usize, usize),
    dilation: (usize, usize),
    padding: Padding,
}

struct Exporter<'g> {
    b: Builder,
    t: &'g [Tensor],
    /// Constant values, including those dequantized or densified by earlier operators.
    konst: Vec<Option<Vec<f32>>>,
}

impl Exporter<'_> {
    fn constant(&self, io: &Io, i: usize) -> R<&[f32]> {
        self.konst[i]
            .as_deref()
            .ok_or(format!("operator {}: input {i} not constant", io.k))
    }

    fn shape4(&self, io: &Io, i: usize, what: &str) -> R<[usize; 4]> {
        let s = &self.t[i].shape;
        s[..]
            .try_into()
            .map_err(|_| format!("operator {}: {what} {s:?} is not 4-D", io.k))
    }

    /// The graph input, NHWC, transposed to NCHW.
    fn input(&mut self, graph: &Graph) -> R<()> {
        let input = *graph.inputs.first().ok_or("graph has no input")?;
        self.b
            .graph
            .msg(11, value_info("input", &self.t[input].shape));
        self.b.node(
            "Transpose",
            &["input"],
            &name(input),
            vec![("perm", Attr::Ints(vec![0, 3, 1, 2]))],
        );
        Ok(())
    }

    fn operator(&mut self, io: &Io, op: &Operator) -> R<()> {
        let k = io.k;
        match (&op.op, &op.options) {
            (Op::Dequantize | Op::Densify, _) => {
                let v = self.constant(io, io.input(0)?)?.to_vec();
                self.t[io.out].holds(v.len())?;
                self.konst[io.out] = Some(v);
            }
            (Op::Conv2d | Op::DepthwiseConv2d, o) => {
                let c = ConvParams::of(o).ok_or(format!("operator {k}: convolution options"))?;
                let w = Window::of(c.stride, c.dilation, c.padding);
                self.conv(io, w, c.activation, op.op == Op::DepthwiseConv2d)?
            }
            (Op::Add, &OpOptions::Add { activation }) => self.binary(io, "Add", activation)?,
            (Op::Mul, &OpOptions::Add { activation }) => self.binary(io, "Mul", activation)?,
            (Op::Pad, _) => self.pad(io)?,
            (Op::Reshape, _) => self.reshape(io)?,
            (Op::Concatenation, &OpOptions::Concat { axis, activation }) => {
                self.concat(io, axis, activation)?
            }
            (
                Op::MaxPool2d,
                &OpOptions::Pool {
                    padding,
                    stride,
                    filter,
                    activation,
                },
            ) => {
                let mut w = Window::of(stride, (1, 1), padding);
                w.kernel = filter;
                self.max_pool(io, w, activation)?
            }
            (
                Op::ResizeBilinear,
                &OpOptions::Resize {
                    align_corners,
                    half_pixel_centers,
                },
            ) => self.resize(io, align_corners, half_pixel_centers)?,
            (Op::DepthToSpace, &OpOptions::DepthToSpace { block }) => {
                let attrs = vec![
                    ("blocksize", Attr::Int(block as i64)),
                    ("mode", Attr::Str("DCR")),
                ];
                self.unary(io, "DepthToSpace", attrs)?
            }
            (Op::Logistic, _) => self.unary(io, "Sigmoid", vec![])?,
            (Op::Relu, _) => self.unary(io, "Relu", vec![])?,
            (Op::Relu6, _) => {
                let x = name(io.input(0)?);
                self.b.activation(Activation::Relu6, &x, &name(io.out))
            }
            (other, _) => return Err(format!("operator {k}: {other:?} cannot be exported")),
        }
        Ok(())
    }

    /// A one-input node straight from the operator's input to its output.
    fn unary(&mut self, io: &Io, op: &str, attrs: Vec<(&str, Attr)>) -> R<()> {
        let x = name(io.input(0)?);
        self.b.node(op, &[&x], &name(io.out), attrs);
        Ok(())
    }

    fn conv(&mut self, io: &Io, mut win: Window, act: Activation, depthwise: bool) -> R<()> {
        let (xi, wi) = (io.input(0)?, io.input(1)?);
        let xs = self.shape4(io, xi, "input")?;
        let ws = self.shape4(io, wi, "weights")?;
        let os = self.shape4(io, io.out, "output")?;
        if depthwise && ws[0] != 1 {
            return Err(format!("operator {}: depthwise weights {ws:?}", io.k));
        }
        win.kernel = (ws[1], ws[2]);
        let pads = self.pads(&win, xs, os)?;
        let (oc, ic) = if depthwise {
            (ws[3], 1)
        } else {
            (ws[0], ws[3])
        };
        let wt = oihw(self.constant(io, wi)?, ws, depthwise);
        let bias = match io.ins.get(2) {
            Some(&bi) => self.constant(io, bi)?.to_vec(),
            None => vec![0.0; oc],
        };
        let (wn, bn, pre) = (self.b.fresh("w"), self.b.fresh("b"), &io.pre);
        self.b.init(f32_tensor(&wn, &[oc, ic, ws[1], ws[2]], &wt));
        self.b.init(f32_tensor(&bn, &[oc], &bias));
        let mut attrs = Builder::window_attrs(win.kernel, win.stride, Some(win.dilation), pads);
        if depthwise {
            attrs.push(("group", Attr::Int(xs[3] as i64)));
        }
        self.b.node("Conv", &[&name(xi), &wn, &bn], pre, attrs);
        self.b.activation(act, pre, &name(io.out));
        Ok(())
    }

    /// ONNX pads (top, left, bottom, right) giving TFLite's output size.
    fn pads(&self, w: &Window, xs: [usize; 4], os: [usize; 4]) -> R<[usize; 4]> {
        let (_, pt) = same::axis(xs[1], w.kernel.0, w.stride.0, w.dilation.0, w.padding)?;
        let (_, pl) = same::axis(xs[2], w.kernel.1, w.stride.1, w.dilation.1, w.padding)?;
        let pb = pad_after(
            os[1],
            w.stride.0,
            w.kernel.0,
            w.dilation.0,
            xs[1].saturating_add(pt),
        )?;
        let pr = pad_after(
            os[2],
            w.stride.1,
            w.kernel.1,
            w.dilation.1,
            xs[2].saturating_add(pl),
        )?;
        Ok([pt, pl, pb, pr])
    }

    fn max_pool(&mut self, io: &Io, win: Window, act: Activation) -> R<()> {
        let xi = io.input(0)?;
        let xs = self.shape4(io, xi, "input")?;
        let os = self.shape4(io, io.out, "output")?;
        let pads = self.pads(&win, xs, os)?;
        let pre = io.pre.clone();
        let attrs = Builder::window_attrs(win.kernel, win.stride, None, pads);
        self.b.node("MaxPool", &[&name(xi)], &pre, attrs);
        self.b.activation(act, &pre, &name(io.out));
        Ok(())
    }

    /// Add or Mul; a constant operand becomes an initialiser.
    fn binary(&mut self, io: &Io, op: &str, act: Activation) -> R<()> {
        let other = io.input(1)?;
        let y = name(other);
        if let Some(v) = &self.konst[other] {
            let s = &self.t[other].shape;
            if s.len() == 4 {
                return Err(format!("operator {}: 4-D constant operand", io.k));
            }
            // A per-channel vector broadcasts over NCHW as [C, 1, 1].
            let dims: Vec<usize> = if s.len() == 1 && self.t[io.out].shape.len() == 4 {
                vec![s[0], 1, 1]
            } else {
                s.clone()
            };
            let init = f32_tensor(&y, &dims, v);
            self.b.init(init);
        }
        let pre = io.pre.clone();
        self.b.node(op, &[&name(io.input(0)?), &y], &pre, vec![]);
        self.b.activation(act, &pre, &name(io.out));
        Ok(())
    }

    fn pad(&mut self, io: &Io) -> R<()> {
        let p = self.t[io.input(1)?]
            .i32s()
            .ok_or(format!("operator {}: paddings", io.k))?;
        let r = self.t[io.input(0)?].shape.len();
        let mut pads = vec![0i64; 2 * r];
        for d in 0..r {
            let to = nchw_axis(d, r);
            pads[to] = p.get(2 * d).copied().unwrap_or(0) as i64;
            pads[r + to] = p.get(2 * d + 1).copied().unwrap_or(0) as i64;
        }
        let pn = self.b.fresh("pads");
        self.b.init(i64_tensor(&pn, &pads));
        self.b
            .node("Pad", &[&name(io.input(0)?), &pn], &name(io.out), vec![]);
        Ok(())
    }

    /// TFLite reshapes in NHWC order, so 4-D tensors go back to NHWC around it.
    fn reshape(&mut self, io: &Io) -> R<()> {
        let (xi, o) = (io.input(0)?, name(io.out));
        let src = if self.t[xi].shape.len() == 4 {
            let n = self.b.fresh("nhwc");
            let perm = vec![("perm", Attr::Ints(vec![0, 2, 3, 1]))];
            self.b.node("Transpose", &[&name(xi)], &n, perm);
            n
        } else {
            name(xi)
        };
        let s = &self.t[io.out].shape;
        let sn = self.b.fresh("shape");
        let dims: Vec<i64> = s.iter().map(|&d| d as i64).collect();
        self.b.init(i64_tensor(&sn, &dims));
        if s.len() == 4 {
            let pre = io.pre.clone();
            self.b.node("Reshape", &[&src, &sn], &pre, vec![]);
            let perm = vec![("perm", Attr::Ints(vec![0, 3, 1, 2]))];
            self.b.node("Transpose", &[&pre], &o, perm);
        } else {
            self.b.node("Reshape", &[&src, &sn], &o, vec![]);
        }
        Ok(())
    }

    fn concat(&mut self, io: &Io, axis: i32, act: Activation) -> R<()> {
        let r = self.t[io.out].shape.len();
        let a = if axis < 0 {
            axis as i64 + r as i64
        } else {
            axis as i64
        };
        if a < 0 || a >= r as i64 {
            return Err(format!("operator {}: axis {axis} of a {r}-D output", io.k));
        }
        let names: Vec<String> = io.ins.iter().map(|&i| name(i)).collect();
        let refs: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
        let pre = io.pre.clone();
        let axis = nchw_axis(a as usize, r) as i64;
        self.b
            .node("Concat", &refs, &pre, vec![("axis", Attr::Int(axis))]);
        self.b.activation(act, &pre, &name(io.out));
        Ok(())
    }

    fn resize(&mut self, io: &Io, align_corners: bool, half_pixel: bool) -> R<()> {
        let os = self.shape4(io, io.out, "output")?;
        let sn = self.b.fresh("sizes");
        let sizes = [os[0], os[3], os[1], os[2]].map(|d| d as i64);
        self.b.init(i64_tensor(&sn, &sizes));
        let mode = match (align_corners, half_pixel) {
            (true, _) => "align_corners",
            (false, true) => "half_pixel",
            (false, false) => "asymmetric",
        };
        let attrs = vec![
            ("mode", Attr::Str("linear")),
            ("coordinate_transformation_mode", Attr::Str(mode)),
        ];
        let x = name(io.input(0)?);
        self.b
            .node("Resize", &[&x, "", "", &sn], &name(io.out), attrs);
        Ok(())
    }

    /// Graph outputs, 4-D ones transposed back to NHWC.
    fn outputs(&mut self, graph: &Graph) {
        for (j, &out) in graph.outputs.iter().enumerate() {
            let s = &self.t[out].shape;
            let on = format!("output{j}");
            let perm = if s.len() == 4 {
                vec![0, 2, 3, 1]
            } else {
                (0..s.len() as i64).collect()
            };
            let perm = vec![("perm", Attr::Ints(perm))];
            self.b.node("Transpose", &[&name(out)], &on, perm);
            self.b.graph.msg(12, value_info(&on, s));
        }
    }

    /// The `ModelProto` around the graph.
    fn model(mut self) -> Vec<u8> {
        let mut model = Pb::default();
        model.int(1, 7).str(2, "gait");
        let mut opset = Pb::default();
        opset.str(1, "").int(2, 13);
        model.msg(8, opset);
        model.msg(7, std::mem::take(&mut self.b.graph));
        model.0
    }
}

impl Window {
    fn of(stride: (usize, usize), dilation: (usize, usize), padding: Padding) -> Self {
        Window {
            kernel: (1, 1),
            stride,
            dilation,
            padding,
        }
    }
}

/// TFLite OHWI weights (depthwise 1HWC) as ONNX OIHW (depthwise C1HW).
fn oihw(w: &[f32], [wo, kh, kw, wi]: [usize; 4], depthwise: bool) -> Vec<f32> {
    let mut out = vec![0f32; w.len()];
    let ic = if depthwise { 1 } else { wi };
    let mut src = w.iter();
    for a in 0..wo {
        for y in 0..kh {
            for x in 0..kw {
                for c in 0..wi {
                    let (o, i) = if depthwise { (c, 0) } else { (a, c) };
                    out[((o * ic + i) * kh + y) * kw + x] = *src.next().unwrap_or(&0.0);
                }
            }
        }
    }
    out
}

/// Padding after the input so that `out` outputs fit: a hostile graph may declare
/// empty or huge sizes, so the arithmetic is checked (found by the `tflite_graph` fuzz target).
fn pad_after(out: usize, stride: usize, k: usize, dilation: usize, padded_in: usize) -> R<usize> {
    let span = out
        .checked_sub(1)
        .and_then(|o| o.checked_mul(stride))
        .zip(k.checked_sub(1).and_then(|k| k.checked_mul(dilation)))
        .and_then(|(a, b)| a.checked_add(b)?.checked_add(1))
        .ok_or_else(|| {
            format!(
                "convolution with output size {out}, kernel {k}, stride {stride}: not a valid layer"
            )
        })?;
    Ok(span.saturating_sub(padded_in))
}
