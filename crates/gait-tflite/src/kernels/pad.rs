//! TFLite PAD with zeros on a contiguous tensor of any rank, in one pass
//! (candle's `pad_with_zeros` concatenates once per padded axis).

use candle_core::{Shape, bail};

use super::Out;

/// Pads `x` (shape `dims`) by `pads[axis] = (before, after)`.
pub(crate) fn pad(x: &[f32], dims: &[usize], pads: &[(usize, usize)]) -> Out {
    if pads.len() != dims.len() {
        bail!("pad: {} paddings for shape {dims:?}", pads.len())
    }
    let out_dims: Vec<usize> = dims.iter().zip(pads).map(|(d, (a, b))| d + a + b).collect();
    let total = out_dims.iter().product();
    // Written in order, zeros and rows appended as they come: zeroing the
    // whole output first and copying the rows in after was two passes.
    let mut out = Vec::with_capacity(total);
    if x.is_empty() {
        out.resize(total, 0.0);
    } else {
        append_padded(&mut out, x, dims, pads, &out_dims);
    }
    debug_assert_eq!(out.len(), total);
    Ok((out, Shape::from(out_dims)))
}

/// Appends `x` (shape `dims`, outermost axis first) padded by `pads` to `out`.
fn append_padded(
    out: &mut Vec<f32>,
    x: &[f32],
    dims: &[usize],
    pads: &[(usize, usize)],
    out_dims: &[usize],
) {
    let (before, after) = pads[0];
    // Values in one step of this axis, in the output.
    let step: usize = out_dims[1..].iter().product();
    out.resize(out.len() + before * step, 0.0);
    if dims.len() == 1 {
        out.extend_from_slice(x);
    } else {
        for part in x.chunks_exact(x.len() / dims[0]) {
            append_padded(out, part, &dims[1..], &pads[1..], &out_dims[1..]);
        }
    }
    out.resize(out.len() + after * step, 0.0);
}

#[cfg(test)]
mod tests {
    use candle_core::{Device, Tensor};

    use super::*;
    use crate::kernels::testutil::{max_diff, tensor};

    #[test]
    fn matches_candle_pad_with_zeros() {
        let x = tensor(&[1, 3, 4, 5], 13);
        let pads = [(0, 0), (1, 2), (0, 1), (0, 3)];
        let xv = x.flatten_all().unwrap().to_vec1::<f32>().unwrap();
        let (v, s) = pad(&xv, x.dims(), &pads).unwrap();
        let ours = Tensor::from_vec(v, s, &Device::Cpu).unwrap();
        let mut want = x.clone();
        for (d, &(a, b)) in pads.iter().enumerate() {
            want = want.pad_with_zeros(d, a, b).unwrap();
        }
        assert_eq!(max_diff(&ours, &want), 0.0);
        assert!(pad(&xv, x.dims(), &pads[..3]).is_err());
    }
}
