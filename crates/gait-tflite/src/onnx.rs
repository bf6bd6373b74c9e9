//! Writes a TFLite graph as an ONNX model (opset 13), encoding the protobuf
//! by hand. Activations are NCHW inside; the input is taken NHWC and 4-D
//! outputs are given back NHWC, like the TFLite model.

use crate::model::{Activation, Graph, Op, OpOptions};
use crate::same::{self, nchw_axis};

/// Protobuf writer: fields are appended as (tag, payload).
#[derive(Default)]
struct Pb(Vec<u8>);

impl Pb {
    fn varint(&mut self, mut v: u64) {
        while v >= 0x80 {
            self.0.push((v as u8) | 0x80);
            v >>= 7;
        }
        self.0.push(v as u8);
    }
    fn int(&mut self, field: u32, v: i64) -> &mut Self {
        self.varint((field as u64) << 3);
        self.varint(v as u64);
        self
    }
    fn bytes(&mut self, field: u32, b: &[u8]) -> &mut Self {
        self.varint(((field as u64) << 3) | 2);
        self.varint(b.len() as u64);
        self.0.extend_from_slice(b);
        self
    }
    fn str(&mut self, field: u32, s: &str) -> &mut Self {
        self.bytes(field, s.as_bytes())
    }
    fn msg(&mut self, field: u32, m: Pb) -> &mut Self {
        self.bytes(field, &m.0)
    }
}

