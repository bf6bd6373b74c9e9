//! What both backends read off one operator: its tensors and, for a convolution, its options.

use crate::model::{Activation, OpOptions, Operator, Padding};

/// One operator's tensors: its given inputs (absent optional ones dropped) and its first output.
pub(crate) struct OpIo<'o> {
    /// The operator's position in the graph (for messages).
    pub k: usize,
    pub op: &'o Operator,
    pub ins: Vec<usize>,
    pub out: usize,
}

impl<'o> OpIo<'o> {
    pub fn new(k: usize, op: &'o Operator) -> Result<Self, String> {
        let ins = op
            .inputs
            .iter()
            .filter(|&&i| i >= 0)
            .map(|&i| i as usize)
            .collect();
        // -1 marks an absent tensor: allowed for optional inputs, never for the output.
        let out = op
            .outputs
            .first()
            .and_then(|&o| usize::try_from(o).ok())
            .ok_or(format!("operator {k} has no output"))?;
        Ok(OpIo { k, op, ins, out })
    }

    /// The tensor of given input `j`.
    pub fn input(&self, j: usize) -> Result<usize, String> {
        self.ins
            .get(j)
            .copied()
            .ok_or(format!("operator {}: missing input {j}", self.k))
    }
}

/// A convolution's options, regular or depthwise (a regular one's multiplier is 1).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ConvParams {
    pub padding: Padding,
    pub stride: (usize, usize),
    pub dilation: (usize, usize),
    pub multiplier: usize,
    pub activation: Activation,
}

impl ConvParams {
    /// The options of a CONV_2D or DEPTHWISE_CONV_2D; `None` for any other operator's.
    pub fn of(o: &OpOptions) -> Option<Self> {
        match *o {
            OpOptions::Conv {
                padding,
                stride,
                dilation,
                activation,
            } => Some(ConvParams {
                padding,
                stride,
                dilation,
                multiplier: 1,
                activation,
            }),
            OpOptions::Depthwise {
                padding,
                stride,
                dilation,
                multiplier,
                activation,
            } => Some(ConvParams {
                padding,
                stride,
                dilation,
                multiplier,
                activation,
            }),
            _ => None,
        }
    }
}
