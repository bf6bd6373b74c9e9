//! `init = "previous"` (this project's addition): a frame starts from the
//! previous frame's final latent noised to `strength`, an SDEdit start
//! (Meng et al. 2022) through the image-to-image path, so only the last
//! `steps * strength` steps run. Consecutive frames of a walk are nearly the
//! same picture; the ControlNet moves the limbs to the new frame's edges.
//! The latent is also the regenerator's state, saved with each frame.

use candle_core::{DType, Device, Tensor};

use crate::DiffuseError;
use crate::modes::begin_step;
use crate::pipeline::{ControlnetPipeline, DenoiseParams, Generated};
use crate::schedule::Scheduler;

/// Marks a saved state's bytes, with a version.
const MAGIC: &[u8; 8] = b"gaitprv1";

impl ControlnetPipeline {
    /// Denoises from `start` latents `(B, 4, h, w)` (the loop's scaled space)
    /// noised with `noise` to the start timestep of `strength`, as diffusers'
    /// img2img pipelines do when handed latents instead of an image.
    #[allow(clippy::too_many_arguments)]
    pub fn from_latents(
        &self,
        context: &Tensor,
        control: &Tensor,
        start: &Tensor,
        noise: &Tensor,
        strength: f64,
        p: &DenoiseParams,
    ) -> Result<Generated, DiffuseError> {
        let begin = begin_step(p.steps, strength)?;
        let sched = Scheduler::new(p.scheduler, p.steps);
        let x = sched.add_noise(
            &start.to_dtype(self.dtype)?,
            &noise.to_dtype(self.dtype)?,
            sched.timesteps()[begin],
        )?;
        self.denoise(context, control, &x, p, begin, None)
    }
}

/// A frame's final latent `(1, 4, h, w)` as state bytes: magic, the three
/// sizes (u32 LE), the values (f32 LE).
pub(crate) fn to_state(latent: &Tensor) -> Result<Vec<u8>, DiffuseError> {
    let (_, c, h, w) = latent.dims4()?;
    let values = latent
        .to_dtype(DType::F32)?
        .flatten_all()?
        .to_vec1::<f32>()?;
    let mut out = Vec::with_capacity(20 + 4 * values.len());
    out.extend_from_slice(MAGIC);
    for d in [c, h, w] {
        out.extend_from_slice(&(d as u32).to_le_bytes());
    }
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
    Ok(out)
}

/// The latent of [`to_state`]'s bytes; `None` when they are not such bytes.
pub(crate) fn from_state(bytes: &[u8]) -> Option<Tensor> {
    let rest = bytes.strip_prefix(MAGIC)?;
    let dim = |i: usize| -> Option<usize> {
        Some(u32::from_le_bytes(rest.get(4 * i..4 * i + 4)?.try_into().ok()?) as usize)
    };
    let (c, h, w) = (dim(0)?, dim(1)?, dim(2)?);
    let data = rest.get(12..)?;
    if c.checked_mul(h)?.checked_mul(w)?.checked_mul(4)? != data.len() {
        return None;
    }
    let values: Vec<f32> = data
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    Tensor::from_vec(values, (1, c, h, w), &Device::Cpu).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn state_bytes_round_trip_and_refuse_others() {
        let t = Tensor::arange(0f32, 24.0, &Device::Cpu)
            .unwrap()
            .reshape((1, 4, 2, 3))
            .unwrap();
        let s = to_state(&t).unwrap();
        let back = from_state(&s).unwrap();
        assert_eq!(back.dims4().unwrap(), (1, 4, 2, 3));
        assert_eq!(
            back.flatten_all().unwrap().to_vec1::<f32>().unwrap(),
            t.flatten_all().unwrap().to_vec1::<f32>().unwrap()
        );
        assert!(from_state(&s[..s.len() - 1]).is_none());
        assert!(from_state(b"not a state").is_none());
        let mut huge = s.clone();
        huge[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(from_state(&huge).is_none());
    }
}
