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
    let mut out = vec![0f32; out_dims.iter().product()];
    if x.is_empty() {
        return Ok((out, Shape::from(out_dims)));
    }
    let r = dims.len();
    let inner = dims[r - 1];
    // Copy each innermost row of the input to its place in the output.
    let mut idx = vec![0usize; r - 1];
    for row in x.chunks_exact(inner) {
        let mut off = 0;
        for d in 0..r - 1 {
            off = off * out_dims[d] + idx[d] + pads[d].0;
        }
        off = off * out_dims[r - 1] + pads[r - 1].0;
        out[off..off + inner].copy_from_slice(row);
        for d in (0..r - 1).rev() {
            idx[d] += 1;
            if idx[d] < dims[d] {
                break;
            }
            idx[d] = 0;
        }
    }
    Ok((out, Shape::from(out_dims)))
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
