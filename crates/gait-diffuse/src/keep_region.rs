//! How inpainting keeps the region it does not redraw, as the denoising loop
//! applies it after each step (4-channel UNet) or feeds it to the UNet
//! (9-channel inpainting UNet); modes.rs builds it from the frame.

use candle_core::Tensor;

use crate::DiffuseError;
use crate::schedule::Scheduler;

/// How the denoising loop keeps the unmasked region.
pub(crate) enum Inpainting {
    /// 4-channel UNet: the known latents are put back after every step.
    Blend(KeepRegion),
    /// 9-channel UNet: `[latents, mask, masked_latents]` is the UNet's input
    /// (the ControlNet sees the latents only); nothing is put back.
    Condition {
        mask: Tensor,
        masked_latents: Tensor,
    },
}

/// Inpainting's known region: the frame's latents, the noise they get and the
/// latent-size mask (1 = regenerate).
pub struct KeepRegion {
    pub image_latents: Tensor,
    pub noise: Tensor,
    pub mask: Tensor,
}

impl KeepRegion {
    /// `mask * x + (1 - mask) * known`, the known latents noised to `next_t`
    /// (none after the last step).
    pub(crate) fn blend(
        &self,
        sched: &Scheduler,
        x: &Tensor,
        next_t: Option<usize>,
    ) -> Result<Tensor, DiffuseError> {
        let known = match next_t {
            Some(t) => sched.add_noise(&self.image_latents, &self.noise, t)?,
            None => self.image_latents.clone(),
        };
        let keep = (1.0 - &self.mask)?;
        Ok((x.broadcast_mul(&self.mask)? + known.broadcast_mul(&keep)?)?)
    }
}

/// A pixel mask `(B, 1, H, W)` in [0, 1] as diffusers' inpainting uses it:
/// binarized at 0.5, then nearest-downsampled to the latents by `scale`.
pub fn latent_mask(mask: &Tensor, scale: usize) -> Result<Tensor, DiffuseError> {
    let (b, _, h, w) = mask.dims4()?;
    let binary = mask.ge(0.5)?.to_dtype(mask.dtype())?;
    let (lh, lw) = (h / scale, w / scale);
    // torch's "nearest" with an integer factor picks pixel (scale*i, scale*j).
    Ok(binary
        .narrow(2, 0, lh * scale)?
        .narrow(3, 0, lw * scale)?
        .reshape((b, 1, lh, scale, lw, scale))?
        .narrow(3, 0, 1)?
        .narrow(5, 0, 1)?
        .reshape((b, 1, lh, lw))?)
}

#[cfg(test)]
mod tests {
    use candle_core::Device;

    use super::*;

    #[test]
    fn latent_mask_binarizes_and_picks_every_scale_th_pixel() {
        let mut v = vec![0f32; 16 * 16];
        v[0] = 0.6; // (0, 0) -> cell (0, 0)
        v[8 * 16 + 1] = 1.0; // (8, 1): not a sampled pixel
        v[8 * 16 + 8] = 0.4; // below 0.5
        v[8] = 0.5; // (0, 8) -> cell (0, 1)
        let m = Tensor::from_vec(v, (1, 1, 16, 16), &Device::Cpu).unwrap();
        let lm = latent_mask(&m, 8).unwrap();
        assert_eq!(
            lm.flatten_all().unwrap().to_vec1::<f32>().unwrap(),
            vec![1.0, 1.0, 0.0, 0.0]
        );
    }
}
