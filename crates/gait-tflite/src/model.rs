//! The owned TFLite graph (first subgraph) and its parsing, following the
//! field ids of TFLite's `schema.fbs`.

use crate::TfliteError;
use crate::densify::{DimMeta, Sparsity};
use crate::flatbuf::{Buf, Table};

type R<T> = Result<T, TfliteError>;

/// Element type of a tensor (`TensorType` in the schema).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DType {
    F32,
    F16,
    I32,
    Other(u8),
}

impl DType {
    fn from_code(c: u8) -> Self {
        match c {
            0 => DType::F32,
            1 => DType::F16,
            2 => DType::I32,
            o => DType::Other(o),
        }
    }
    fn size(self) -> Option<usize> {
        match self {
            DType::F32 | DType::I32 => Some(4),
            DType::F16 => Some(2),
            DType::Other(_) => None,
        }
    }
}

/// A tensor; `data` holds the dense little-endian bytes of constants.
#[derive(Debug, Clone)]
pub struct Tensor {
    pub name: String,
    pub shape: Vec<usize>,
    pub dtype: DType,
    pub data: Option<Vec<u8>>,
}

impl Tensor {
    /// Whether `n` values fill this tensor's shape: an operator that passes a constant on
    /// (dequantize, densify) must not hand a weight of one size to a layer expecting another.
    pub fn holds(&self, n: usize) -> Result<(), String> {
        let want = self.shape.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
        match want == Some(n) {
            true => Ok(()),
            false => Err(format!(
                "tensor {}: {n} values for shape {:?}",
                self.name, self.shape
            )),
        }
    }

    /// Constant values as f32 (from float32 or float16).
    pub fn f32s(&self) -> Option<Vec<f32>> {
        let d = self.data.as_ref()?;
        match self.dtype {
            DType::F32 => Some(
                d.chunks_exact(4)
                    .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                    .collect(),
            ),
            DType::F16 => Some(
                d.chunks_exact(2)
                    .map(|c| half::f16::from_le_bytes([c[0], c[1]]).to_f32())
                    .collect(),
            ),
            _ => None,
        }
    }

    /// Constant values of an int32 tensor.
    pub fn i32s(&self) -> Option<Vec<i32>> {
        let d = self.data.as_ref()?;
        (self.dtype == DType::I32).then(|| {
            d.chunks_exact(4)
                .map(|c| i32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect()
        })
    }
}

/// Builtin operators used by the BlazePose graphs (others keep their code).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Op {
    Add,
    AveragePool2d,
    Concatenation,
    Conv2d,
    DepthwiseConv2d,
    DepthToSpace,
    Dequantize,
    Logistic,
    MaxPool2d,
    Mul,
    Relu,
    Relu6,
    Reshape,
    ResizeBilinear,
    Pad,
    Transpose,
    Densify,
    Prelu,
    HardSwish,
    /// A custom operator (`CUSTOM`); MediaPipe's only one in the selfie
    /// segmentation model is `Convolution2DTransposeBias`.
    Custom,
    Other(i32),
}

