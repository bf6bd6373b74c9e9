//! Appends nodes and initialisers to an ONNX graph, naming intermediate values.

use super::proto::{Attr, Pb, attr, f32_tensor};
use crate::model::Activation;

/// A `GraphProto` being written.
pub(super) struct Builder {
    pub(super) graph: Pb,
    count: usize,
}

impl Builder {
    pub(super) fn new() -> Self {
        let mut graph = Pb::default();
        graph.str(2, "tflite");
        Builder { graph, count: 0 }
    }

    /// A node of `op` with one output.
    pub(super) fn node(
        &mut self,
        op: &str,
        inputs: &[&str],
        output: &str,
        attrs: Vec<(&str, Attr)>,
    ) {
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

    /// A constant (`TensorProto`) of the graph.
    pub(super) fn init(&mut self, t: Pb) {
        self.graph.msg(5, t);
    }

    /// A name no other value has.
    pub(super) fn fresh(&mut self, base: &str) -> String {
        self.count += 1;
        format!("{base}__{}", self.count)
    }

    /// `out = act(x)`, TFLite's fused activation as its own node.
    pub(super) fn activation(&mut self, act: Activation, x: &str, out: &str) {
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
    }

    /// A 2-D window's ONNX attributes: kernel, strides, dilations (when given) and pads.
    pub(super) fn window_attrs(
        kernel: (usize, usize),
        stride: (usize, usize),
        dilation: Option<(usize, usize)>,
        pads: [usize; 4],
    ) -> Vec<(&'static str, Attr)> {
        let pair = |p: (usize, usize)| Attr::Ints(vec![p.0 as i64, p.1 as i64]);
        let mut attrs = vec![("kernel_shape", pair(kernel)), ("strides", pair(stride))];
        if let Some(d) = dilation {
            attrs.push(("dilations", pair(d)));
        }
        attrs.push(("pads", Attr::Ints(pads.iter().map(|&p| p as i64).collect())));
        attrs
    }
}
