//! TFLite CONV_2D on NHWC activations as one gemm: [pixels, kh*kw*cin] x
//! [kh*kw*cin, cout] (1x1 convolutions read the input as is; others gather
//! their patches first), with bias and activation fused per block of rows.

use candle_core::{Shape, bail};

use super::{Out, act, nhwc};
use crate::model::Activation;

/// Output rows per gemm call: the block's output stays in L2 for the
/// bias/activation pass.
const BLOCK_FLOATS: usize = 32 * 1024;

/// A convolution with its weights packed as the gemm's right-hand side.
pub(crate) struct Conv {
    /// [kh * kw * cin, cout], row-major.
    w: Vec<f32>,
    bias: Vec<f32>,
    pub kernel: (usize, usize),
    pub stride: (usize, usize),
    pub dilation: (usize, usize),
    /// Zero padding before the first row and column.
    pub pad: (usize, usize),
    pub out_size: (usize, usize),
    cin: usize,
    pub act: Activation,
}

impl Conv {
    /// From TFLite's [cout, kh, kw, cin] weights; geometry fields default to
    /// a 1x1 stride-1 convolution over an `out_size` of (0, 0) (set them).
    pub fn new(
        ohwi: &[f32],
        dims: [usize; 4],
        bias: Vec<f32>,
        act: Activation,
    ) -> Result<Self, String> {
        let [o, kh, kw, i] = dims;
        let k = kh * kw * i;
        if ohwi.len() != o * k || bias.len() != o {
            return Err(format!(
                "conv2d: {} weights and {} biases for shape {dims:?}",
                ohwi.len(),
                bias.len()
            ));
        }
        let mut w = vec![0f32; k * o];
        for (oc, row) in ohwi.chunks_exact(k).enumerate() {
            for (j, v) in row.iter().enumerate() {
                w[j * o + oc] = *v;
            }
        }
        Ok(Self {
            w,
            bias,
            kernel: (kh, kw),
            stride: (1, 1),
            dilation: (1, 1),
            pad: (0, 0),
            out_size: (0, 0),
            cin: i,
            act,
        })
    }

    /// From a packed [cin, cout] matrix (row-major) and `cout` biases.
    pub fn pointwise(w: Vec<f32>, cin: usize, bias: Vec<f32>, act: Activation) -> Self {
        Self {
            w,
            bias,
            kernel: (1, 1),
            stride: (1, 1),
            dilation: (1, 1),
            pad: (0, 0),
            out_size: (0, 0),
            cin,
            act,
        }
    }

    fn is_pointwise(&self) -> bool {
        self.kernel == (1, 1) && self.stride == (1, 1) && self.pad == (0, 0)
    }

    /// Runs on a [1, h, w, cin] input.
    pub fn run(&self, x: &[f32], dims: &[usize]) -> Out {
        let (h, w, c) = nhwc(dims, "conv2d")?;
        let cout = self.bias.len();
        if c != self.cin || self.w.len() != self.kernel.0 * self.kernel.1 * c * cout {
            bail!("conv2d: weights do not fit input {dims:?}")
        }
        let (oh, ow) = if self.is_pointwise() {
            (h, w)
        } else {
            self.out_size
        };
        let patches;
        let lhs = if self.is_pointwise() {
            x
        } else {
            patches = self.im2col(x, h, w, c);
            &patches[..]
        };
        let k = self.kernel.0 * self.kernel.1 * c;
        // Filled block by block without zeroing first: the gemm writes every
        // value (zeroing the outputs was 8 % of a BlazePose frame).
        let total = oh * ow * cout;
        let mut out: Vec<f32> = Vec::with_capacity(total);
        let rows = (BLOCK_FLOATS / cout.max(1)).max(16);
        let pixels = oh * ow;
        for start in (0..pixels).step_by(rows) {
            let m = rows.min(pixels - start);
            let dst = out.spare_capacity_mut()[start * cout..][..m * cout]
                .as_mut_ptr()
                .cast::<f32>();
            // SAFETY: dst addresses m * cout values of `out`'s capacity, which
            // the gemm writes (it does not read them); the slice is made after.
            let dst = unsafe {
                gemm_rows(&lhs[start * k..][..m * k], &self.w, dst, m, k, cout);
                std::slice::from_raw_parts_mut(dst, m * cout)
            };
            act::bias_act(dst, &self.bias, self.act);
        }
        // SAFETY: the loop wrote all `total` values.
        unsafe { out.set_len(total) };
        Ok((out, Shape::from((1, oh, ow, cout))))
    }

    /// [oh * ow, kh * kw * c] patches, zeros where they leave the image.
    fn im2col(&self, x: &[f32], h: usize, w: usize, c: usize) -> Vec<f32> {
        let (kh, kw) = self.kernel;
        let (oh, ow) = self.out_size;
        let (sy, sx) = self.stride;
        let (dy, dx) = self.dilation;
        let mut p = vec![0f32; oh * ow * kh * kw * c];
        let mut rows = p.chunks_exact_mut(kh * kw * c);
        for oy in 0..oh {
            for ox in 0..ow {
                let Some(row) = rows.next() else { return p };
                for ky in 0..kh {
                    let iy = (oy * sy + ky * dy).wrapping_sub(self.pad.0);
                    if iy >= h {
                        continue;
                    }
                    for kx in 0..kw {
                        let ix = (ox * sx + kx * dx).wrapping_sub(self.pad.1);
                        if ix >= w {
                            continue;
                        }
                        row[(ky * kw + kx) * c..][..c]
                            .copy_from_slice(&x[(iy * w + ix) * c..][..c]);
                    }
                }
            }
        }
        p
    }
}

