//! Noise schedulers with diffusers' formulas for SD 1.5's training schedule
//! (scaled-linear betas 0.00085..0.012 over 1000 steps, `steps_offset = 1`,
//! `set_alpha_to_one = false`): DDIM (eta 0, "leading" spacing), UniPC
//! (order 2, bh2, data prediction, "linspace" spacing, lower order at the end)
//! and DPM-Solver++ 2M (diffusers' `DPMSolverMultistepScheduler`: order 2,
//! midpoint, "linspace" spacing, final sigma 0 so the last step is first order).

use candle_core::{Result, Tensor};
use serde::{Deserialize, Serialize};

const TRAIN_STEPS: usize = 1000;

/// Which scheduler drives the denoising loop (`scheduler = "..."`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SchedulerKind {
    Ddim,
    #[default]
    Unipc,
    /// DPM-Solver++ 2M (`scheduler = "dpmpp2m"`).
    Dpmpp2m,
}

impl SchedulerKind {
    /// The name used in the TOML.
    pub fn name(self) -> &'static str {
        match self {
            SchedulerKind::Ddim => "ddim",
            SchedulerKind::Unipc => "unipc",
            SchedulerKind::Dpmpp2m => "dpmpp2m",
        }
    }
}

/// `alphas_cumprod` of SD's scaled-linear beta schedule.
fn alphas_cumprod() -> Vec<f64> {
    let (a, b) = (0.00085f64.sqrt(), 0.012f64.sqrt());
    let mut acc = 1.0;
    (0..TRAIN_STEPS)
        .map(|i| {
            let s = a + (b - a) * i as f64 / (TRAIN_STEPS - 1) as f64;
            acc *= 1.0 - s * s;
            acc
        })
        .collect()
}

/// A scheduler prepared for a number of inference steps.
#[derive(Debug, Clone)]
pub struct Scheduler {
    kind: SchedulerKind,
    timesteps: Vec<usize>,
    acp: Vec<f64>,
    /// UniPC: sigma per step (then 0 at the end).
    sigmas: Vec<f64>,
    step_index: usize,
    outputs: Vec<Tensor>,
    last_sample: Option<Tensor>,
    last_order: usize,
}

impl Scheduler {
    pub fn new(kind: SchedulerKind, steps: usize) -> Self {
        let steps = steps.clamp(1, TRAIN_STEPS);
        let acp = alphas_cumprod();
        let timesteps: Vec<usize> = match kind {
            SchedulerKind::Ddim => {
                let ratio = TRAIN_STEPS / steps;
                (0..steps).rev().map(|i| i * ratio + 1).collect()
            }
            // np.linspace(0, 999, steps + 1).round() (ties to even), reversed, last dropped.
            SchedulerKind::Unipc | SchedulerKind::Dpmpp2m => (1..=steps)
                .rev()
                .map(|i| {
                    (i as f64 * (TRAIN_STEPS - 1) as f64 / steps as f64).round_ties_even() as usize
                })
                .collect(),
        };
        let mut sigmas: Vec<f64> = timesteps
            .iter()
            .map(|&t| ((1.0 - acp[t]) / acp[t]).sqrt())
            .collect();
        sigmas.push(0.0);
        Self {
            kind,
            timesteps,
            acp,
            sigmas,
            step_index: 0,
            outputs: Vec::new(),
            last_sample: None,
            last_order: 0,
        }
    }

    /// Timesteps from noisiest to cleanest.
    pub fn timesteps(&self) -> &[usize] {
        &self.timesteps
    }

    /// Starts at step `index` (image-to-image skips the noisiest steps).
    pub fn set_begin_index(&mut self, index: usize) {
        self.step_index = index;
    }

    /// Noises `x0` to the level of `timestep` (image-to-image start).
    pub fn add_noise(&self, x0: &Tensor, noise: &Tensor, timestep: usize) -> Result<Tensor> {
        let a = self.acp[timestep.min(TRAIN_STEPS - 1)];
        (x0 * a.sqrt())? + (noise * (1.0 - a).sqrt())?
    }

    /// One denoising step from the model's noise prediction `eps`.
    pub fn step(&mut self, eps: &Tensor, sample: &Tensor) -> Result<Tensor> {
        let out = match self.kind {
            SchedulerKind::Ddim => self.ddim(eps, sample),
            SchedulerKind::Unipc => self.unipc(eps, sample),
            SchedulerKind::Dpmpp2m => self.dpmpp2m(eps, sample),
        };
        self.step_index += 1;
        out
    }

    fn ddim(&self, eps: &Tensor, sample: &Tensor) -> Result<Tensor> {
        let t = self.timesteps[self.step_index.min(self.timesteps.len() - 1)];
        let ratio = TRAIN_STEPS / self.timesteps.len();
        let a_t = self.acp[t];
        let a_prev = if t >= ratio {
            self.acp[t - ratio]
        } else {
            self.acp[0]
        };
        let x0 = ((sample - (eps * (1.0 - a_t).sqrt())?)? / a_t.sqrt())?;
        (x0 * a_prev.sqrt())? + (eps * (1.0 - a_prev).sqrt())?
    }

    /// `(alpha_t, sigma_t, lambda_t)` of the VP SDE at step `i`.
    fn coeffs(&self, i: usize) -> (f64, f64, f64) {
        let s = self.sigmas[i];
        let alpha = 1.0 / (s * s + 1.0).sqrt();
        let sigma = s * alpha;
        (alpha, sigma, alpha.ln() - sigma.ln())
    }

