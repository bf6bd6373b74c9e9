//! The StableDiffusionControlNetPipeline loop: prompt embeddings with
//! classifier-free guidance, ControlNet residuals into the UNet at each
//! scheduler step, VAE decode to an image in [0, 1]. The networks come from a
//! [`DiffusionModels`] backend (candle or ONNX Runtime); the loop is the same.

use std::path::Path;

use candle_core::{DType, Device, Tensor};

use crate::DiffuseError;
use crate::controlnet::ControlResiduals;
use crate::guidance::{Cutoffs, StepPlan};
use crate::keep_region::Inpainting;
use crate::models::DiffusionModels;
use crate::ort_models::OrtModels;
use crate::savings::{LoopSavings, Savings};
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
    /// Steps without CFG or without the ControlNet (1, 0, 1: none).
    pub cutoffs: Cutoffs,
    /// DeepCache and token merging (default: off).
    pub savings: Savings,
}

/// What a denoising loop gives: images `(B, 3, H, W)` in [0, 1] (f32) and
/// the final latents `(B, 4, h, w)` they were decoded from, in the loop's
/// (scaled) space, as diffusers' `output_type="latent"`.
#[derive(Debug, Clone)]
pub struct Generated {
    pub images: Tensor,
    pub latents: Tensor,
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
        Ok(self.denoise(context, control, latents, p, 0, None)?.images)
    }

    /// As [`Self::generate`], keeping the final latents too.
    pub fn generate_full(
        &self,
        context: &Tensor,
        control: &Tensor,
        latents: &Tensor,
        p: &DenoiseParams,
    ) -> Result<Generated, DiffuseError> {
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
    ) -> Result<Generated, DiffuseError> {
        let b = latents.dim(0)?;
        let guided = p.guidance_scale > 1.0;
        let extra = match inpaint {
            Some(Inpainting::Condition {
                mask,
                masked_latents,
            }) => Some(Tensor::cat(&[mask, masked_latents], 1)?.to_dtype(self.dtype)?),
            _ => None,
        };
        self.check_inputs(context, latents, extra.as_ref(), guided)?;
        let rows = Rows::new(self, context, control, extra, b, guided)?;
        let mut x = latents.to_dtype(self.dtype)?;
        let mut sched = Scheduler::new(p.scheduler, p.steps);
        let timesteps = sched.timesteps().get(begin..).unwrap_or_default().to_vec();
        sched.set_begin_index(begin);
        let mut savings = LoopSavings::new(&p.savings);
        for (i, &t) in timesteps.iter().enumerate() {
            let plan = p.cutoffs.step(i, timesteps.len(), guided);
            let step = Step {
                i,
                t: t as f64,
                plan,
            };
            let eps = self.predict_noise(&rows, &x, step, p, &mut savings)?;
            x = sched.step(&eps, &x)?;
            if let Some(Inpainting::Blend(k)) = inpaint {
                x = k.blend(&sched, &x, timesteps.get(i + 1).copied())?;
            }
        }
        let img = self
            .models
            .decode(&(&x / self.models.vae_config().scaling_factor)?)?;
        Ok(Generated {
            images: ((img.to_dtype(DType::F32)? / 2.0)? + 0.5)?.clamp(0f32, 1f32)?,
            latents: x,
        })
    }

    /// The UNet's input channels and the context's rows fit this run.
    fn check_inputs(
        &self,
        context: &Tensor,
        latents: &Tensor,
        extra: Option<&Tensor>,
        guided: bool,
    ) -> Result<(), DiffuseError> {
        let unet_channels = self.models.unet_in_channels();
        let expected = latents.dim(1)? + extra.map_or(Ok(0), |e| e.dim(1))?;
        if unet_channels != expected {
            return Err(DiffuseError::Config(format!(
                "the UNet takes {unet_channels} input channels but this mode gives it {expected}: \
                 a 9-channel (inpainting) UNet needs regenerator.mode = \"inpaint\", the other \
                 modes a 4-channel UNet such as SD 1.5's"
            )));
        }
        let copies = if guided { 2 } else { 1 };
        if context.dim(0)? != copies {
            return Err(DiffuseError::Config(format!(
                "context has {} rows, guidance needs {copies}",
                context.dim(0)?
            )));
        }
        Ok(())
    }

    /// One step's noise prediction: ControlNet (when the plan runs it; its
    /// shallow part on a DeepCache shallow step), UNet, and the guidance mix
    /// (when the plan guides).
    fn predict_noise(
        &self,
        rows: &Rows,
        x: &Tensor,
        step: Step,
        p: &DenoiseParams,
        savings: &mut LoopSavings,
    ) -> Result<Tensor, DiffuseError> {
        let (ctx, control, extra) = rows.get(step.plan.guided);
        let input = per_guidance_row(x, step.plan.guided)?;
        let (t, scale) = (step.t, p.conditioning_scale);
        let res: Option<ControlResiduals> = match (step.plan.controlnet, savings.shallow(step.i)) {
            (false, _) => None,
            (true, None) => Some(self.models.controlnet(&input, t, ctx, control, scale)?),
            (true, Some(b)) => Some(
                self.models
                    .controlnet_shallow(&input, t, ctx, control, scale, b)?,
            ),
        };
        let unet_input = match extra {
            Some(e) => Tensor::cat(&[&input, e], 1)?,
            None => input,
        };
        let eps =
            self.models
                .unet_saving(&unet_input, t, ctx, res.as_ref(), savings.unet(step.i))?;
        if !step.plan.guided {
            return Ok(eps);
        }
        let b = x.dim(0)?;
        let u = eps.narrow(0, 0, b)?;
        let c = eps.narrow(0, b, b)?;
        Ok((&u + ((c - &u)? * p.guidance_scale)?)?)
    }
}

