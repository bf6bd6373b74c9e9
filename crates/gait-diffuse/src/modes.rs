//! Image-to-image and inpainting from the original frame, as diffusers'
//! StableDiffusionControlNetImg2ImgPipeline and
//! StableDiffusionControlNetInpaintPipeline do: the frame's VAE latents are
//! noised to the start timestep that `strength` picks and denoised from there.
//! Inpainting with a 4-channel UNet (SD 1.5) puts the unmasked latents (noised
//! to the next timestep) back after every step; a 9-channel inpainting UNet
//! (runwayml/stable-diffusion-inpainting) instead sees the mask and the
//! masked frame's latents as extra input channels.

use std::path::Path;

use candle_core::{DType, Device, Tensor};
use serde::{Deserialize, Serialize};

use crate::DiffuseError;
use crate::keep_region::{Inpainting, KeepRegion, latent_mask};
use crate::model_config::INPAINT_UNET_CHANNELS;
use crate::pipeline::{ControlnetPipeline, DenoiseParams, Generated};
use crate::schedule::Scheduler;
use crate::tokenizer::ClipTokenizer;
use crate::weights::{MERGES_FILE, Models};

/// Where the denoising starts (`mode = "..."` in `[regenerator]`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RegenMode {
    /// From noise, conditioned on the edge map only (the paper).
    #[default]
    Text2img,
    /// From the frame, noised by `strength`: colour and layout are kept.
    Img2img,
    /// Only the leg mask built from the original frame's pose is redrawn.
    Inpaint,
}

impl RegenMode {
    /// The name used in the TOML.
    pub fn name(self) -> &'static str {
        match self {
            RegenMode::Text2img => "text2img",
            RegenMode::Img2img => "img2img",
            RegenMode::Inpaint => "inpaint",
        }
    }

    /// diffusers' default strength for the mode (its pipelines' `strength=`).
    pub fn default_strength(self) -> f64 {
        match self {
            RegenMode::Img2img => 0.8,
            RegenMode::Text2img | RegenMode::Inpaint => 1.0,
        }
    }

    /// True when the mode starts from the frame (needs the VAE encoder).
    pub fn uses_frame(self) -> bool {
        !matches!(self, RegenMode::Text2img)
    }
}

/// The first scheduler step run at `strength` (diffusers' `get_timesteps`:
/// `steps - min(int(steps * strength), steps)`); an error when `strength` is
/// outside (0, 1] or leaves no step to run.
pub fn begin_step(steps: usize, strength: f64) -> Result<usize, DiffuseError> {
    if !(strength > 0.0 && strength <= 1.0) {
        return Err(DiffuseError::Config(format!(
            "regenerator.strength = {strength} must be in (0, 1]"
        )));
    }
    let run = ((steps as f64 * strength) as usize).min(steps);
    if run == 0 {
        return Err(DiffuseError::Config(format!(
            "regenerator.strength = {strength} with steps = {steps} runs no denoising step \
             (steps * strength must be at least 1)"
        )));
    }
    Ok(steps - run)
}

impl ControlnetPipeline {
    /// As [`ControlnetPipeline::load`], with the VAE encoder that
    /// image-to-image and inpainting need.
    pub fn load_with_encoder(
        sd_dir: &Path,
        controlnet_dir: &Path,
        dtype: DType,
        device: &Device,
    ) -> Result<Self, DiffuseError> {
        let mut models = Models::load(sd_dir, controlnet_dir, dtype, device)?;
        models.load_vae_encoder(sd_dir, dtype, device)?;
        let tokenizer = ClipTokenizer::from_merges_file(&sd_dir.join(MERGES_FILE))?;
        Ok(Self::from_parts(Box::new(models), tokenizer, dtype, device))
    }

    /// Scaled latents of `images` `(B, 3, H, W)` in [-1, 1]: a sample
    /// `mean + std * eps` of the VAE's distribution with the caller's standard
    /// normals `eps` (what diffusers does when given a generator), times the
    /// VAE's scaling factor.
    pub fn encode_latents(&self, images: &Tensor, eps: &Tensor) -> Result<Tensor, DiffuseError> {
        let (mean, std) = self.models.encode_image(&images.to_dtype(self.dtype)?)?;
        let z = (mean + std.mul(&eps.to_dtype(self.dtype)?)?)?;
        Ok((z * self.models.vae_config().scaling_factor)?)
    }

