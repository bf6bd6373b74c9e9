//! TFLite's output sizes and padding (SAME puts the odd padding pixel after).

use crate::Padding;

/// (output size, padding before) along one axis.
pub(crate) fn axis(
    input: usize,
    kernel: usize,
    stride: usize,
    dilation: usize,
    padding: Padding,
) -> (usize, usize) {
    let eff = (kernel - 1) * dilation + 1;
    match padding {
        Padding::Same => {
            let out = input.div_ceil(stride);
            let total = ((out - 1) * stride + eff).saturating_sub(input);
            (out, total / 2)
        }
        Padding::Valid => ((input + stride).saturating_sub(eff) / stride, 0),
    }
}

/// The NCHW axis of TFLite's NHWC axis `axis` in a tensor of `rank` (only
/// 4-D tensors are stored NCHW).
pub(crate) fn nchw_axis(axis: usize, rank: usize) -> usize {
    match (rank, axis) {
        (4, 1) => 2,
        (4, 2) => 3,
        (4, 3) => 1,
        _ => axis,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_and_valid() {
        // 3x3 stride 2 on 224: 112 out, pad 0 before, 1 after.
        assert_eq!(axis(224, 3, 2, 1, Padding::Same), (112, 0));
        assert_eq!(axis(7, 3, 1, 1, Padding::Same), (7, 1));
        assert_eq!(axis(8, 2, 2, 1, Padding::Same), (4, 0));
        assert_eq!(axis(7, 3, 1, 1, Padding::Valid), (5, 0));
    }
}