/// One step of the loop: its index from the loop's first step, timestep and plan.
#[derive(Debug, Clone, Copy)]
struct Step {
    i: usize,
    t: f64,
    plan: StepPlan,
}

/// The per-row inputs of the networks, with guidance (unconditional rows then
/// conditional ones, as diffusers concatenates) and without (after the CFG
/// cut-off: the conditional rows only).
struct Rows {
    guided: Option<(Tensor, Tensor, Option<Tensor>)>,
    single: (Tensor, Tensor, Option<Tensor>),
}

impl Rows {
    fn new(
        pipe: &ControlnetPipeline,
        context: &Tensor,
        control: &Tensor,
        extra: Option<Tensor>,
        b: usize,
        guided: bool,
    ) -> Result<Self, DiffuseError> {
        let (copies, n, d) = context.dims3()?;
        let per_row = |c: &Tensor| -> candle_core::Result<Tensor> {
            c.unsqueeze(0)?
                .broadcast_as((b, n, d))?
                .contiguous()?
                .to_dtype(pipe.dtype)
        };
        let control = control.to_dtype(pipe.dtype)?;
        // The conditional prompt is the last row of the context.
        let single = (
            per_row(&context.get(copies - 1)?)?,
            control.clone(),
            extra.clone(),
        );
        let guided = if guided {
            let ctx = Tensor::cat(&[per_row(&context.get(0)?)?, single.0.clone()], 0)?;
            let extra = extra.map(|e| per_guidance_row(&e, true)).transpose()?;
            Some((ctx, per_guidance_row(&control, true)?, extra))
        } else {
            None
        };
        Ok(Self { guided, single })
    }

    /// Context, control image and inpainting channels for a step.
    fn get(&self, guided: bool) -> (&Tensor, &Tensor, Option<&Tensor>) {
        let r = match (&self.guided, guided) {
            (Some(g), true) => g,
            _ => &self.single,
        };
        (&r.0, &r.1, r.2.as_ref())
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
