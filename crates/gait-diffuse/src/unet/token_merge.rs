//! Token merging for Stable Diffusion (Bolya & Hoffman 2023, "Token Merging
//! for Fast Stable Diffusion"), as PyPI `tomesd` 0.1.3 applies it with its
//! defaults: in the transformer blocks at the UNet's full latent resolution
//! only, before self-attention, the most similar `ratio` of the tokens are
//! averaged into a destination token and copied back out after it.
//!
//! Destinations are one token of every 2x2 cell, picked at random when the
//! batch is even (tomesd turns the randomness off for odd batches, whose rows
//! cannot be guidance pairs). tomesd draws them from a torch generator forked
//! from the global state; we draw from SplitMix64 with a seed the caller sets
//! per image, and tools/diffuse/make_speedup_fixtures.py feeds tomesd the same
//! stream, so the fixtures are reproducible and ours equal them.

use candle_core::{D, DType, Device, Result, Tensor};

/// tomesd's defaults: stride of the destination grid, and merging only where
/// the latent is not downsampled.
const STRIDE: usize = 2;
const MAX_DOWNSAMPLE: usize = 1;

/// Token merging for one denoising loop: the ratio, the latent size of the
/// current UNet call and the random stream of destination picks.
#[derive(Debug, Clone)]
pub struct TokenMerge {
    ratio: f64,
    rng: SplitMix64,
    size: (usize, usize),
}

impl TokenMerge {
    /// Merges `ratio` of the tokens (tomesd's `ratio`); `seed` starts the
    /// destination picks.
    pub fn new(ratio: f64, seed: u64) -> Self {
        Self {
            ratio,
            rng: SplitMix64(seed),
            size: (0, 0),
        }
    }

    /// The latent `(h, w)` of the UNet call that follows (tomesd's pre-hook).
    pub fn set_size(&mut self, h: usize, w: usize) {
        self.size = (h, w);
    }

    /// The merge of a transformer block whose input tokens are `x` `(B, N, C)`,
    /// or none when the block's resolution is below the full one.
    pub fn plan(&mut self, x: &Tensor) -> Result<Option<MergePlan>> {
        let (b, n, _) = x.dims3()?;
        let (oh, ow) = self.size;
        if n == 0 || oh * ow == 0 {
            return Ok(None);
        }
        let downsample = ((oh * ow / n) as f64).sqrt().ceil() as usize;
        if downsample > MAX_DOWNSAMPLE {
            return Ok(None);
        }
        let (h, w) = (oh.div_ceil(downsample), ow.div_ceil(downsample));
        let r = (n as f64 * self.ratio) as usize;
        if r == 0 || h * w != n {
            return Ok(None);
        }
        let (dst, src) = self.split(h, w, b % 2 == 0);
        MergePlan::new(x, &dst, &src, r).map(Some)
    }

    /// Destination and source token indices, each ascending (the stable order
    /// of tomesd's argsort of its -1/0 buffer).
    fn split(&mut self, h: usize, w: usize, random: bool) -> (Vec<usize>, Vec<usize>) {
        let (hs, ws) = (h / STRIDE, w / STRIDE);
        let mut is_dst = vec![false; h * w];
        for cy in 0..hs {
            for cx in 0..ws {
                let k = if random {
                    (self.rng.next() % (STRIDE * STRIDE) as u64) as usize
                } else {
                    0
                };
                let (dy, dx) = (k / STRIDE, k % STRIDE);
                is_dst[(cy * STRIDE + dy) * w + cx * STRIDE + dx] = true;
            }
        }
        (0..h * w).partition(|&i| is_dst[i])
    }
}

/// The merge and unmerge of one block's tokens, the same for every tensor of
/// that block (tomesd computes it once from the block's input).
#[derive(Debug)]
pub struct MergePlan {
    /// Rows of the flattened `(B * N, C)` input kept as they are, then the
    /// destinations, batch after batch: the merged `(B, N - r, C)` layout.
    keep: Tensor,
    /// Destination rows, their global row in the merged output, the source
    /// rows averaged into them, and each destination's count (itself + sources).
    dst: Tensor,
    merged_src: Tensor,
    merged_into: Tensor,
    counts: Tensor,
    /// For every input token, the merged row its output comes from.
    unmerge: Tensor,
    shape: (usize, usize, usize),
}

