//! Loading the four SD 1.5 + ControlNet components from diffusers-layout
//! folders, with errors naming the file (and, from candle, the tensor), and a
//! recording backend that lists the tensors each loader asks for.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use candle_core::{DType, Device, Shape, Tensor};
use candle_nn::VarBuilder;
use candle_nn::var_builder::SimpleBackend;

use crate::DiffuseError;
use crate::clip_text::ClipTextModel;
use crate::controlnet::ControlNet;
use crate::model_config::{INPAINT_UNET_CHANNELS, TextConfig, UnetConfig, VaeConfig, read_config};
use crate::unet::UNet2DConditionModel;
use crate::vae_decoder::VaeDecoder;
use crate::vae_encoder::VaeEncoder;

/// Weight file of each component inside the SD folder (diffusers layout).
pub const UNET_FILE: &str = "unet/diffusion_pytorch_model.safetensors";
pub const VAE_FILE: &str = "vae/diffusion_pytorch_model.safetensors";
pub const TEXT_FILE: &str = "text_encoder/model.safetensors";
pub const MERGES_FILE: &str = "tokenizer/merges.txt";
/// Weight file inside the ControlNet folder.
pub const CONTROLNET_FILE: &str = "diffusion_pytorch_model.safetensors";

/// Every file a SD + ControlNet pair needs, in the order they are loaded.
pub fn required_files(sd_dir: &Path, controlnet_dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = [UNET_FILE, VAE_FILE, TEXT_FILE, MERGES_FILE]
        .iter()
        .map(|f| sd_dir.join(f))
        .collect();
    v.push(controlnet_dir.join(CONTROLNET_FILE));
    v
}

/// Fails with the list of missing files and where they go.
pub fn check_files(sd_dir: &Path, controlnet_dir: &Path) -> Result<(), DiffuseError> {
    let missing: Vec<PathBuf> = required_files(sd_dir, controlnet_dir)
        .into_iter()
        .filter(|p| !p.is_file())
        .collect();
    if missing.is_empty() {
        return Ok(());
    }
    Err(DiffuseError::Missing {
        files: missing,
        hint: format!(
            "run `gait models fetch sd15-controlnet-canny` (into the models folder, \
             --models-dir or GAIT_MODELS_DIR), or put files fetched elsewhere there: the \
             diffusers-layout files of stable-diffusion-v1-5 (unet/, vae/, text_encoder/, \
             tokenizer/) in {} and of lllyasviel/sd-controlnet-canny in {}",
            sd_dir.display(),
            controlnet_dir.display()
        ),
    })
}

fn var_builder(
    path: &Path,
    dtype: DType,
    device: &Device,
) -> Result<VarBuilder<'static>, DiffuseError> {
    // SAFETY: the file is mapped read-only and not modified while the models live.
    unsafe { VarBuilder::from_mmaped_safetensors(&[path], dtype, device) }
        .map_err(|e| DiffuseError::bad_model(path, e))
}

/// The loaded models of one SD 1.5 + ControlNet pair.
pub struct Models {
    pub unet: UNet2DConditionModel,
    pub controlnet: ControlNet,
    pub vae: VaeDecoder,
    pub text: ClipTextModel,
    pub vae_config: VaeConfig,
    pub text_config: TextConfig,
    /// 4, or 9 for an inpainting UNet.
    pub unet_in_channels: usize,
    /// Image-to-image and inpainting only (see [`Models::load_vae_encoder`]).
    pub vae_encoder: Option<VaeEncoder>,
}

impl Models {
    /// Loads all four from diffusers-layout folders (configs read when present).
    pub fn load(
        sd_dir: &Path,
        controlnet_dir: &Path,
        dtype: DType,
        device: &Device,
    ) -> Result<Self, DiffuseError> {
        check_files(sd_dir, controlnet_dir)?;
        let unet_cfg: UnetConfig = read_config(&sd_dir.join("unet"))?;
        let cn_cfg: UnetConfig = read_config(controlnet_dir)?;
        let vae_config: VaeConfig = read_config(&sd_dir.join("vae"))?;
        let text_config: TextConfig = read_config(&sd_dir.join("text_encoder"))?;
        if cn_cfg.block_out_channels != unet_cfg.block_out_channels
            || cn_cfg.cross_attention_dim != unet_cfg.cross_attention_dim
        {
            return Err(DiffuseError::bad_model(
                controlnet_dir.join("config.json"),
                format!(
                    "ControlNet (channels {:?}, cross-attention {}) does not fit the UNet (channels {:?}, cross-attention {})",
                    cn_cfg.block_out_channels,
                    cn_cfg.cross_attention_dim,
                    unet_cfg.block_out_channels,
                    unet_cfg.cross_attention_dim
                ),
            ));
        }
        if ![4, INPAINT_UNET_CHANNELS].contains(&unet_cfg.in_channels) {
            return Err(DiffuseError::bad_model(
                sd_dir.join("unet").join("config.json"),
                format!(
                    "UNet with {} input channels: SD 1.5's takes 4, an inpainting UNet 9",
                    unet_cfg.in_channels
                ),
            ));
        }
        if cn_cfg.in_channels != 4 {
            return Err(DiffuseError::bad_model(
                controlnet_dir.join("config.json"),
                format!(
                    "ControlNet with {} input channels: it sees the 4 latent channels",
                    cn_cfg.in_channels
                ),
            ));
        }
        let path = sd_dir.join(UNET_FILE);
        let unet = build_unet(var_builder(&path, dtype, device)?, &unet_cfg)
            .map_err(|e| DiffuseError::bad_model(&path, e))?;
        let path = controlnet_dir.join(CONTROLNET_FILE);
        let controlnet = ControlNet::new(var_builder(&path, dtype, device)?, &cn_cfg)
            .map_err(|e| DiffuseError::bad_model(&path, e))?;
        let path = sd_dir.join(VAE_FILE);
        let vae = VaeDecoder::new(var_builder(&path, dtype, device)?, &vae_config)
            .map_err(|e| DiffuseError::bad_model(&path, e))?;
        let path = sd_dir.join(TEXT_FILE);
        let text = ClipTextModel::new(var_builder(&path, dtype, device)?, &text_config)
            .map_err(|e| DiffuseError::bad_model(&path, e))?;
        Ok(Self {
            unet,
            controlnet,
            vae,
            text,
            vae_config,
            text_config,
            unet_in_channels: unet_cfg.in_channels,
            vae_encoder: None,
        })
    }

