//! The StableDiffusionControlNetPipeline loop: prompt embeddings with
//! classifier-free guidance, ControlNet residuals into the UNet at each
//! scheduler step, VAE decode to an image in [0, 1]. The networks come from a
//! [`DiffusionModels`] backend (candle or ONNX Runtime); the loop is the same.

use std::path::Path;

use candle_core::{DType, Device, Tensor};

use crate::DiffuseError;
use crate::models::DiffusionModels;
use crate::modes::Inpainting;
use crate::ort_models::OrtModels;
use crate::schedule::{Scheduler, SchedulerKind};
use crate::tokenizer::ClipTokenizer;
use crate::weights::{MERGES_FILE, Models};

/// Per-run knobs of the denoising loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DenoiseParams {
    pub steps: usize,
    /// Classifier-free guidance weight; guidance is off at 1 or below.
    pub guidance_scale: f64,
    /// Multiplies the ControlNet residuals.
    pub conditioning_scale: f64,
    pub scheduler: SchedulerKind,
}

/// SD 1.5 + ControlNet, loaded and ready to generate.
pub struct ControlnetPipeline {
    pub models: Box<dyn DiffusionModels>,
    pub tokenizer: ClipTokenizer,
    pub dtype: DType,
    pub device: Device,
}

impl ControlnetPipeline {
    /// Loads the candle models and tokenizer from diffusers-layout folders.
    pub fn load(
        sd_dir: &Path,
        controlnet_dir: &Path,
        dtype: DType,
        device: &Device,
    ) -> Result<Self, DiffuseError> {
        let models = Models::load(sd_dir, controlnet_dir, dtype, device)?;
        let tokenizer = ClipTokenizer::from_merges_file(&sd_dir.join(MERGES_FILE))?;
        Ok(Self::from_parts(Box::new(models), tokenizer, dtype, device))
    }

    /// Loads the ONNX exports of `tools/diffuse/export_onnx.py` from `onnx_dir`
    /// (f32 on ONNX Runtime) with the tokenizer merges at `merges`.
    pub fn load_ort(onnx_dir: &Path, merges: &Path) -> Result<Self, DiffuseError> {
        Self::load_ort_on(onnx_dir, merges, gait_core::Device::Cpu)
    }

    /// [`ControlnetPipeline::load_ort`] with ONNX Runtime on `device`.
    pub fn load_ort_on(
        onnx_dir: &Path,
        merges: &Path,
        device: gait_core::Device,
    ) -> Result<Self, DiffuseError> {
        let models = OrtModels::load_on(onnx_dir, device)?;
        let tokenizer = ClipTokenizer::from_merges_file(merges)?;
        Ok(Self::from_parts(
            Box::new(models),
            tokenizer,
            DType::F32,
            &Device::Cpu,
        ))
    }

    /// A pipeline on any backend; `dtype` is the type the backend computes in.
    pub fn from_parts(
        models: Box<dyn DiffusionModels>,
        tokenizer: ClipTokenizer,
        dtype: DType,
        device: &Device,
    ) -> Self {
        Self {
            models,
            tokenizer,
            dtype,
            device: device.clone(),
        }
    }

    /// Pixels per latent cell (8 for SD 1.5).
    pub fn vae_scale(&self) -> usize {
        self.models.vae_config().scale_factor()
    }

    /// Text-encoder hidden states `(1, 77, dim)` of a prompt.
    pub fn encode_prompt(&self, prompt: &str) -> Result<Tensor, DiffuseError> {
        let ids = self.tokenizer.encode(prompt);
        let ids = Tensor::new(ids.as_slice(), &self.device)?.unsqueeze(0)?;
        self.models.encode_text(&ids)
    }

    /// The cross-attention context for one image: `[negative; prompt]` when
    /// guidance is on (diffusers' order), else the prompt alone.
    pub fn context(
        &self,
        prompt: &str,
        negative: &str,
        guidance_scale: f64,
    ) -> Result<Tensor, DiffuseError> {
        let pos = self.encode_prompt(prompt)?;
        if guidance_scale > 1.0 {
            Ok(Tensor::cat(&[&self.encode_prompt(negative)?, &pos], 0)?)
        } else {
            Ok(pos)
        }
    }