impl MergePlan {
    fn new(x: &Tensor, dst: &[usize], src: &[usize], r: usize) -> Result<Self> {
        let (b, n, c) = x.dims3()?;
        let r = r.min(src.len());
        let metric = x.to_dtype(DType::F32)?;
        let metric = metric.broadcast_div(&metric.sqr()?.sum_keepdim(D::Minus1)?.sqrt()?)?;
        let dev = x.device();
        let a = metric.index_select(&index(src, dev)?, 1)?;
        let bb = metric.index_select(&index(dst, dev)?, 1)?;
        let scores = a.matmul(&bb.t()?.contiguous()?)?;
        let best = scores.max(D::Minus1)?;
        let best_dst = scores.argmax(D::Minus1)?.to_vec2::<u32>()?;
        let order = best.arg_sort_last_dim(false)?.to_vec2::<u32>()?;
        let m = n - r;
        let (mut keep, mut dst_rows, mut merged_src, mut merged_into) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut counts = vec![1f32; b * dst.len()];
        let mut unmerge = vec![0u32; b * n];
        for bi in 0..b {
            let (row, out) = (bi * n, bi * m);
            let unm = src.len() - r;
            for (k, &e) in order[bi][r..].iter().enumerate() {
                let t = src[e as usize];
                keep.push((row + t) as u32);
                unmerge[row + t] = (out + k) as u32;
            }
            for (j, &t) in dst.iter().enumerate() {
                dst_rows.push((row + t) as u32);
                unmerge[row + t] = (out + unm + j) as u32;
            }
            for &e in &order[bi][..r] {
                let t = src[e as usize];
                let j = best_dst[bi][e as usize] as usize;
                merged_src.push((row + t) as u32);
                merged_into.push((bi * dst.len() + j) as u32);
                counts[bi * dst.len() + j] += 1.0;
                unmerge[row + t] = (out + unm + j) as u32;
            }
        }
        let u32s = |v: Vec<u32>| {
            let n = v.len();
            Tensor::from_vec(v, n, dev)
        };
        let nd = counts.len();
        Ok(Self {
            keep: u32s(keep)?,
            dst: u32s(dst_rows)?,
            merged_src: u32s(merged_src)?,
            merged_into: u32s(merged_into)?,
            counts: Tensor::from_vec(counts, (nd, 1), dev)?,
            unmerge: u32s(unmerge)?,
            shape: (b, m, c),
        })
    }

    /// `(B, N, C)` tokens to the `(B, N - r, C)` merged ones: kept sources,
    /// then destinations averaged with the sources merged into them.
    pub fn merge(&self, x: &Tensor) -> Result<Tensor> {
        let (b, n, c) = x.dims3()?;
        let flat = x.reshape((b * n, c))?;
        let kept = flat.index_select(&self.keep, 0)?;
        let dst = flat.index_select(&self.dst, 0)?;
        let src = flat.index_select(&self.merged_src, 0)?;
        let summed = dst.index_add(&self.merged_into, &src, 0)?;
        let dst = summed.broadcast_div(&self.counts.to_dtype(x.dtype())?)?;
        let (_, m, _) = self.shape;
        let per_batch = |t: &Tensor| t.reshape((b, (), c));
        Tensor::cat(&[per_batch(&kept)?, per_batch(&dst)?], 1)?.reshape((b, m, c))
    }

    /// Merged `(B, N - r, C)` outputs back to `(B, N, C)`: each token takes the
    /// output of the row it was merged into (or its own).
    pub fn unmerge(&self, y: &Tensor) -> Result<Tensor> {
        let (b, m, c) = y.dims3()?;
        let n = self.unmerge.dim(0)? / b;
        y.reshape((b * m, c))?
            .index_select(&self.unmerge, 0)?
            .reshape((b, n, c))
    }
}

fn index(v: &[usize], dev: &Device) -> Result<Tensor> {
    Tensor::from_vec(
        v.iter().map(|&i| i as u32).collect::<Vec<_>>(),
        v.len(),
        dev,
    )
}

/// SplitMix64 (Steele, Lea & Flood 2014): small, seedable, and the same in
/// the fixture script.
#[derive(Debug, Clone)]
struct SplitMix64(u64);

impl SplitMix64 {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merge_then_unmerge_keeps_unmerged_tokens_and_averages_merged_ones() {
        let dev = Device::Cpu;
        // 4x4 tokens, 2 batch rows (random destinations), 3 channels.
        let x = Tensor::randn(0f32, 1.0, (2, 16, 3), &dev).unwrap();
        let mut tm = TokenMerge::new(0.5, 9);
        tm.set_size(4, 4);
        let plan = tm.plan(&x).unwrap().expect("full resolution merges");
        let merged = plan.merge(&x).unwrap();
        assert_eq!(merged.dims3().unwrap(), (2, 8, 3));
        let back = plan.unmerge(&merged).unwrap();
        assert_eq!(back.dims3().unwrap(), (2, 16, 3));
        // Every output row is some merged row, and the mean of the merged rows
        // weighted by how many inputs they stand for is the input's mean.
        let total_in = x.sum_all().unwrap().to_scalar::<f32>().unwrap();
        let total_back = back.sum_all().unwrap().to_scalar::<f32>().unwrap();
        assert!(
            (total_in - total_back).abs() < 1e-3,
            "{total_in} {total_back}"
        );
    }

    #[test]
    fn lower_resolutions_and_odd_batches() {
        let dev = Device::Cpu;
        let mut tm = TokenMerge::new(0.5, 1);
        tm.set_size(8, 8);
        let low = Tensor::zeros((2, 16, 4), DType::F32, &dev).unwrap();
        assert!(tm.plan(&low).unwrap().is_none());
        // Odd batch: the top-left token of each cell, no draw from the stream.
        let before = tm.rng.clone();
        let (dst, src) = tm.split(4, 4, false);
        assert_eq!(dst, vec![0, 2, 8, 10]);
        assert_eq!(src.len(), 12);
        assert_eq!(before.0, tm.rng.0);
    }
}
