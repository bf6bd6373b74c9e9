//! TFLite RESIZE_BILINEAR on NHWC activations.

use candle_core::{Shape, bail};

use super::{Out, nhwc};

/// Per output index along one axis: (lower source, upper source, weight of upper).
pub(crate) fn taps(
    input: usize,
    output: usize,
    align: bool,
    half: bool,
) -> Vec<(usize, usize, f32)> {
    let scale = if align && output > 1 {
        (input - 1) as f32 / (output - 1) as f32
    } else {
        input as f32 / output as f32
    };
    (0..output)
        .map(|o| {
            let s = if half {
                (o as f32 + 0.5) * scale - 0.5
            } else {
                o as f32 * scale
            };
            let lo = (s.floor().max(0.0) as usize).min(input - 1);
            let hi = (s.ceil().max(0.0) as usize).min(input - 1);
            (lo, hi, s - lo as f32)
        })
        .collect()
}

/// A bilinear resize to `ys.len()` x `xs.len()` pixels.
pub(crate) struct Resize {
    pub ys: Vec<(usize, usize, f32)>,
    pub xs: Vec<(usize, usize, f32)>,
}

impl Resize {
    /// Runs on a [1, h, w, c] input.
    pub fn run(&self, x: &[f32], dims: &[usize]) -> Out {
        let (h, w, c) = nhwc(dims, "resize")?;
        let fits = |t: &[(usize, usize, f32)], n| t.iter().all(|&(lo, hi, _)| lo < n && hi < n);
        if !fits(&self.ys, h) || !fits(&self.xs, w) {
            bail!("resize: taps do not fit input {dims:?}")
        }
        let (oh, ow) = (self.ys.len(), self.xs.len());
        let mut out = vec![0f32; oh * ow * c];
        let mut pixels = out.chunks_exact_mut(c.max(1));
        let px = |y: usize, x0: usize| &x[(y * w + x0) * c..][..c];
        for &(y0, y1, fy) in &self.ys {
            for &(x0, x1, fx) in &self.xs {
                let Some(dst) = pixels.next() else { break };
                let (a, b, cc, d) = (px(y0, x0), px(y0, x1), px(y1, x0), px(y1, x1));
                for j in 0..c {
                    let top = a[j] + (b[j] - a[j]) * fx;
                    let bot = cc[j] + (d[j] - cc[j]) * fx;
                    dst[j] = top + (bot - top) * fy;
                }
            }
        }
        Ok((out, Shape::from((1, oh, ow, c))))
    }
}

#[cfg(test)]
mod tests {
    use candle_core::{Device, Tensor};

    use super::*;
    use crate::kernels::testutil::{max_diff, tensor};

    /// The same interpolation as two dense matrices applied with candle matmuls.
    fn matrix(t: &[(usize, usize, f32)], input: usize) -> Tensor {
        let mut m = vec![0f32; t.len() * input];
        for (o, &(lo, hi, f)) in t.iter().enumerate() {
            m[o * input + lo] += 1.0 - f;
            m[o * input + hi] += f;
        }
        Tensor::from_vec(m, (t.len(), input), &Device::Cpu).unwrap()
    }

    #[test]
    fn matches_interpolation_matrices() {
        let x = tensor(&[1, 5, 6, 3], 12);
        for (align, half) in [(false, false), (true, false), (false, true)] {
            let r = Resize {
                ys: taps(5, 11, align, half),
                xs: taps(6, 9, align, half),
            };
            let xv = x.flatten_all().unwrap().to_vec1::<f32>().unwrap();
            let (v, s) = r.run(&xv, x.dims()).unwrap();
            let ours = Tensor::from_vec(v, s, &Device::Cpu).unwrap();
            // [c, h, w] -> ry . x . rx^T
            let chw = x
                .squeeze(0)
                .unwrap()
                .permute((2, 0, 1))
                .unwrap()
                .contiguous()
                .unwrap();
            let ry = matrix(&r.ys, 5);
            let rxt = matrix(&r.xs, 6).t().unwrap().contiguous().unwrap();
            let want = ry
                .broadcast_matmul(&chw.broadcast_matmul(&rxt).unwrap())
                .unwrap();
            let want = want.permute((1, 2, 0)).unwrap().unsqueeze(0).unwrap();
            let d = max_diff(&ours, &want);
            assert!(d < 1e-5, "align {align} half {half}: {d}");
        }
    }
}