impl Op {
    fn from_code(c: i32) -> Self {
        match c {
            0 => Op::Add,
            1 => Op::AveragePool2d,
            2 => Op::Concatenation,
            3 => Op::Conv2d,
            4 => Op::DepthwiseConv2d,
            5 => Op::DepthToSpace,
            6 => Op::Dequantize,
            14 => Op::Logistic,
            17 => Op::MaxPool2d,
            18 => Op::Mul,
            19 => Op::Relu,
            21 => Op::Relu6,
            22 => Op::Reshape,
            32 => Op::Custom,
            23 => Op::ResizeBilinear,
            34 => Op::Pad,
            39 => Op::Transpose,
            54 => Op::Prelu,
            117 => Op::HardSwish,
            124 => Op::Densify,
            o => Op::Other(o),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Padding {
    Same,
    Valid,
}

/// Activation fused into an operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Activation {
    None,
    Relu,
    ReluN1To1,
    Relu6,
    Tanh,
}

/// Builtin options of the operators we run.
#[derive(Debug, Clone, PartialEq)]
pub enum OpOptions {
    None,
    Conv {
        padding: Padding,
        stride: (usize, usize),
        dilation: (usize, usize),
        activation: Activation,
    },
    Depthwise {
        padding: Padding,
        stride: (usize, usize),
        dilation: (usize, usize),
        multiplier: usize,
        activation: Activation,
    },
    Pool {
        padding: Padding,
        stride: (usize, usize),
        filter: (usize, usize),
        activation: Activation,
    },
    Add {
        activation: Activation,
    },
    Concat {
        axis: i32,
        activation: Activation,
    },
    Resize {
        align_corners: bool,
        half_pixel_centers: bool,
    },
    DepthToSpace {
        block: usize,
    },
}

/// One operator: tensor indices in and out (-1 = absent optional input).
#[derive(Debug, Clone)]
pub struct Operator {
    pub op: Op,
    pub inputs: Vec<i32>,
    pub outputs: Vec<i32>,
    pub options: OpOptions,
}

/// The first subgraph of a model.
#[derive(Debug, Clone)]
pub struct Graph {
    pub tensors: Vec<Tensor>,
    pub operators: Vec<Operator>,
    pub inputs: Vec<usize>,
    pub outputs: Vec<usize>,
}

fn padding(c: u8) -> Padding {
    if c == 1 {
        Padding::Valid
    } else {
        Padding::Same
    }
}

fn activation(c: u8) -> R<Activation> {
    Ok(match c {
        0 => Activation::None,
        1 => Activation::Relu,
        2 => Activation::ReluN1To1,
        3 => Activation::Relu6,
        4 => Activation::Tanh,
        o => return Err(TfliteError::Unsupported(format!("fused activation {o}"))),
    })
}

fn positive(v: i32, what: &str) -> R<usize> {
    usize::try_from(v)
        .ok()
        .filter(|v| *v > 0)
        .ok_or_else(|| TfliteError::Malformed(format!("{what} = {v}")))
}

fn options(op: Op, t: Option<Table>) -> R<OpOptions> {
    let Some(t) = t else {
        return Ok(match op {
            Op::Add => OpOptions::Add {
                activation: Activation::None,
            },
            _ => OpOptions::None,
        });
    };
    let stride = |w: usize, h: usize| -> R<(usize, usize)> {
        Ok((
            positive(t.i32_or(h, 0)?, "stride_h")?,
            positive(t.i32_or(w, 0)?, "stride_w")?,
        ))
    };
    Ok(match op {
        Op::Conv2d => OpOptions::Conv {
            padding: padding(t.u8_or(0, 0)?),
            stride: stride(1, 2)?,
            activation: activation(t.u8_or(3, 0)?)?,
            dilation: (
                positive(t.i32_or(5, 1)?, "dilation")?,
                positive(t.i32_or(4, 1)?, "dilation")?,
            ),
        },
        Op::DepthwiseConv2d => OpOptions::Depthwise {
            padding: padding(t.u8_or(0, 0)?),
            stride: stride(1, 2)?,
            multiplier: positive(t.i32_or(3, 1)?, "depth_multiplier")?,
            activation: activation(t.u8_or(4, 0)?)?,
            dilation: (
                positive(t.i32_or(6, 1)?, "dilation")?,
                positive(t.i32_or(5, 1)?, "dilation")?,
            ),
        },
        Op::MaxPool2d | Op::AveragePool2d => OpOptions::Pool {
            padding: padding(t.u8_or(0, 0)?),
            stride: stride(1, 2)?,
            filter: (
                positive(t.i32_or(4, 0)?, "filter_height")?,
                positive(t.i32_or(3, 0)?, "filter_width")?,
            ),
            activation: activation(t.u8_or(5, 0)?)?,
        },
        Op::Add | Op::Mul => OpOptions::Add {
            activation: activation(t.u8_or(0, 0)?)?,
        },
        Op::Concatenation => OpOptions::Concat {
            axis: t.i32_or(0, 0)?,
            activation: activation(t.u8_or(1, 0)?)?,
        },
        Op::ResizeBilinear => OpOptions::Resize {
            align_corners: t.bool_or(2, false)?,
            half_pixel_centers: t.bool_or(3, false)?,
        },
        Op::DepthToSpace => OpOptions::DepthToSpace {
            block: positive(t.i32_or(0, 0)?, "block_size")?,
        },
        _ => OpOptions::None,
    })
}

fn index_vector(t: Option<Table>, kind: u8) -> R<Vec<usize>> {
    let Some(t) = t else { return Ok(Vec::new()) };
    Ok(match kind {
        1 => t
            .i32s(0)?
            .into_iter()
            .map(|v| {
                usize::try_from(v)
                    .map_err(|_| TfliteError::Malformed("negative sparse index".into()))
            })
            .collect::<R<_>>()?,
        2 => t.u16s(0)?.into_iter().map(usize::from).collect(),
        3 => t
            .bytes(0)?
            .unwrap_or_default()
            .iter()
            .map(|&b| b as usize)
            .collect(),
        o => {
            return Err(TfliteError::Unsupported(format!(
                "sparse index vector type {o}"
            )));
        }
    })
}

fn sparsity(t: Table) -> R<Sparsity> {
    let dims = |v: Vec<i32>| -> R<Vec<usize>> {
        v.into_iter()
            .map(|d| {
                usize::try_from(d).map_err(|_| TfliteError::Malformed("negative sparse dim".into()))
            })
            .collect()
    };
    let mut dim_metadata = Vec::new();
    for m in t.tables(2)? {
        dim_metadata.push(if m.u8_or(0, 0)? == 0 {
            DimMeta::Dense(
                usize::try_from(m.i32_or(1, 0)?)
                    .map_err(|_| TfliteError::Malformed("dense_size".into()))?,
            )
        } else {
            DimMeta::SparseCsr {
                segments: index_vector(m.table(3)?, m.u8_or(2, 0)?)?,
                indices: index_vector(m.table(5)?, m.u8_or(4, 0)?)?,
            }
        });
    }
    Ok(Sparsity {
        traversal_order: dims(t.i32s(0)?)?,
        block_map: dims(t.i32s(1)?)?,
        dim_metadata,
    })
}

/// The most elements one tensor may declare (64 MiB as float32; BlazePose's largest is under 10^6).
pub const MAX_TENSOR_ELEMENTS: usize = 1 << 24;

impl Graph {
    /// Parses a `.tflite` file's bytes.
    pub fn parse(bytes: &[u8]) -> R<Self> {
        if bytes.len() < 8 {
            return Err(TfliteError::Malformed(format!(
                "only {} bytes",
                bytes.len()
            )));
        }
        if &bytes[4..8] != b"TFL3" {
            return Err(TfliteError::Foreign(
                String::from_utf8_lossy(&bytes[4..8]).into_owned(),
            ));
        }
        let buf = Buf(bytes);
        let model = buf.root()?;
        let codes: Vec<Op> = model
            .tables(1)?
            .iter()
            .map(|c| {
                let dep = c.u8_or(0, 0)? as i8 as i32;
                Ok(Op::from_code(dep.max(c.i32_or(3, 0)?)))
            })
            .collect::<R<_>>()?;
        let buffers = model.tables(4)?;
        let sub = model
            .tables(2)?
            .into_iter()
            .next()
            .ok_or_else(|| TfliteError::Malformed("no subgraph".into()))?;

        let mut tensors = Vec::new();
        for t in sub.tables(0)? {
            let shape = t
                .i32s(0)?
                .into_iter()
                .map(|d| {
                    usize::try_from(d)
                        .map_err(|_| TfliteError::Unsupported(format!("dynamic dimension {d}")))
                })
                .collect::<R<Vec<_>>>()?;
            let dtype = DType::from_code(t.u8_or(1, 0)?);
            let name = t.string(3)?;
            // Activations have no data to check their shape against, and both backends
            // allocate what the shape declares: refuse absurd ones before anything runs.
            let elems = shape.iter().try_fold(1usize, |a, &n| a.checked_mul(n));
            if elems.is_none_or(|n| n > MAX_TENSOR_ELEMENTS) {
                return Err(TfliteError::Unsupported(format!(
                    "tensor {name} of shape {shape:?} (over {MAX_TENSOR_ELEMENTS} elements)"
                )));
            }
            let bidx = t.u32_or(2, 0)? as usize;
            let mut data = match buffers.get(bidx) {
                Some(b) if bidx > 0 => buffer_bytes(bytes, b)?,
                _ => None,
            };
            if let (Some(sp), Some(raw)) = (t.table(6)?, data.as_ref()) {
                let elem = dtype.size().ok_or_else(|| {
                    TfliteError::Unsupported(format!("sparse tensor {name} of type {dtype:?}"))
                })?;
                data = Some(sparsity(sp)?.densify(&shape, raw, elem)?);
            }
            if let (Some(d), Some(elem)) = (data.as_ref(), dtype.size()) {
                let want = shape.iter().try_fold(elem, |a, &n| a.checked_mul(n));
                if want != Some(d.len()) {
                    return Err(TfliteError::Malformed(format!(
                        "tensor {name}: {} bytes of data for shape {shape:?}",
                        d.len()
                    )));
                }
            }
            tensors.push(Tensor {
                name,
                shape,
                dtype,
                data,
            });
        }

        let idx = |v: Vec<i32>, what: &str| -> R<Vec<usize>> {
            v.into_iter()
                .map(|i| {
                    usize::try_from(i)
                        .ok()
                        .filter(|i| *i < tensors.len())
                        .ok_or_else(|| TfliteError::Malformed(format!("{what} tensor index {i}")))
                })
                .collect()
        };
        let inputs = idx(sub.i32s(1)?, "input")?;
        let outputs = idx(sub.i32s(2)?, "output")?;
        let mut operators = Vec::new();
        for o in sub.tables(3)? {
            let code = o.u32_or(0, 0)? as usize;
            let op = *codes
                .get(code)
                .ok_or_else(|| TfliteError::Malformed(format!("opcode index {code}")))?;
            let ins = o.i32s(1)?;
            let outs = o.i32s(2)?;
            for &i in ins.iter().chain(&outs) {
                if i < -1 || i >= tensors.len() as i32 {
                    return Err(TfliteError::Malformed(format!("operator tensor index {i}")));
                }
            }
            operators.push(Operator {
                op,
                inputs: ins,
                outputs: outs,
                options: options(op, o.table(4)?)?,
            });
        }
        Ok(Graph {
            tensors,
            operators,
            inputs,
            outputs,
        })
    }

    /// Reads and parses a `.tflite` file.
    pub fn load(path: &std::path::Path) -> R<Self> {
        let bytes =
            std::fs::read(path).map_err(|e| TfliteError::Malformed(format!("cannot read: {e}")))?;
        Self::parse(&bytes)
    }

    /// Keeps only the graph outputs chosen by `keep` (given each output's
    /// tensor) and drops the operators that feed none of them, so neither
    /// backend computes results nobody reads (e.g. BlazePose's segmentation).
    pub fn keep_outputs(&mut self, keep: impl Fn(&Tensor) -> bool) {
        self.outputs.retain(|&o| keep(&self.tensors[o]));
        let mut needed = vec![false; self.tensors.len()];
        for &o in &self.outputs {
            needed[o] = true;
        }
        // Operators are stored in execution order, so one backward pass finds
        // everything the kept outputs depend on.
        let mut live = vec![false; self.operators.len()];
        for (k, op) in self.operators.iter().enumerate().rev() {
            if op.outputs.iter().any(|&t| t >= 0 && needed[t as usize]) {
                live[k] = true;
                for &t in op.inputs.iter().filter(|&&t| t >= 0) {
                    needed[t as usize] = true;
                }
            }
        }
        let mut k = 0;
        self.operators.retain(|_| {
            k += 1;
            live[k - 1]
        });
    }
}

/// Bytes of a `Buffer`: inline data, or (large models) an offset into the file.
fn buffer_bytes(file: &[u8], b: &Table) -> R<Option<Vec<u8>>> {
    if let Some(d) = b.bytes(0)? {
        return Ok((!d.is_empty()).then(|| d.to_vec()));
    }
    let (off, size) = (b.u64_or(1, 0)? as usize, b.u64_or(2, 0)? as usize);
    if off > 1 {
        let d = off
            .checked_add(size)
            .and_then(|end| file.get(off..end))
            .ok_or_else(|| TfliteError::Malformed("buffer outside the file".into()))?;
        return Ok(Some(d.to_vec()));
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tensor(name: &str, len: usize) -> Tensor {
        Tensor {
            name: name.into(),
            shape: vec![1, len],
            dtype: DType::F32,
            data: None,
        }
    }

    fn relu(from: i32, to: i32) -> Operator {
        Operator {
            op: Op::Relu,
            inputs: vec![from],
            outputs: vec![to],
            options: OpOptions::None,
        }
    }

    #[test]
    fn keep_outputs_drops_dead_branches() {
        // in(0) -> a(1) -> out_a(2) and in(0) -> b(3) -> out_b(4).
        let mut g = Graph {
            tensors: vec![
                tensor("in", 1),
                tensor("a", 1),
                tensor("out_a", 2),
                tensor("b", 1),
                tensor("out_b", 3),
            ],
            operators: vec![relu(0, 1), relu(0, 3), relu(1, 2), relu(3, 4)],
            inputs: vec![0],
            outputs: vec![2, 4],
        };
        g.keep_outputs(|t| t.name == "out_a");
        assert_eq!(g.outputs, vec![2]);
        let outs: Vec<i32> = g.operators.iter().map(|o| o.outputs[0]).collect();
        assert_eq!(outs, vec![1, 2]);
    }
}