/// dst[m, n] = lhs[m, k] x rhs[k, n], all row-major; single-threaded (the
/// caller decides about threads, and rayon's spinning workers cost more than
/// they give on a loaded 2-core machine).
///
/// # Safety
/// `dst` must address `m * n` writable floats (it is written, not read).
unsafe fn gemm_rows(lhs: &[f32], rhs: &[f32], dst: *mut f32, m: usize, k: usize, n: usize) {
    assert!(lhs.len() >= m * k && rhs.len() >= k * n);
    // SAFETY: the inputs hold at least m*k and k*n floats (checked above), dst
    // m*n (the caller's promise), and the strides describe row-major matrices
    // of those sizes.
    unsafe {
        gemm::gemm(
            m,
            n,
            k,
            dst,
            1,
            n as isize,
            false,
            lhs.as_ptr(),
            1,
            k as isize,
            rhs.as_ptr(),
            1,
            n as isize,
            0.0,
            1.0,
            false,
            false,
            false,
            gemm::Parallelism::None,
        );
    }
}

#[cfg(test)]
mod tests {
    use candle_core::{Device, Tensor};

    use super::*;
    use crate::kernels::testutil::{max_diff, tensor};

    /// candle's NCHW conv2d on an NHWC input with TFLite-style padding.
    fn reference(x: &Tensor, w_ohwi: &Tensor, b: &Tensor, c: &Conv) -> Tensor {
        let (_, h, wd, _) = x.dims4().unwrap();
        let (oh, ow) = c.out_size;
        let (kh, kw) = c.kernel;
        let pb = ((oh - 1) * c.stride.0 + (kh - 1) * c.dilation.0 + 1).saturating_sub(h + c.pad.0);
        let pr = ((ow - 1) * c.stride.1 + (kw - 1) * c.dilation.1 + 1).saturating_sub(wd + c.pad.1);
        let x = x.permute((0, 3, 1, 2)).unwrap();
        let x = x.pad_with_zeros(2, c.pad.0, pb).unwrap();
        let x = x.pad_with_zeros(3, c.pad.1, pr).unwrap();
        let w = w_ohwi.permute((0, 3, 1, 2)).unwrap().contiguous().unwrap();
        let y = x.conv2d(&w, 0, c.stride.0, c.dilation.0, 1).unwrap();
        let n = b.dim(0).unwrap();
        let y = y.broadcast_add(&b.reshape((1, n, 1, 1)).unwrap()).unwrap();
        y.permute((0, 2, 3, 1)).unwrap().clamp(0f32, 6f32).unwrap()
    }

    fn check(
        (h, w, cin): (usize, usize, usize),
        cout: usize,
        k: usize,
        stride: usize,
        dil: usize,
        pad: usize,
        out: (usize, usize),
    ) {
        let x = tensor(&[1, h, w, cin], 1);
        let wt = tensor(&[cout, k, k, cin], 2);
        let b = tensor(&[cout], 3);
        let mut conv = Conv::new(
            &wt.flatten_all().unwrap().to_vec1::<f32>().unwrap(),
            [cout, k, k, cin],
            b.to_vec1::<f32>().unwrap(),
            Activation::Relu6,
        )
        .unwrap();
        conv.stride = (stride, stride);
        conv.dilation = (dil, dil);
        conv.pad = (pad, pad);
        conv.out_size = out;
        let xs = x.flatten_all().unwrap().to_vec1::<f32>().unwrap();
        let (v, shape) = conv.run(&xs, x.dims()).unwrap();
        let ours = Tensor::from_vec(v, shape, &Device::Cpu).unwrap();
        let d = max_diff(&ours, &reference(&x, &wt, &b, &conv));
        assert!(
            d < 1e-4,
            "{h}x{w}x{cin}->{cout} k{k} s{stride}: max diff {d}"
        );
    }

    #[test]
    fn pointwise_matches_candle_conv2d() {
        // More rows than one gemm block, so block boundaries are covered.
        check((37, 41, 13), 24, 1, 1, 1, 0, (37, 41));
        check((5, 3, 7), 2000, 1, 1, 1, 0, (5, 3));
    }

    #[test]
    fn strided_padded_conv_matches_candle_conv2d() {
        // TFLite SAME 3x3 stride 2 on 16x15: 8x8 out, nothing before, odd pixel after.
        check((16, 15, 3), 8, 3, 2, 1, 0, (8, 8));
        check((9, 9, 5), 6, 5, 1, 1, 2, (9, 9));
        check((11, 10, 4), 3, 3, 1, 2, 2, (11, 10));
    }
}
