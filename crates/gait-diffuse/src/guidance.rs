//! Which denoising steps run classifier-free guidance and which run the
//! ControlNet: the cut-offs that save network calls (issue 20). Both follow
//! diffusers to the step, so the fixtures of tools/diffuse/make_cutoff_fixtures.py
//! hold: the ControlNet's `control_guidance_start` / `control_guidance_end`
//! (`controlnet_keep`), and CFG until `SDCFGCutoffCallback`'s cut-off step.

/// Cut-offs, as fractions of the loop's steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cutoffs {
    /// CFG runs on steps `0..=floor(n * guidance_end)`: diffusers' cut-off
    /// callback turns it off after the step it fires on. 1.0 keeps it on.
    pub guidance_end: f64,
    /// The ControlNet runs on step `i` of `n` unless `i / n < start` or
    /// `(i + 1) / n > end`; outside, diffusers multiplies its output by 0,
    /// so skipping the call gives the same result.
    pub control_start: f64,
    pub control_end: f64,
}

impl Default for Cutoffs {
    fn default() -> Self {
        Self {
            guidance_end: 1.0,
            control_start: 0.0,
            control_end: 1.0,
        }
    }
}

/// What one step of a loop of `n` runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StepPlan {
    /// Unconditional and conditional rows (CFG), or the conditional only.
    pub guided: bool,
    pub controlnet: bool,
}

impl Cutoffs {
    /// The plan of step `i` of a loop of `n` steps, when guidance is on at all.
    pub fn step(&self, i: usize, n: usize, guidance_on: bool) -> StepPlan {
        let (fi, fn_) = (i as f64, n as f64);
        // Python's int(n * ratio): truncation of the same double product.
        let cutoff = (fn_ * self.guidance_end) as usize;
        StepPlan {
            guided: guidance_on && i <= cutoff,
            controlnet: !(fi / fn_ < self.control_start || (fi + 1.0) / fn_ > self.control_end),
        }
    }

    /// Checks the ranges; the message names the key.
    pub fn validate(&self) -> Result<(), String> {
        let unit = |key: &str, v: f64| {
            if (0.0..=1.0).contains(&v) {
                Ok(())
            } else {
                Err(format!("regenerator.{key} = {v} must be in [0, 1]"))
            }
        };
        unit("guidance_end", self.guidance_end)?;
        unit("control_guidance_start", self.control_start)?;
        unit("control_guidance_end", self.control_end)?;
        if self.control_start >= self.control_end {
            return Err(format!(
                "regenerator.control_guidance_start = {} must be below control_guidance_end = {}",
                self.control_start, self.control_end
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cfg_runs_through_the_cutoff_step_as_diffusers_callback_does() {
        let c = Cutoffs {
            guidance_end: 0.5,
            ..Default::default()
        };
        let guided: Vec<bool> = (0..10).map(|i| c.step(i, 10, true).guided).collect();
        assert_eq!(guided.iter().filter(|g| **g).count(), 6);
        assert!(guided[5] && !guided[6]);
        assert!((0..10).all(|i| Cutoffs::default().step(i, 10, true).guided));
        assert!(!Cutoffs::default().step(0, 10, false).guided);
    }

    #[test]
    fn controlnet_keep_matches_diffusers_window() {
        let c = Cutoffs {
            control_start: 0.2,
            control_end: 0.8,
            ..Default::default()
        };
        let on: Vec<bool> = (0..10).map(|i| c.step(i, 10, true).controlnet).collect();
        assert_eq!(
            on,
            [
                false, false, true, true, true, true, true, true, false, false
            ]
        );
    }

    #[test]
    fn bad_ranges_name_the_key() {
        let e = Cutoffs {
            guidance_end: 1.5,
            ..Default::default()
        };
        assert!(e.validate().unwrap_err().contains("guidance_end = 1.5"));
        let e = Cutoffs {
            control_start: 0.6,
            control_end: 0.4,
            ..Default::default()
        };
        assert!(e.validate().unwrap_err().contains("control_guidance_start"));
    }
}
