//! Runs a TFLite graph on candle (CPU), op by op, in TFLite's own NHWC layout
//! (no transposes). The heavy operators are our kernels on contiguous
//! slices (`kernels`), run as candle custom ops with their weights packed
//! once at compile time and their activations fused.

mod compile;
mod fold;
mod step;

use candle_core::{Device, Tensor};

use crate::kernels::{act, apply1};
use crate::model::{Activation, Graph};
use step::Node;

type R<T> = Result<T, String>;

fn ce(e: candle_core::Error) -> String {
    e.to_string()
}

/// A TFLite graph compiled to candle operations.
pub struct CandleGraph {
    nodes: Vec<Node>,
    consts: Vec<Option<Tensor>>,
    input: usize,
    input_shape: Vec<usize>,
    outputs: Vec<usize>,
}

impl CandleGraph {
    /// Compiles `graph`; fails on operators or layouts it cannot run.
    pub fn new(graph: &Graph) -> R<Self> {
        let (nodes, values) = compile::nodes(graph)?;
        let mut nodes = fold::pads_into_windows(nodes, &graph.outputs);
        let consts = constant_tensors(graph, values)?;
        let input = *graph.inputs.first().ok_or("graph has no input")?;
        mark_last_uses(&mut nodes, &consts, &graph.outputs);
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
            let mut y = step::run(node, &get).map_err(|e| format!("node {k}: {e}"))?;
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

/// The constant values as tensors of their declared shapes.
fn constant_tensors(graph: &Graph, values: compile::Constants) -> R<Vec<Option<Tensor>>> {
    values
        .into_iter()
        .zip(&graph.tensors)
        .map(|(v, t)| {
            v.map(|v| Tensor::from_vec(v, t.shape.clone(), &Device::Cpu).map_err(ce))
                .transpose()
        })
        .collect()
}

/// Notes on each node the computed values no later node (nor the output) reads.
fn mark_last_uses(nodes: &mut [Node], consts: &[Option<Tensor>], outputs: &[usize]) {
    let mut seen = vec![false; consts.len()];
    for &o in outputs {
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
}
