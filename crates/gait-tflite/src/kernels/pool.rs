//! TFLite MAX_POOL_2D and AVERAGE_POOL_2D on NHWC activations (padding taps
//! are skipped: ignored by the max, not counted by the average).

use candle_core::Shape;

use super::{Out, act, nhwc};
use crate::model::Activation;

/// A pooling window's geometry.
pub(crate) struct Pool {
    pub max: bool,
    pub filter: (usize, usize),
    pub stride: (usize, usize),
    /// Padding before the first row and column.
    pub pad: (usize, usize),
    pub out_size: (usize, usize),
    pub act: Activation,
}

impl Pool {
    /// Runs on a [1, h, w, c] input.
    pub fn run(&self, x: &[f32], dims: &[usize]) -> Out {
        let (h, w, c) = nhwc(dims, "pool")?;
        let (oh, ow) = self.out_size;
        let mut out = vec![0f32; oh * ow * c];
        let mut pixels = out.chunks_exact_mut(c.max(1));
        for oy in 0..oh {
            for ox in 0..ow {
                let Some(dst) = pixels.next() else { break };
                dst.fill(if self.max { f32::NEG_INFINITY } else { 0.0 });
                let mut n = 0usize;
                for ky in 0..self.filter.0 {
                    let iy = (oy * self.stride.0 + ky).wrapping_sub(self.pad.0);
                    if iy >= h {
                        continue;
                    }
                    for kx in 0..self.filter.1 {
                        let ix = (ox * self.stride.1 + kx).wrapping_sub(self.pad.1);
                        if ix >= w {
                            continue;
                        }
                        n += 1;
                        let src = &x[(iy * w + ix) * c..][..c];
                        if self.max {
                            dst.iter_mut().zip(src).for_each(|(d, s)| *d = d.max(*s));
                        } else {
                            dst.iter_mut().zip(src).for_each(|(d, s)| *d += s);
                        }
                    }
                }
                if !self.max && n > 0 {
                    let inv = 1.0 / n as f32;
                    dst.iter_mut().for_each(|d| *d *= inv);
                }
                act::apply(self.act, dst);
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

    fn ours(p: &Pool, x: &Tensor) -> Tensor {
        let xv = x.flatten_all().unwrap().to_vec1::<f32>().unwrap();
        let (v, s) = p.run(&xv, x.dims()).unwrap();
        Tensor::from_vec(v, s, &Device::Cpu).unwrap()
    }

    #[test]
    fn matches_candle_pools() {
        let x = tensor(&[1, 7, 8, 6], 11);
        let nchw = x.permute((0, 3, 1, 2)).unwrap();
        // SAME 2x2 stride 2 on 7 rows: the last window hangs over the edge;
        // candle pads by repeating the edge, which leaves the max unchanged.
        let p = Pool {
            max: true,
            filter: (2, 2),
            stride: (2, 2),
            pad: (0, 0),
            out_size: (4, 4),
            act: Activation::None,
        };
        let padded = nchw.pad_with_same(2, 0, 1).unwrap();
        let want = padded.max_pool2d_with_stride((2, 2), (2, 2)).unwrap();
        let want = want.permute((0, 2, 3, 1)).unwrap();
        assert!(max_diff(&ours(&p, &x), &want) < 1e-7);
        // VALID 3x3 stride 1 average.
        let p = Pool {
            max: false,
            filter: (3, 3),
            stride: (1, 1),
            pad: (0, 0),
            out_size: (5, 6),
            act: Activation::None,
        };
        let want = nchw.avg_pool2d_with_stride((3, 3), (1, 1)).unwrap();
        let want = want.permute((0, 2, 3, 1)).unwrap();
        assert!(max_diff(&ours(&p, &x), &want) < 1e-6);
    }
}