    /// Loads the VAE encoder too (from the same file as the decoder), for
    /// the modes that start from the frame.
    pub fn load_vae_encoder(
        &mut self,
        sd_dir: &Path,
        dtype: DType,
        device: &Device,
    ) -> Result<(), DiffuseError> {
        let path = sd_dir.join(VAE_FILE);
        let enc = VaeEncoder::new(var_builder(&path, dtype, device)?, &self.vae_config)
            .map_err(|e| DiffuseError::bad_model(&path, e))?;
        self.vae_encoder = Some(enc);
        Ok(())
    }
}

/// Our UNet from a diffusers UNet config.
pub fn build_unet(vb: VarBuilder, cfg: &UnetConfig) -> candle_core::Result<UNet2DConditionModel> {
    UNet2DConditionModel::new(vb, cfg)
}

/// A VarBuilder backend that hands out unallocated (broadcast) zero tensors and
/// records every name and shape asked for.
struct Recorder {
    seen: Mutex<BTreeMap<String, Vec<usize>>>,
    /// Names the loader may probe for (e.g. the VAE's attention naming).
    present: Vec<String>,
}

impl SimpleBackend for Recorder {
    fn get(
        &self,
        s: Shape,
        name: &str,
        _h: candle_nn::Init,
        dtype: DType,
        dev: &Device,
    ) -> candle_core::Result<Tensor> {
        if let Ok(mut seen) = self.seen.lock() {
            seen.insert(name.to_string(), s.dims().to_vec());
        }
        Tensor::zeros((), dtype, dev)?.broadcast_as(s)
    }

    fn get_unchecked(
        &self,
        name: &str,
        _dtype: DType,
        _dev: &Device,
    ) -> candle_core::Result<Tensor> {
        candle_core::bail!("shape of {name} unknown to the recorder")
    }

    fn contains_tensor(&self, name: &str) -> bool {
        self.present.iter().any(|p| p == name)
    }
}

/// Which model a manifest is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Component {
    Unet,
    ControlNet,
    Vae,
    TextEncoder,
    /// The encoder half of the VAE file (image-to-image and inpainting).
    VaeEncoder,
}

/// Names and shapes our loader requests for `component` with the given
/// config (SD 1.5's by default); `present` answers the loader's probes.
pub fn requested_tensors(
    component: Component,
    unet: &UnetConfig,
    vae: &VaeConfig,
    text: &TextConfig,
    present: Vec<String>,
) -> Result<BTreeMap<String, Vec<usize>>, DiffuseError> {
    let rec = std::sync::Arc::new(Recorder {
        seen: Mutex::new(BTreeMap::new()),
        present,
    });
    let backend: Box<dyn SimpleBackend> = Box::new(ArcRecorder(rec.clone()));
    let vb = VarBuilder::from_backend(backend, DType::F32, Device::Cpu);
    match component {
        Component::Unet => build_unet(vb, unet).map(|_| ())?,
        Component::ControlNet => ControlNet::new(vb, unet).map(|_| ())?,
        Component::Vae => VaeDecoder::new(vb, vae).map(|_| ())?,
        Component::TextEncoder => ClipTextModel::new(vb, text).map(|_| ())?,
        Component::VaeEncoder => VaeEncoder::new(vb, vae).map(|_| ())?,
    }
    let seen = rec.seen.lock().map(|s| s.clone()).unwrap_or_default();
    Ok(seen)
}

struct ArcRecorder(std::sync::Arc<Recorder>);

impl SimpleBackend for ArcRecorder {
    fn get(
        &self,
        s: Shape,
        name: &str,
        h: candle_nn::Init,
        dtype: DType,
        dev: &Device,
    ) -> candle_core::Result<Tensor> {
        self.0.get(s, name, h, dtype, dev)
    }
    fn get_unchecked(&self, name: &str, dtype: DType, dev: &Device) -> candle_core::Result<Tensor> {
        self.0.get_unchecked(name, dtype, dev)
    }
    fn contains_tensor(&self, name: &str) -> bool {
        self.0.contains_tensor(name)
    }
}
