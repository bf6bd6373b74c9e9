//! TFLite's output sizes and padding (SAME puts the odd padding pixel after).

use crate::Padding;

/// (output size, padding before) along one axis; an error for an empty input or kernel (a
/// hostile graph may declare them) or a window too large to compute.
pub(crate) fn axis(
    input: usize,
    kernel: usize,
    stride: usize,
    dilation: usize,
    padding: Padding,
) -> Result<(usize, usize), String> {
    let bad =
        || format!("window of {kernel} (stride {stride}, dilation {dilation}) over {input} pixels");
    let eff = kernel
        .checked_sub(1)
        .and_then(|k| k.checked_mul(dilation)?.checked_add(1))
        .filter(|_| input > 0 && stride > 0)
        .ok_or_else(bad)?;
    Ok(match padding {
        Padding::Same => {
            let out = input.div_ceil(stride);
            let span = ((out - 1) * stride).checked_add(eff).ok_or_else(bad)?;
            (out, span.saturating_sub(input) / 2)
        }
        Padding::Valid => (input.saturating_add(stride).saturating_sub(eff) / stride, 0),
    })
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
        assert_eq!(axis(224, 3, 2, 1, Padding::Same), Ok((112, 0)));
        assert_eq!(axis(7, 3, 1, 1, Padding::Same), Ok((7, 1)));
        assert_eq!(axis(8, 2, 2, 1, Padding::Same), Ok((4, 0)));
        assert_eq!(axis(7, 3, 1, 1, Padding::Valid), Ok((5, 0)));
    }

    #[test]
    fn empty_windows_are_errors() {
        assert!(axis(0, 3, 1, 1, Padding::Same).is_err());
        assert!(axis(7, 0, 1, 1, Padding::Valid).is_err());
        assert!(axis(7, usize::MAX, 1, 2, Padding::Same).is_err());
    }
}