enum Attr {
    Int(i64),
    Ints(Vec<i64>),
    Str(&'static str),
}

fn attr(name: &str, a: Attr) -> Pb {
    let mut p = Pb::default();
    p.str(1, name);
    match a {
        Attr::Int(i) => p.int(3, i).int(20, 2),
        Attr::Str(s) => p.bytes(4, s.as_bytes()).int(20, 3),
        Attr::Ints(v) => {
            for i in v {
                p.int(8, i);
            }
            p.int(20, 7)
        }
    };
    p
}

fn tensor(name: &str, dims: &[usize], data_type: i64, raw: Vec<u8>) -> Pb {
    let mut p = Pb::default();
    for &d in dims {
        p.int(1, d as i64);
    }
    p.int(2, data_type).str(8, name).bytes(9, &raw);
    p
}

fn f32_tensor(name: &str, dims: &[usize], v: &[f32]) -> Pb {
    tensor(
        name,
        dims,
        1,
        v.iter().flat_map(|x| x.to_le_bytes()).collect(),
    )
}

fn i64_tensor(name: &str, v: &[i64]) -> Pb {
    tensor(
        name,
        &[v.len()],
        7,
        v.iter().flat_map(|x| x.to_le_bytes()).collect(),
    )
}

fn value_info(name: &str, dims: &[usize]) -> Pb {
    let mut shape = Pb::default();
    for &d in dims {
        let mut dim = Pb::default();
        dim.int(1, d as i64);
        shape.msg(1, dim);
    }
    let mut tt = Pb::default();
    tt.int(1, 1).msg(2, shape);
    let mut ty = Pb::default();
    ty.msg(1, tt);
    let mut p = Pb::default();
    p.str(1, name).msg(2, ty);
    p
}

struct Builder {
    graph: Pb,
    count: usize,
}

impl Builder {
    fn node(&mut self, op: &str, inputs: &[&str], output: &str, attrs: Vec<(&str, Attr)>) {
        let mut n = Pb::default();
        for i in inputs {
            n.str(1, i);
        }
        n.str(2, output)
            .str(3, &format!("n{}", self.count))
            .str(4, op);
        for (name, a) in attrs {
            n.msg(5, attr(name, a));
        }
        self.count += 1;
        self.graph.msg(1, n);
    }
    fn init(&mut self, t: Pb) {
        self.graph.msg(5, t);
    }
    fn fresh(&mut self, base: &str) -> String {
        self.count += 1;
        format!("{base}__{}", self.count)
    }
    fn activation(&mut self, act: Activation, x: &str, out: &str) -> Result<(), String> {
        match act {
            Activation::None => self.node("Identity", &[x], out, vec![]),
            Activation::Relu => self.node("Relu", &[x], out, vec![]),
            Activation::Relu6 | Activation::ReluN1To1 => {
                let (lo, hi) = if act == Activation::Relu6 {
                    (0.0, 6.0)
                } else {
                    (-1.0, 1.0)
                };
                let (a, b) = (self.fresh("lo"), self.fresh("hi"));
                self.init(f32_tensor(&a, &[], &[lo]));
                self.init(f32_tensor(&b, &[], &[hi]));
                self.node("Clip", &[x, &a, &b], out, vec![]);
            }
            Activation::Tanh => self.node("Tanh", &[x], out, vec![]),
        }
        Ok(())
    }
}

/// The ONNX model bytes of `graph`.
/// Padding after the input so that `out` outputs fit: a hostile graph may declare
/// empty or huge sizes, so the arithmetic is checked (found by the `tflite_graph` fuzz target).
fn pad_after(
    out: usize,
    stride: usize,
    k: usize,
    dilation: usize,
    padded_in: usize,
) -> Result<usize, String> {
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

pub fn to_onnx(graph: &Graph) -> Result<Vec<u8>, String> {
    let mut b = Builder {
        graph: Pb::default(),
        count: 0,
    };
    b.graph.str(2, "tflite");
    let t = &graph.tensors;
    let name = |i: usize| format!("t{i}");
    let mut konst: Vec<Option<Vec<f32>>> = t.iter().map(|t| t.f32s()).collect();
    let input = *graph.inputs.first().ok_or("graph has no input")?;
    b.graph.msg(11, value_info("input", &t[input].shape));
    b.node(
        "Transpose",
        &["input"],
        &name(input),
        vec![("perm", Attr::Ints(vec![0, 3, 1, 2]))],
    );
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
        let get = |j: usize| {
            ins.get(j)
                .copied()
                .ok_or(format!("operator {k}: missing input {j}"))
        };
        let cst = |i: usize| {
            konst[i]
                .clone()
                .ok_or(format!("operator {k}: input {i} not constant"))
        };
        let pre = b.fresh("pre");
        let (o, x) = (name(out), name(get(0)?));
        match (&op.op, &op.options) {
            (Op::Dequantize | Op::Densify, _) => {
                konst[out] = Some(cst(get(0)?)?);
                continue;
            }
            (Op::Conv2d | Op::DepthwiseConv2d, opts) => {
                let (padding, stride, dilation, act, depthwise) = match opts {
                    OpOptions::Conv {
                        padding,
                        stride,
                        dilation,
                        activation,
                    } => (*padding, *stride, *dilation, *activation, false),
                    OpOptions::Depthwise {
                        padding,
                        stride,
                        dilation,
                        activation,
                        ..
                    } => (*padding, *stride, *dilation, *activation, true),
                    _ => return Err(format!("operator {k}: conv options")),
                };
                let (xs, ws, os) = (&t[get(0)?].shape, &t[get(1)?].shape, &t[out].shape);
                let [wo, kh, kw, wi] = ws[..] else {
                    return Err(format!("operator {k}: weights {ws:?}"));
                };
                let w = cst(get(1)?)?;
                // TFLite OHWI (depthwise 1HWC) -> ONNX OIHW (depthwise C1HW).
                let (oc, ic) = if depthwise { (wi, 1) } else { (wo, wi) };
                let mut wt = vec![0f32; w.len()];
                for (j, v) in w.iter().enumerate() {
                    let (a, y, xx, c) = (
                        j / (kh * kw * wi),
                        (j / (kw * wi)) % kh,
                        (j / wi) % kw,
                        j % wi,
                    );
                    let (oo, ii) = if depthwise { (c, 0) } else { (a, c) };
                    wt[((oo * ic + ii) * kh + y) * kw + xx] = *v;
                }
                let (wn, bn) = (b.fresh("w"), b.fresh("b"));
                b.init(f32_tensor(&wn, &[oc, ic, kh, kw], &wt));
                let bias = match ins.get(2) {
                    Some(&bi) => cst(bi)?,
                    None => vec![0.0; oc],
                };
                b.init(f32_tensor(&bn, &[oc], &bias));
                let (_, pt) = same::axis(xs[1], kh, stride.0, dilation.0, padding);
                let (_, pl) = same::axis(xs[2], kw, stride.1, dilation.1, padding);
                let pb = pad_after(os[1], stride.0, kh, dilation.0, xs[1] + pt)?;
                let pr = pad_after(os[2], stride.1, kw, dilation.1, xs[2] + pl)?;
                let mut attrs = vec![
                    ("kernel_shape", Attr::Ints(vec![kh as i64, kw as i64])),
                    (
                        "strides",
                        Attr::Ints(vec![stride.0 as i64, stride.1 as i64]),
                    ),
                    (
                        "dilations",
                        Attr::Ints(vec![dilation.0 as i64, dilation.1 as i64]),
                    ),
                    (
                        "pads",
                        Attr::Ints(vec![pt as i64, pl as i64, pb as i64, pr as i64]),
                    ),
                ];
                if depthwise {
                    attrs.push(("group", Attr::Int(xs[3] as i64)));
                }
                b.node("Conv", &[&x, &wn, &bn], &pre, attrs);
                b.activation(act, &pre, &o)?;
            }
            (Op::Add | Op::Mul, OpOptions::Add { activation }) => {
                let onnx_op = if op.op == Op::Add { "Add" } else { "Mul" };
                let other = get(1)?;
                let y = name(other);
                if let Some(v) = konst[other].clone() {
                    let s = &t[other].shape;
                    if s.len() == 4 {
                        return Err(format!("operator {k}: 4-D constant operand"));
                    }
                    // A per-channel vector broadcasts over NCHW as [C, 1, 1].
                    let dims: Vec<usize> = if s.len() == 1 && t[out].shape.len() == 4 {
                        vec![s[0], 1, 1]
                    } else {
                        s.clone()
                    };
                    b.init(f32_tensor(&y, &dims, &v));
                }
                b.node(onnx_op, &[&x, &y], &pre, vec![]);
                b.activation(*activation, &pre, &o)?;
            }
            (Op::Pad, _) => {
                let p = t[get(1)?].i32s().ok_or(format!("operator {k}: paddings"))?;
                let r = t[get(0)?].shape.len();
                let mut pads = vec![0i64; 2 * r];
                for d in 0..r {
                    let to = nchw_axis(d, r);
                    pads[to] = p.get(2 * d).copied().unwrap_or(0) as i64;
                    pads[r + to] = p.get(2 * d + 1).copied().unwrap_or(0) as i64;
                }
                let pn = b.fresh("pads");
                b.init(i64_tensor(&pn, &pads));
                b.node("Pad", &[&x, &pn], &o, vec![]);
            }
            (Op::Reshape, _) => {
                let src = if t[get(0)?].shape.len() == 4 {
                    let n = b.fresh("nhwc");
                    b.node(
                        "Transpose",
                        &[&x],
                        &n,
                        vec![("perm", Attr::Ints(vec![0, 2, 3, 1]))],
                    );
                    n
                } else {
                    x.clone()
                };
                let s = &t[out].shape;
                let sn = b.fresh("shape");
                b.init(i64_tensor(
                    &sn,
                    &s.iter().map(|&d| d as i64).collect::<Vec<_>>(),
                ));
                if s.len() == 4 {
                    b.node("Reshape", &[&src, &sn], &pre, vec![]);
                    b.node(
                        "Transpose",
                        &[&pre],
                        &o,
                        vec![("perm", Attr::Ints(vec![0, 3, 1, 2]))],
                    );
                } else {
                    b.node("Reshape", &[&src, &sn], &o, vec![]);
                }
            }
            (Op::Concatenation, OpOptions::Concat { axis, activation }) => {
                let r = t[out].shape.len() as i32;
                let a = if *axis < 0 { axis + r } else { *axis } as usize;
                let a = nchw_axis(a, r as usize);
                let names: Vec<String> = ins.iter().map(|&i| name(i)).collect();
                let refs: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
                b.node("Concat", &refs, &pre, vec![("axis", Attr::Int(a as i64))]);
                b.activation(*activation, &pre, &o)?;
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
                let (xs, os) = (&t[get(0)?].shape, &t[out].shape);
                let (_, pt) = same::axis(xs[1], filter.0, stride.0, 1, *padding);
                let (_, pl) = same::axis(xs[2], filter.1, stride.1, 1, *padding);
                let pb = ((os[1] - 1) * stride.0 + filter.0).saturating_sub(xs[1] + pt);
                let pr = ((os[2] - 1) * stride.1 + filter.1).saturating_sub(xs[2] + pl);
                let attrs = vec![
                    (
                        "kernel_shape",
                        Attr::Ints(vec![filter.0 as i64, filter.1 as i64]),
                    ),
                    (
                        "strides",
                        Attr::Ints(vec![stride.0 as i64, stride.1 as i64]),
                    ),
                    (
                        "pads",
                        Attr::Ints(vec![pt as i64, pl as i64, pb as i64, pr as i64]),
                    ),
                ];
                b.node("MaxPool", &[&x], &pre, attrs);
                b.activation(*activation, &pre, &o)?;
            }
            (
                Op::ResizeBilinear,
                OpOptions::Resize {
                    align_corners,
                    half_pixel_centers,
                },
            ) => {
                let os = &t[out].shape;
                let sn = b.fresh("sizes");
                b.init(i64_tensor(
                    &sn,
                    &[os[0] as i64, os[3] as i64, os[1] as i64, os[2] as i64],
                ));
                let mode = match (align_corners, half_pixel_centers) {
                    (true, _) => "align_corners",
                    (false, true) => "half_pixel",
                    (false, false) => "asymmetric",
                };
                let attrs = vec![
                    ("mode", Attr::Str("linear")),
                    ("coordinate_transformation_mode", Attr::Str(mode)),
                ];
                b.node("Resize", &[&x, "", "", &sn], &o, attrs);
            }
            (Op::DepthToSpace, OpOptions::DepthToSpace { block }) => {
                let attrs = vec![
                    ("blocksize", Attr::Int(*block as i64)),
                    ("mode", Attr::Str("DCR")),
                ];
                b.node("DepthToSpace", &[&x], &o, attrs);
            }
            (Op::Logistic, _) => b.node("Sigmoid", &[&x], &o, vec![]),
            (Op::Relu, _) => b.node("Relu", &[&x], &o, vec![]),
            (Op::Relu6, _) => b.activation(Activation::Relu6, &x, &o)?,
            (other, _) => return Err(format!("operator {k}: {other:?} cannot be exported")),
        }
    }
    for (j, &out) in graph.outputs.iter().enumerate() {
        let s = &t[out].shape;
        let on = format!("output{j}");
        let perm = if s.len() == 4 {
            vec![0, 2, 3, 1]
        } else {
            (0..s.len() as i64).collect()
        };
        b.node(
            "Transpose",
            &[&name(out)],
            &on,
            vec![("perm", Attr::Ints(perm))],
        );
        b.graph.msg(12, value_info(&on, s));
    }
    let mut model = Pb::default();
    model.int(1, 7).str(2, "gait");
    let mut opset = Pb::default();
    opset.str(1, "").int(2, 13);
    model.msg(8, opset);
    model.msg(7, std::mem::take(&mut b.graph));
    Ok(model.0)
}