    /// Denoises `latents` `(B, 4, h, w)` under `control` `(B, 3, 8h, 8w)` in
    /// [0, 1]; returns the decoded images `(B, 3, 8h, 8w)` in [0, 1] as f32.
    pub fn generate(
        &self,
        context: &Tensor,
        control: &Tensor,
        latents: &Tensor,
        p: &DenoiseParams,
    ) -> Result<Tensor, DiffuseError> {
        self.denoise(context, control, latents, p, 0, None)
    }

    /// The loop from scheduler step `begin` (image-to-image and inpainting
    /// skip the noisiest steps); `inpaint` says how inpainting keeps the
    /// known region.
    pub(crate) fn denoise(
        &self,
        context: &Tensor,
        control: &Tensor,
        latents: &Tensor,
        p: &DenoiseParams,
        begin: usize,
        inpaint: Option<&Inpainting>,
    ) -> Result<Tensor, DiffuseError> {
        let b = latents.dim(0)?;
        let guided = p.guidance_scale > 1.0;
        let copies = if guided { 2 } else { 1 };
        let unet_channels = self.models.unet_in_channels();
        let extra = match inpaint {
            Some(Inpainting::Condition {
                mask,
                masked_latents,
            }) => {
                let extra = Tensor::cat(&[mask, masked_latents], 1)?.to_dtype(self.dtype)?;
                Some(per_guidance_row(&extra, guided)?)
            }
            _ => None,
        };
        let expected = latents.dim(1)? + extra.as_ref().map_or(Ok(0), |e| e.dim(1))?;
        if unet_channels != expected {
            return Err(DiffuseError::Config(format!(
                "the UNet takes {unet_channels} input channels but this mode gives it {expected}: \
                 a 9-channel (inpainting) UNet needs regenerator.mode = \"inpaint\", the other \
                 modes a 4-channel UNet such as SD 1.5's"
            )));
        }
        if context.dim(0)? != copies {
            return Err(DiffuseError::Config(format!(
                "context has {} rows, guidance needs {copies}",
                context.dim(0)?
            )));
        }
        let (_, n, d) = context.dims3()?;
        // Rows: B unconditional then B conditional, as diffusers concatenates.
        let ctx = context
            .unsqueeze(1)?
            .broadcast_as((copies, b, n, d))?
            .reshape((copies * b, n, d))?
            .to_dtype(self.dtype)?;
        let control = per_guidance_row(&control.to_dtype(self.dtype)?, guided)?;
        let mut x = latents.to_dtype(self.dtype)?;
        let mut sched = Scheduler::new(p.scheduler, p.steps);
        let timesteps = sched.timesteps().get(begin..).unwrap_or_default().to_vec();
        sched.set_begin_index(begin);
        for (i, &t) in timesteps.iter().enumerate() {
            let input = per_guidance_row(&x, guided)?;
            let t = t as f64;
            let res = self
                .models
                .controlnet(&input, t, &ctx, &control, p.conditioning_scale)?;
            let eps = match &extra {
                Some(e) => self
                    .models
                    .unet(&Tensor::cat(&[&input, e], 1)?, t, &ctx, &res)?,
                None => self.models.unet(&input, t, &ctx, &res)?,
            };
            let eps = if guided {
                let u = eps.narrow(0, 0, b)?;
                let c = eps.narrow(0, b, b)?;
                (&u + ((c - &u)? * p.guidance_scale)?)?
            } else {
                eps
            };
            x = sched.step(&eps, &x)?;
            if let Some(Inpainting::Blend(k)) = inpaint {
                x = k.blend(&sched, &x, timesteps.get(i + 1).copied())?;
            }
        }
        let x = (x / self.models.vae_config().scaling_factor)?;
        let img = self.models.decode(&x)?;
        Ok(((img.to_dtype(DType::F32)? / 2.0)? + 0.5)?.clamp(0f32, 1f32)?)
    }
}

/// `t` once per guidance half (unconditional, conditional) when `guided`.
fn per_guidance_row(t: &Tensor, guided: bool) -> candle_core::Result<Tensor> {
    if guided {
        Tensor::cat(&[t, t], 0)
    } else {
        Ok(t.clone())
    }
}
