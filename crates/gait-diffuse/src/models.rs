//! The four network calls of the ControlNet pipeline, behind one trait so the
//! same denoising loop (tokenizer, guidance, schedulers, noise, batches) runs
//! on candle ([`Models`]) and on ONNX Runtime ([`crate::OrtModels`]).
//! Tensors cross the trait as candle CPU tensors in the pipeline's dtype.

use candle_core::{DType, Tensor};

use crate::DiffuseError;
use crate::controlnet::ControlResiduals;
use crate::model_config::VaeConfig;
use crate::savings::Savings;
use crate::unet::{CacheBranch, UnetSavings};
use crate::weights::Models;

/// Text encoder, ControlNet, UNet and VAE decoder of one SD + ControlNet pair.
pub trait DiffusionModels: Send {
    /// Last hidden state `(B, n, dim)` for token ids `(B, n)` (u32).
    fn encode_text(&self, ids: &Tensor) -> Result<Tensor, DiffuseError>;

    /// ControlNet residuals for `sample` `(B, 4, h, w)` at `timestep`, under
    /// `cond` `(B, 3, 8h, 8w)` in [0, 1], each multiplied by `scale`.
    fn controlnet(
        &self,
        sample: &Tensor,
        timestep: f64,
        context: &Tensor,
        cond: &Tensor,
        scale: f64,
    ) -> Result<ControlResiduals, DiffuseError>;

    /// Input channels of the UNet: 4 (latents), or 9 for an inpainting UNet
    /// (latents, mask, masked-image latents).
    fn unet_in_channels(&self) -> usize;

    /// The UNet's noise prediction with the ControlNet residuals added
    /// (none on the steps past a ControlNet cut-off).
    fn unet(
        &self,
        sample: &Tensor,
        timestep: f64,
        context: &Tensor,
        residuals: Option<&ControlResiduals>,
    ) -> Result<Tensor, DiffuseError>;

    /// As [`Self::unet`], with DeepCache's full or shallow step and token
    /// merging; backends that cannot split their UNet refuse them at load
    /// ([`Self::check_savings`]).
    fn unet_saving(
        &self,
        sample: &Tensor,
        timestep: f64,
        context: &Tensor,
        residuals: Option<&ControlResiduals>,
        savings: UnetSavings,
    ) -> Result<Tensor, DiffuseError> {
        if savings.cache.is_some() || savings.merge.is_some() {
            return Err(unsupported_savings());
        }
        self.unet(sample, timestep, context, residuals)
    }

    /// The ControlNet residuals a DeepCache shallow step on `branch` uses
    /// (the first skip connections'); by default the full call.
    fn controlnet_shallow(
        &self,
        sample: &Tensor,
        timestep: f64,
        context: &Tensor,
        cond: &Tensor,
        scale: f64,
        _branch: CacheBranch,
    ) -> Result<ControlResiduals, DiffuseError> {
        self.controlnet(sample, timestep, context, cond, scale)
    }

    /// Whether these networks can apply `savings`.
    fn check_savings(&self, savings: &Savings) -> Result<(), DiffuseError> {
        if savings.any() {
            return Err(unsupported_savings());
        }
        Ok(())
    }

    /// Images `(B, 3, 8h, 8w)` in [-1, 1] from latents already divided by the
    /// VAE's scaling factor.
    fn decode(&self, latents: &Tensor) -> Result<Tensor, DiffuseError>;

    /// The VAE's configuration (scaling factor, pixels per latent cell).
    fn vae_config(&self) -> &VaeConfig;

    /// Mean and standard deviation of the VAE's latent distribution of
    /// images `(B, 3, 8h, 8w)` in [-1, 1] (image-to-image and inpainting).
    fn encode_image(&self, _images: &Tensor) -> Result<(Tensor, Tensor), DiffuseError> {
        Err(DiffuseError::Config(
            "this backend has no VAE encoder, which regenerator.mode = \"img2img\" and \
             \"inpaint\" need"
                .into(),
        ))
    }
}

fn unsupported_savings() -> DiffuseError {
    DiffuseError::Config(
        "regenerator.cache_interval > 1 and regenerator.token_merge_ratio > 0 need \
         backend = \"candle\": the ONNX export is one UNet graph, which cannot stop at \
         DeepCache's branch or merge tokens inside its attention"
            .into(),
    )
}

impl DiffusionModels for Models {
    fn unet_saving(
        &self,
        sample: &Tensor,
        timestep: f64,
        context: &Tensor,
        residuals: Option<&ControlResiduals>,
        savings: UnetSavings,
    ) -> Result<Tensor, DiffuseError> {
        Ok(self
            .unet
            .forward_saving(sample, timestep, context, residuals, savings)?)
    }

    fn controlnet_shallow(
        &self,
        sample: &Tensor,
        timestep: f64,
        context: &Tensor,
        cond: &Tensor,
        scale: f64,
        branch: CacheBranch,
    ) -> Result<ControlResiduals, DiffuseError> {
        Ok(self
            .controlnet
            .forward_shallow(sample, timestep, context, cond, scale, branch)?)
    }

    fn check_savings(&self, savings: &Savings) -> Result<(), DiffuseError> {
        if let Some(b) = savings.branch() {
            self.unet
                .check_branch(b)
                .map_err(|e| DiffuseError::Config(format!("regenerator.cache_branch: {e}")))?;
        }
        Ok(())
    }

    fn encode_text(&self, ids: &Tensor) -> Result<Tensor, DiffuseError> {
        Ok(self.text.forward(&ids.to_dtype(DType::U32)?)?)
    }

    fn controlnet(
        &self,
        sample: &Tensor,
        timestep: f64,
        context: &Tensor,
        cond: &Tensor,
        scale: f64,
    ) -> Result<ControlResiduals, DiffuseError> {
        Ok(self
            .controlnet
            .forward(sample, timestep, context, cond, scale)?)
    }

    fn unet_in_channels(&self) -> usize {
        self.unet_in_channels
    }

    fn unet(
        &self,
        sample: &Tensor,
        timestep: f64,
        context: &Tensor,
        residuals: Option<&ControlResiduals>,
    ) -> Result<Tensor, DiffuseError> {
        Ok(match residuals {
            Some(r) => self
                .unet
                .forward_with_residuals(sample, timestep, context, r)?,
            None => self.unet.forward(sample, timestep, context)?,
        })
    }

    fn decode(&self, latents: &Tensor) -> Result<Tensor, DiffuseError> {
        // One image at a time: a decode's activations at 512x512 are hundreds of MB.
        let imgs = (0..latents.dim(0)?)
            .map(|i| self.vae.decode(&latents.narrow(0, i, 1)?))
            .collect::<candle_core::Result<Vec<_>>>()?;
        Ok(Tensor::cat(&imgs, 0)?)
    }

    fn vae_config(&self) -> &VaeConfig {
        &self.vae_config
    }

    fn encode_image(&self, images: &Tensor) -> Result<(Tensor, Tensor), DiffuseError> {
        let enc = self.vae_encoder.as_ref().ok_or_else(|| {
            DiffuseError::Config("the VAE encoder was not loaded (Models::load_vae_encoder)".into())
        })?;
        Ok(enc.encode(images)?)
    }
}