    fn unipc(&mut self, eps: &Tensor, sample: &Tensor) -> Result<Tensor> {
        let i = self.step_index.min(self.timesteps.len() - 1);
        let (alpha_i, sigma_i, _) = self.coeffs(i);
        let m = ((sample - (eps * sigma_i)?)? / alpha_i)?;
        // Corrector (UniC) on the sample the last predictor produced.
        let sample = match (&self.last_sample, self.outputs.last()) {
            (Some(last), Some(m0)) if i > 0 => {
                let (alpha_t, sigma_t, lambda_t) = self.coeffs(i);
                let (_, sigma_s0, lambda_s0) = self.coeffs(i - 1);
                let h = lambda_t - lambda_s0;
                let hh = -h;
                let h_phi_1 = hh.exp_m1();
                let b_h = hh.exp_m1();
                let base = ((last * (sigma_t / sigma_s0))? - (m0 * (alpha_t * h_phi_1))?)?;
                let d1_t = (&m - m0)?;
                let corr = if self.last_order >= 2 && self.outputs.len() >= 2 && i >= 2 {
                    let (_, _, lambda_s1) = self.coeffs(i - 2);
                    let rk = (lambda_s1 - lambda_s0) / h;
                    let d1 = ((&self.outputs[self.outputs.len() - 2] - m0)? / rk)?;
                    let (b1, b2) = b_coeffs(hh, b_h);
                    let rho0 = (b1 - b2) / (1.0 - rk);
                    let rho1 = b1 - rho0;
                    ((d1 * rho0)? + (d1_t * rho1)?)?
                } else {
                    (d1_t * 0.5)?
                };
                (base - (corr * (alpha_t * b_h))?)?
            }
            _ => sample.clone(),
        };
        self.outputs.push(m);
        if self.outputs.len() > 2 {
            self.outputs.remove(0);
        }
        let remaining = self.timesteps.len() - i;
        let order = 2.min(remaining).min(self.outputs.len());
        self.last_order = order;
        self.last_sample = Some(sample.clone());
        // Predictor (UniP).
        let (alpha_t, sigma_t, lambda_t) = self.coeffs(i + 1);
        let (_, sigma_s0, lambda_s0) = self.coeffs(i);
        let h = lambda_t - lambda_s0;
        let hh = -h;
        let h_phi_1 = hh.exp_m1();
        let b_h = hh.exp_m1();
        let m0 = &self.outputs[self.outputs.len() - 1];
        let x = ((&sample * (sigma_t / sigma_s0))? - (m0 * (alpha_t * h_phi_1))?)?;
        if order == 2 && i >= 1 {
            let (_, _, lambda_s1) = self.coeffs(i - 1);
            let rk = (lambda_s1 - lambda_s0) / h;
            let d1 = ((&self.outputs[0] - m0)? / rk)?;
            x - (d1 * (alpha_t * b_h * 0.5))?
        } else {
            Ok(x)
        }
    }
}

impl Scheduler {
    /// DPM-Solver++ 2M: the data prediction `m`, then a first-order update
    /// at the first and last steps (the last goes to sigma 0) and the
    /// second-order midpoint update in between.
    fn dpmpp2m(&mut self, eps: &Tensor, sample: &Tensor) -> Result<Tensor> {
        let i = self.step_index.min(self.timesteps.len() - 1);
        let (alpha_s0, sigma_s0, lambda_s0) = self.coeffs(i);
        let m = ((sample - (eps * sigma_s0)?)? / alpha_s0)?;
        self.outputs.push(m);
        if self.outputs.len() > 2 {
            self.outputs.remove(0);
        }
        // At the last step sigma is 0: lambda is +inf and exp(-h) - 1 = -1.
        let (alpha_t, sigma_t, lambda_t) = self.coeffs(i + 1);
        let h = lambda_t - lambda_s0;
        let phi = (-h).exp_m1();
        let m0 = &self.outputs[self.outputs.len() - 1];
        let x = ((sample * (sigma_t / sigma_s0))? - (m0 * (alpha_t * phi))?)?;
        let last = i + 1 == self.timesteps.len();
        if self.outputs.len() < 2 || last {
            return Ok(x);
        }
        let (_, _, lambda_s1) = self.coeffs(i - 1);
        let r0 = (lambda_s0 - lambda_s1) / h;
        let d1 = ((m0 - &self.outputs[0])? / r0)?;
        x - (d1 * (0.5 * alpha_t * phi))?
    }
}

/// First two B(h) coefficients of UniPC's linear system (bh2 variant).
fn b_coeffs(hh: f64, b_h: f64) -> (f64, f64) {
    let h_phi_1 = hh.exp_m1();
    let mut h_phi_k = h_phi_1 / hh - 1.0;
    let b1 = h_phi_k / b_h;
    h_phi_k = h_phi_k / hh - 0.5;
    let b2 = h_phi_k * 2.0 / b_h;
    (b1, b2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ddim_leading_timesteps() {
        assert_eq!(
            Scheduler::new(SchedulerKind::Ddim, 4).timesteps(),
            &[751, 501, 251, 1]
        );
    }

    #[test]
    fn dpmpp2m_shares_unipc_timesteps() {
        assert_eq!(
            Scheduler::new(SchedulerKind::Dpmpp2m, 4).timesteps(),
            Scheduler::new(SchedulerKind::Unipc, 4).timesteps()
        );
    }

    #[test]
    fn unipc_linspace_timesteps() {
        assert_eq!(
            Scheduler::new(SchedulerKind::Unipc, 2).timesteps(),
            &[999, 500]
        );
    }
}
