//! DeepCache (Ma, Fang & Wang, CVPR 2024): the UNet's deep features change
//! little between adjacent denoising steps, so they are computed on every
//! `interval`-th step only; on the steps between, the shallow branch (the
//! first skip connections and the last up layers) runs on the cached feature.
//! The step and layer rules are those of PyPI `deepcache` 0.1.1's
//! `DeepCacheSDHelper` (uniform skipping), which the fixtures of
//! tools/diffuse/make_speedup_fixtures.py come from.

use candle_core::Tensor;

/// Where the shallow branch leaves the UNet: DeepCache's `cache_branch_id`,
/// read as down stage `id / 3` and layer `id % 3` of that stage.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CacheBranch {
    pub block: usize,
    pub layer: usize,
}

impl CacheBranch {
    pub fn from_id(id: usize) -> Self {
        Self {
            block: id / 3,
            layer: id % 3,
        }
    }
}

/// DeepCache over one denoising loop: which steps are full, and the deep
/// feature the last full step left.
#[derive(Debug, Clone)]
pub struct DeepCache {
    interval: usize,
    branch: CacheBranch,
    feature: Option<Tensor>,
}

impl DeepCache {
    /// Full steps every `interval` steps (1: every step, no saving).
    pub fn new(interval: usize, branch: CacheBranch) -> Self {
        Self {
            interval: interval.max(1),
            branch,
            feature: None,
        }
    }

    /// What the UNet call of step `i` (counted from the loop's first step, as
    /// the helper counts from the first timestep it sees) does with the cache.
    pub fn step(&mut self, i: usize) -> CacheStep<'_> {
        CacheStep {
            branch: self.branch,
            reuse: !i.is_multiple_of(self.interval) && self.feature.is_some(),
            feature: &mut self.feature,
        }
    }

    pub fn branch(&self) -> CacheBranch {
        self.branch
    }

    /// True when step `i` runs the shallow branch only (its ControlNet call
    /// then needs only the shallow residuals).
    pub fn reuses(&self, i: usize) -> bool {
        !i.is_multiple_of(self.interval) && self.feature.is_some()
    }
}

/// One UNet call's use of the cache: fill it (a full step) or reuse it.
#[derive(Debug)]
pub struct CacheStep<'a> {
    pub branch: CacheBranch,
    pub reuse: bool,
    pub feature: &'a mut Option<Tensor>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn branch_ids_read_as_the_helper_reads_them() {
        assert_eq!(CacheBranch::from_id(0), CacheBranch { block: 0, layer: 0 });
        assert_eq!(CacheBranch::from_id(5), CacheBranch { block: 1, layer: 2 });
        assert_eq!(CacheBranch::from_id(9), CacheBranch { block: 3, layer: 0 });
    }

    #[test]
    fn full_steps_every_interval_and_only_after_a_fill() {
        let mut c = DeepCache::new(3, CacheBranch::from_id(0));
        assert!(!c.reuses(1), "nothing cached yet");
        *c.step(0).feature =
            Some(Tensor::zeros(1, candle_core::DType::F32, &candle_core::Device::Cpu).unwrap());
        let reuse: Vec<bool> = (0..7).map(|i| c.reuses(i)).collect();
        assert_eq!(reuse, [false, true, true, false, true, true, false]);
    }
}
