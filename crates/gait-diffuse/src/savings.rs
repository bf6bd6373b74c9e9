//! The training-free savings inside the denoising loop's network calls
//! (issue 30): DeepCache's reuse of deep UNet features between full steps and
//! token merging in the full-resolution attention, with their `[regenerator]`
//! keys' ranges. The loop asks [`LoopSavings`] what each step's calls do.

use crate::unet::{CacheBranch, DeepCache, TokenMerge, UnetSavings};

/// Settings of the savings (all off by default).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Savings {
    /// DeepCache: a full UNet step every `cache_interval` steps (1: off).
    pub cache_interval: usize,
    /// DeepCache's `cache_branch_id`: where the shallow branch leaves the UNet.
    pub cache_branch: usize,
    /// tomesd's `ratio` of tokens merged before self-attention (0: off).
    pub token_merge_ratio: f64,
    /// Seed of token merging's random destination picks.
    pub merge_seed: u64,
}

/// Highest `cache_branch` of SD 1.5's UNet (4 down stages, 3 layers each).
pub const MAX_CACHE_BRANCH: usize = 11;
/// tomesd's recommended ceiling is 0.5 and its hard one 0.75; the 0.9.
pub const MAX_MERGE_RATIO: f64 = 0.9;

impl Default for Savings {
    fn default() -> Self {
        Self {
            cache_interval: 1,
            cache_branch: 0,
            token_merge_ratio: 0.0,
            merge_seed: 0,
        }
    }
}

impl Savings {
    /// True when any saving is on.
    pub fn any(&self) -> bool {
        self.cache_interval > 1 || self.token_merge_ratio > 0.0
    }

    /// Checks the ranges against a loop of `steps`; the message names the key.
    pub fn validate(&self, steps: usize) -> Result<(), String> {
        if self.cache_interval < 1 || self.cache_interval > steps {
            return Err(format!(
                "regenerator.cache_interval = {} must be in 1..={steps} (regenerator.steps)",
                self.cache_interval
            ));
        }
        if self.cache_branch > MAX_CACHE_BRANCH {
            return Err(format!(
                "regenerator.cache_branch = {} must be in 0..={MAX_CACHE_BRANCH}",
                self.cache_branch
            ));
        }
        let r = self.token_merge_ratio;
        if !(0.0..=MAX_MERGE_RATIO).contains(&r) {
            return Err(format!(
                "regenerator.token_merge_ratio = {r} must be in [0, {MAX_MERGE_RATIO}]"
            ));
        }
        Ok(())
    }

    /// The DeepCache branch, when DeepCache is on.
    pub fn branch(&self) -> Option<CacheBranch> {
        (self.cache_interval > 1).then(|| CacheBranch::from_id(self.cache_branch))
    }
}

/// The savings' state over one denoising loop.
pub(crate) struct LoopSavings {
    cache: Option<DeepCache>,
    merge: Option<TokenMerge>,
}

impl LoopSavings {
    pub fn new(s: &Savings) -> Self {
        Self {
            cache: s.branch().map(|b| DeepCache::new(s.cache_interval, b)),
            merge: (s.token_merge_ratio > 0.0)
                .then(|| TokenMerge::new(s.token_merge_ratio, s.merge_seed)),
        }
    }

    /// The branch whose shallow residuals step `i`'s ControlNet call needs,
    /// when step `i` is a shallow one.
    pub fn shallow(&self, i: usize) -> Option<CacheBranch> {
        let c = self.cache.as_ref()?;
        c.reuses(i).then(|| c.branch())
    }

    /// What step `i`'s UNet call saves.
    pub fn unet(&mut self, i: usize) -> UnetSavings<'_> {
        UnetSavings {
            cache: self.cache.as_mut().map(|c| c.step(i)),
            merge: self.merge.as_mut(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_values_name_the_key() {
        let bad = |s: Savings| s.validate(8).unwrap_err();
        let d = Savings::default();
        assert!(
            bad(Savings {
                cache_interval: 0,
                ..d
            })
            .contains("cache_interval = 0")
        );
        assert!(
            bad(Savings {
                cache_interval: 9,
                ..d
            })
            .contains("cache_interval = 9")
        );
        assert!(
            bad(Savings {
                cache_branch: 12,
                ..d
            })
            .contains("cache_branch")
        );
        assert!(
            bad(Savings {
                token_merge_ratio: 0.95,
                ..d
            })
            .contains("token_merge_ratio")
        );
        assert!(
            bad(Savings {
                token_merge_ratio: -0.1,
                ..d
            })
            .contains("token_merge_ratio")
        );
        assert!(
            Savings {
                cache_interval: 8,
                token_merge_ratio: 0.9,
                ..d
            }
            .validate(8)
            .is_ok()
        );
        assert!(!d.any());
    }
}
