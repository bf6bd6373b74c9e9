//! Explicit spatial PAD operators folded into the convolution that reads them.
//!
//! TFLite models (BlazePose among them) pad before each stride-2 convolution with a PAD
//! operator and then convolve with VALID padding. Our convolution kernels skip taps outside
//! the input, which is zero padding without the copy: the PAD steps were 6 % of BlazePose's
//! model time on the CPU (every padded tensor written whole, zeros included). A padded tap
//! adds 0 x weight to the sum, and adding zero leaves a float sum as it was, so the results
//! keep their bits (the signs of exact zeros aside).

use super::step::{Node, Step};

/// `nodes` with every PAD of height and width only whose output is read by one convolution or
/// depthwise convolution (with no padding of its own) and nothing else removed, that
/// convolution reading the PAD's input with the padding as its own.
pub(super) fn pads_into_windows(mut nodes: Vec<Node>, outputs: &[usize]) -> Vec<Node> {
    let mut readers = std::collections::HashMap::<usize, usize>::new();
    for node in &nodes {
        for &i in &node.inputs {
            *readers.entry(i).or_default() += 1;
        }
    }
    let mut removed = vec![false; nodes.len()];
    for j in 0..nodes.len() {
        let Some(&t) = nodes[j].inputs.first() else {
            continue;
        };
        let Some(i) = nodes[..j].iter().rposition(|n| n.output == t) else {
            continue;
        };
        let Some((before, source)) = spatial_pad(&nodes[i]) else {
            continue;
        };
        if readers.get(&t) != Some(&1) || outputs.contains(&t) {
            continue;
        }
        let own = match &mut nodes[j].step {
            Step::Conv(c) => &mut c.pad,
            Step::Depthwise(d) => &mut d.pad,
            _ => continue,
        };
        if *own != (0, 0) {
            continue;
        }
        *own = before;
        nodes[j].inputs[0] = source;
        removed[i] = true;
    }
    let mut keep = removed.iter().map(|r| !r);
    nodes.retain(|_| keep.next().unwrap_or(true));
    nodes
}

/// A PAD of an NHWC tensor's height and width only: its (top, left) padding and its input.
fn spatial_pad(node: &Node) -> Option<((usize, usize), usize)> {
    let Step::Pad(p) = &node.step else {
        return None;
    };
    match p[..] {
        [(0, 0), (top, _), (left, _), (0, 0)] => Some(((top, left), *node.inputs.first()?)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::depthwise::Depthwise;
    use crate::kernels::pad::pad;
    use crate::kernels::testutil::values;
    use crate::model::Activation;

    fn depthwise(pad: (usize, usize)) -> Depthwise {
        Depthwise {
            weights: values(3 * 3 * 8, 2),
            bias: values(8, 3),
            kernel: (3, 3),
            stride: (2, 2),
            dilation: (1, 1),
            pad,
            out_size: (5, 5),
            multiplier: 1,
            act: Activation::Relu6,
        }
    }

    fn node(step: Step, inputs: Vec<usize>, output: usize) -> Node {
        Node {
            step,
            inputs,
            output,
            act: Activation::None,
            last_use: Vec::new(),
        }
    }

    #[test]
    fn a_folded_pad_gives_the_same_bits() {
        let x = values(9 * 9 * 8, 1);
        let pads = [(0, 0), (1, 1), (1, 1), (0, 0)];
        let (padded, _) = pad(&x, &[1, 9, 9, 8], &pads).unwrap();
        let (a, _) = depthwise((0, 0)).run(&padded, &[1, 11, 11, 8]).unwrap();
        let (b, _) = depthwise((1, 1)).run(&x, &[1, 9, 9, 8]).unwrap();
        let bits = |v: &[f32]| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&a), bits(&b));
    }

    #[test]
    fn only_a_spatial_pad_read_once_is_folded() {
        let pads = vec![(0, 0), (1, 2), (1, 2), (0, 0)];
        let folded = pads_into_windows(
            vec![
                node(Step::Pad(pads.clone()), vec![0, 9], 1),
                node(Step::Depthwise(depthwise((0, 0))), vec![1, 7, 8], 2),
            ],
            &[2],
        );
        assert_eq!(folded.len(), 1);
        assert_eq!(folded[0].inputs, vec![0, 7, 8]);
        assert!(matches!(&folded[0].step, Step::Depthwise(d) if d.pad == (1, 1)));

        // Read twice (by the convolution and an add), or padding channels: kept.
        let read_twice = pads_into_windows(
            vec![
                node(Step::Pad(pads.clone()), vec![0, 9], 1),
                node(Step::Depthwise(depthwise((0, 0))), vec![1, 7, 8], 2),
                node(Step::Reshape(vec![1]), vec![1], 3),
            ],
            &[2, 3],
        );
        assert_eq!(read_twice.len(), 3);
        let channels = pads_into_windows(
            vec![
                node(
                    Step::Pad(vec![(0, 0), (0, 0), (0, 0), (0, 4)]),
                    vec![0, 9],
                    1,
                ),
                node(Step::Depthwise(depthwise((0, 0))), vec![1, 7, 8], 2),
            ],
            &[2],
        );
        assert_eq!(channels.len(), 2);
    }
}