    /// Image-to-image: the frames' latents (`eps` for the VAE sample) noised
    /// with `noise` to the start timestep of `strength`, then denoised under
    /// `control`. Returns images in [0, 1] as [`ControlnetPipeline::generate`].
    #[allow(clippy::too_many_arguments)]
    pub fn img2img(
        &self,
        context: &Tensor,
        control: &Tensor,
        images: &Tensor,
        eps: &Tensor,
        noise: &Tensor,
        strength: f64,
        p: &DenoiseParams,
    ) -> Result<Tensor, DiffuseError> {
        Ok(self
            .img2img_full(context, control, images, eps, noise, strength, p)?
            .images)
    }

    /// As [`Self::img2img`], keeping the final latents too.
    #[allow(clippy::too_many_arguments)]
    pub fn img2img_full(
        &self,
        context: &Tensor,
        control: &Tensor,
        images: &Tensor,
        eps: &Tensor,
        noise: &Tensor,
        strength: f64,
        p: &DenoiseParams,
    ) -> Result<Generated, DiffuseError> {
        let latents = self.encode_latents(images, eps)?;
        self.from_latents(context, control, &latents, noise, strength, p)
    }

    /// Inpainting: as [`Self::img2img`], but only where `mask` `(B, 1, H, W)`
    /// (1 = regenerate) is set; at strength 1 the start is pure noise, as in
    /// diffusers. A 9-channel inpainting UNet gets the mask and the masked
    /// frame's latents (same `eps`) as inputs instead of the blending.
    #[allow(clippy::too_many_arguments)]
    pub fn inpaint(
        &self,
        context: &Tensor,
        control: &Tensor,
        images: &Tensor,
        mask: &Tensor,
        eps: &Tensor,
        noise: &Tensor,
        strength: f64,
        p: &DenoiseParams,
    ) -> Result<Tensor, DiffuseError> {
        let begin = begin_step(p.steps, strength)?;
        let noise = noise.to_dtype(self.dtype)?;
        let sched = Scheduler::new(p.scheduler, p.steps);
        let lmask = latent_mask(&mask.to_dtype(self.dtype)?, self.vae_scale())?;
        let conditioned = self.models.unet_in_channels() == INPAINT_UNET_CHANNELS;
        // The frame's latents: the start point below strength 1, and the
        // known region a 4-channel UNet blends back in.
        let latents = if conditioned && strength >= 1.0 {
            None
        } else {
            Some(self.encode_latents(images, eps)?)
        };
        // DDIM's and UniPC's initial noise sigma is 1.
        let x = match &latents {
            Some(l) if strength < 1.0 => sched.add_noise(l, &noise, sched.timesteps()[begin])?,
            _ => noise.clone(),
        };
        let how = if conditioned {
            // diffusers: image * (mask < 0.5), encoded like the frame.
            let keep = mask.lt(0.5)?.to_dtype(images.dtype())?;
            let masked = images.broadcast_mul(&keep)?;
            Inpainting::Condition {
                mask: lmask,
                masked_latents: self.encode_latents(&masked, eps)?,
            }
        } else {
            Inpainting::Blend(KeepRegion {
                image_latents: latents.expect("encoded for a 4-channel UNet"),
                noise,
                mask: lmask,
            })
        };
        Ok(self
            .denoise(context, control, &x, p, begin, Some(&how))?
            .images)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn begin_step_follows_diffusers_get_timesteps() {
        assert_eq!(begin_step(3, 0.75).unwrap(), 1);
        assert_eq!(begin_step(20, 0.8).unwrap(), 4);
        assert_eq!(begin_step(20, 1.0).unwrap(), 0);
        assert_eq!(begin_step(10, 0.15).unwrap(), 9);
        for bad in [0.0, -0.1, 1.5, f64::NAN] {
            let err = begin_step(20, bad).unwrap_err().to_string();
            assert!(err.contains("strength"), "{err}");
        }
        let err = begin_step(3, 0.2).unwrap_err().to_string();
        assert!(err.contains("no denoising step"), "{err}");
    }
}
