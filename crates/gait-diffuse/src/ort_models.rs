//! The four networks on ONNX Runtime (`ort`, library from `ORT_DYLIB_PATH`),
//! from the exports of `tools/diffuse/export_onnx.py`: the ControlNet returns
//! its residuals as outputs `down_block_res_*` / `mid_block_res`, and the UNet
//! takes them as inputs of the same names. Everything runs in f32.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use candle_core::{DType, Device, Tensor};
use gait_ort::Session;
use ort::value::DynTensor;

use crate::DiffuseError;
use crate::controlnet::ControlResiduals;
use crate::model_config::{VaeConfig, read_config};
use crate::models::DiffusionModels;

/// Graph files inside the ONNX folder (`onnx_path` in the TOML).
pub const ONNX_TEXT: &str = "text_encoder/model.onnx";
pub const ONNX_CONTROLNET: &str = "controlnet/model.onnx";
pub const ONNX_UNET: &str = "unet/model.onnx";
pub const ONNX_VAE: &str = "vae_decoder/model.onnx";
/// Optional: the VAE encoder image-to-image and inpainting need.
pub const ONNX_VAE_ENCODER: &str = "vae_encoder/model.onnx";
/// The tokenizer merges the export script copies next to the graphs.
pub const ONNX_MERGES: &str = "tokenizer/merges.txt";
const EXPORT_HINT: &str = "export them from the diffusers-layout SD 1.5 and ControlNet folders \
     (`gait models fetch sd15-controlnet-canny` downloads those) with \
     `python tools/diffuse/export_onnx.py --sd SD_DIR --controlnet CONTROLNET_DIR --out`";

/// Every file the ort backend reads from `onnx_dir` (graphs, their external
/// weight files where present, the tokenizer merges).
pub fn onnx_files(onnx_dir: &Path) -> Vec<PathBuf> {
    let mut v = Vec::new();
    for f in [ONNX_TEXT, ONNX_CONTROLNET, ONNX_UNET, ONNX_VAE] {
        let p = onnx_dir.join(f);
        let data = onnx_dir.join(format!("{f}_data"));
        v.push(p);
        if data.is_file() {
            v.push(data);
        }
    }
    v.push(onnx_dir.join(ONNX_MERGES));
    v
}

/// Fails with the list of missing files and how to make them.
pub fn check_onnx_files(onnx_dir: &Path) -> Result<(), DiffuseError> {
    check(onnx_dir, onnx_files(onnx_dir))
}

fn check(onnx_dir: &Path, files: Vec<PathBuf>) -> Result<(), DiffuseError> {
    let missing: Vec<PathBuf> = files.into_iter().filter(|p| !p.is_file()).collect();
    if missing.is_empty() {
        return Ok(());
    }
    Err(DiffuseError::Missing {
        files: missing,
        hint: format!("{EXPORT_HINT} {}", onnx_dir.display()),
    })
}

fn ort_err(e: impl ToString) -> DiffuseError {
    DiffuseError::Ort(e.to_string())
}

/// One ONNX graph in its own session. `Session::run` needs `&mut`; the
/// mutex lets the pipeline call the models through `&self`.
struct OnnxNet {
    session: Mutex<Session>,
    path: PathBuf,
    inputs: Vec<String>,
    /// Input shapes, -1 on dynamic axes.
    input_shapes: Vec<Vec<i64>>,
    outputs: Vec<String>,
}

impl OnnxNet {
    fn load(path: &Path, device: gait_ort::Device) -> Result<Self, DiffuseError> {
        let session = gait_ort::session(path, device).map_err(|e| match e {
            gait_ort::SessionError::Runtime(m) => DiffuseError::Ort(m),
            gait_ort::SessionError::Model(m) => DiffuseError::bad_model(path, m),
        })?;
        let inputs = session
            .inputs()
            .iter()
            .map(|i| i.name().to_string())
            .collect();
        let input_shapes = session
            .inputs()
            .iter()
            .map(|i| i.dtype().tensor_shape().map_or(vec![], |s| s.to_vec()))
            .collect();
        let outputs = session
            .outputs()
            .iter()
            .map(|o| o.name().to_string())
            .collect();
        Ok(Self {
            session: Mutex::new(session),
            path: path.to_path_buf(),
            inputs,
            input_shapes,
            outputs,
        })
    }

    /// Fails naming the file when the graph lacks one of `names` as an input
    /// (or output), e.g. a plain UNet export without the residual inputs.
    fn require(&self, names: &[String], outputs: bool) -> Result<(), DiffuseError> {
        let (have, what) = if outputs {
            (&self.outputs, "output")
        } else {
            (&self.inputs, "input")
        };
        match names.iter().find(|n| !have.contains(n)) {
            None => Ok(()),
            Some(n) => Err(DiffuseError::bad_model(
                &self.path,
                format!(
                    "graph has no {what} `{n}` ({what}s: {have:?}); re-export it with tools/diffuse/export_onnx.py"
                ),
            )),
        }
    }

    /// The fixed size of axis `axis` of input `name` (None when dynamic).
    fn input_dim(&self, name: &str, axis: usize) -> Option<usize> {
        let i = self.inputs.iter().position(|n| n == name)?;
        let d = *self.input_shapes[i].get(axis)?;
        usize::try_from(d).ok()
    }

    /// Runs the graph; returns every output, in the graph's output order.
    fn run(&self, inputs: Vec<(String, DynTensor)>) -> Result<Vec<Tensor>, DiffuseError> {
        let mut session = self
            .session
            .lock()
            .map_err(|_| ort_err("session poisoned by an earlier panic"))?;
        let outs = session.run(inputs).map_err(ort_err)?;
        self.outputs
            .iter()
            .map(|name| {
                let v = outs
                    .get(name)
                    .ok_or_else(|| ort_err(format!("no output `{name}`")))?;
                let (shape, data) = v.try_extract_tensor::<f32>().map_err(ort_err)?;
                let dims: Vec<usize> = shape.iter().map(|&d| d.max(0) as usize).collect();
                Ok(Tensor::from_slice(data, dims, &Device::Cpu)?)
            })
            .collect()
    }
}

/// A candle tensor as an f32 ort input.
fn f32_input(name: &str, t: &Tensor) -> Result<(String, DynTensor), DiffuseError> {
    let shape: Vec<i64> = t.dims().iter().map(|&d| d as i64).collect();
    let data = t.to_dtype(DType::F32)?.flatten_all()?.to_vec1::<f32>()?;
    let v = ort::value::Tensor::from_array((shape, data)).map_err(ort_err)?;
    Ok((name.to_string(), v.upcast()))
}

/// `timestep` as the `[batch]` f32 input both denoisers take.
fn timestep_input(batch: usize, t: f64) -> Result<(String, DynTensor), DiffuseError> {
    let v = ort::value::Tensor::from_array((vec![batch as i64], vec![t as f32; batch]))
        .map_err(ort_err)?;
    Ok(("timestep".to_string(), v.upcast()))
}

fn residual_names(n: usize) -> Vec<String> {
    (0..n)
        .map(|i| format!("down_block_res_{i}"))
        .chain(std::iter::once("mid_block_res".to_string()))
        .collect()
}

/// A sample shape and the residual shapes the ControlNet gives for it.
type ShapesOf = (Vec<usize>, Vec<Vec<usize>>);

/// ControlNet + UNet on ONNX Runtime: what one denoising step runs.
pub struct OrtDenoiser {
    controlnet: OnnxNet,
    unet: OnnxNet,
    /// Skip-connection residuals (12 for SD 1.5).
    residuals: usize,
    /// Residual shapes by sample shape, for the steps the ControlNet skips.
    residual_shapes: Mutex<Vec<ShapesOf>>,
}

impl OrtDenoiser {
    /// Opens `controlnet/model.onnx` and `unet/model.onnx` under `onnx_dir`
    /// and checks that the ControlNet's residuals fit the UNet's inputs.
    pub fn load(onnx_dir: &Path) -> Result<Self, DiffuseError> {
        Self::load_on(onnx_dir, gait_ort::Device::Cpu)
    }

    /// [`OrtDenoiser::load`] with ONNX Runtime on `device`.
    pub fn load_on(onnx_dir: &Path, device: gait_ort::Device) -> Result<Self, DiffuseError> {
        check(
            onnx_dir,
            [ONNX_CONTROLNET, ONNX_UNET]
                .iter()
                .map(|f| onnx_dir.join(f))
                .collect(),
        )?;
        let controlnet = OnnxNet::load(&onnx_dir.join(ONNX_CONTROLNET), device)?;
        let unet = OnnxNet::load(&onnx_dir.join(ONNX_UNET), device)?;
        let residuals = controlnet
            .outputs
            .iter()
            .filter(|o| o.starts_with("down_block_res_"))
            .count();
        let names = residual_names(residuals);
        controlnet.require(&names, true)?;
        let fixed = ["sample", "timestep", "encoder_hidden_states"].map(String::from);
        controlnet.require(&fixed, false)?;
        controlnet.require(
            &["controlnet_cond", "conditioning_scale"].map(String::from),
            false,
        )?;
        unet.require(&fixed, false)?;
        unet.require(&names, false)?;
        if unet.inputs.len() != fixed.len() + names.len() {
            return Err(DiffuseError::bad_model(
                &unet.path,
                format!(
                    "UNet takes {} residual inputs, the ControlNet ({}) gives {}",
                    unet.inputs.len().saturating_sub(fixed.len()),
                    controlnet.path.display(),
                    names.len()
                ),
            ));
        }
        Ok(Self {
            controlnet,
            unet,
            residuals,
            residual_shapes: Mutex::new(Vec::new()),
        })
    }

    /// Number of skip-connection residuals (12 for SD 1.5).
    pub fn num_residuals(&self) -> usize {
        self.residuals
    }

    /// Residuals of zeros for `sample`: the exported UNet always takes them,
    /// so the steps past a ControlNet cut-off feed these. Their shapes come
    /// from one ControlNet run per sample shape (the graph leaves them dynamic).
    pub fn zero_residuals(
        &self,
        sample: &Tensor,
        context: &Tensor,
    ) -> Result<ControlResiduals, DiffuseError> {
        let key = sample.dims().to_vec();
        let known = self.lock_shapes().iter().find(|(k, _)| *k == key).cloned();
        let shapes = match known {
            Some((_, shapes)) => shapes,
            None => {
                // The ControlNet's condition is 8x the latents (its embedding halves three times).
                let (b, _, h, w) = sample.dims4()?;
                let cond = Tensor::zeros((b, 3, 8 * h, 8 * w), sample.dtype(), sample.device())?;
                let r = self.controlnet(sample, 0.0, context, &cond, 0.0)?;
                let shapes: Vec<Vec<usize>> = r
                    .down
                    .iter()
                    .chain(r.mid.as_ref())
                    .map(|t| t.dims().to_vec())
                    .collect();
                self.lock_shapes().push((key, shapes.clone()));
                shapes
            }
        };
        let zeros = |d: &Vec<usize>| Tensor::zeros(d.as_slice(), sample.dtype(), sample.device());
        let (mid, down) = shapes.split_last().ok_or_else(|| ort_err("no residuals"))?;
        Ok(ControlResiduals {
            down: down.iter().map(zeros).collect::<candle_core::Result<_>>()?,
            mid: Some(zeros(mid)?),
        })
    }

    fn lock_shapes(&self) -> std::sync::MutexGuard<'_, Vec<ShapesOf>> {
        // A panic elsewhere cannot leave the list half-written: pushes are whole.
        self.residual_shapes
            .lock()
            .unwrap_or_else(|e| e.into_inner())
    }

    /// The UNet graph's `sample` channels (4, or 9 for an inpainting UNet;
    /// 4 when the export left the axis dynamic).
    pub fn unet_in_channels(&self) -> usize {
        self.unet.input_dim("sample", 1).unwrap_or(4)
    }

    /// See [`DiffusionModels::controlnet`].
    pub fn controlnet(
        &self,
        sample: &Tensor,
        timestep: f64,
        context: &Tensor,
        cond: &Tensor,
        scale: f64,
    ) -> Result<ControlResiduals, DiffuseError> {
        let scale = ort::value::Tensor::from_array((Vec::<i64>::new(), vec![scale as f32]))
            .map_err(ort_err)?;
        let mut outs = self.controlnet.run(vec![
            f32_input("sample", sample)?,
            timestep_input(sample.dim(0)?, timestep)?,
            f32_input("encoder_hidden_states", context)?,
            f32_input("controlnet_cond", cond)?,
            ("conditioning_scale".to_string(), scale.upcast()),
        ])?;
        // Outputs follow the graph's order; pick them by name.
        let mut down = Vec::with_capacity(self.residuals);
        for i in 0..self.residuals {
            down.push(self.take(&mut outs, &format!("down_block_res_{i}"))?);
        }
        let mid = self.take(&mut outs, "mid_block_res")?;
        let dtype = sample.dtype();
        Ok(ControlResiduals {
            down: down
                .iter()
                .map(|t| t.to_dtype(dtype))
                .collect::<candle_core::Result<_>>()?,
            mid: Some(mid.to_dtype(dtype)?),
        })
    }

    fn take(&self, outs: &mut [Tensor], name: &str) -> Result<Tensor, DiffuseError> {
        let i = self
            .controlnet
            .outputs
            .iter()
            .position(|o| o == name)
            .ok_or_else(|| ort_err(format!("ControlNet has no output `{name}`")))?;
        Ok(outs[i].clone())
    }

    /// See [`DiffusionModels::unet`].
    pub fn unet(
        &self,
        sample: &Tensor,
        timestep: f64,
        context: &Tensor,
        residuals: &ControlResiduals,
    ) -> Result<Tensor, DiffuseError> {
        if residuals.down.len() != self.residuals {
            return Err(ort_err(format!(
                "{} down residuals for a UNet that takes {}",
                residuals.down.len(),
                self.residuals
            )));
        }
        let mut inputs = vec![
            f32_input("sample", sample)?,
            timestep_input(sample.dim(0)?, timestep)?,
            f32_input("encoder_hidden_states", context)?,
        ];
        for (i, r) in residuals.down.iter().enumerate() {
            inputs.push(f32_input(&format!("down_block_res_{i}"), r)?);
        }
        let mid = residuals
            .mid
            .as_ref()
            .ok_or_else(|| ort_err("the UNet graph needs the ControlNet's mid residual"))?;
        inputs.push(f32_input("mid_block_res", mid)?);
        let out = self.unet.run(inputs)?;
        let eps = out
            .into_iter()
            .next()
            .ok_or_else(|| ort_err("UNet graph has no output"))?;
        Ok(eps.to_dtype(sample.dtype())?)
    }
}

/// SD 1.5 + ControlNet on ONNX Runtime.
pub struct OrtModels {
    text: OnnxNet,
    denoiser: OrtDenoiser,
    vae: OnnxNet,
    vae_config: VaeConfig,
    /// Loaded when `vae_encoder/model.onnx` exists.
    vae_encoder: Option<OnnxNet>,
}

impl OrtModels {
    /// Opens the four graphs under `onnx_dir` (layout of `tools/diffuse/export_onnx.py`);
    /// the VAE's `config.json` next to its graph gives the scaling factor.
    pub fn load(onnx_dir: &Path) -> Result<Self, DiffuseError> {
        Self::load_on(onnx_dir, gait_ort::Device::Cpu)
    }

    /// [`OrtModels::load`] with ONNX Runtime on `device`; inputs and outputs
    /// stay in host memory (candle CPU tensors).
    pub fn load_on(onnx_dir: &Path, device: gait_ort::Device) -> Result<Self, DiffuseError> {
        let graphs = [ONNX_TEXT, ONNX_CONTROLNET, ONNX_UNET, ONNX_VAE];
        check(onnx_dir, graphs.iter().map(|f| onnx_dir.join(f)).collect())?;
        let text = OnnxNet::load(&onnx_dir.join(ONNX_TEXT), device)?;
        text.require(&["input_ids".to_string()], false)?;
        let denoiser = OrtDenoiser::load_on(onnx_dir, device)?;
        let vae = OnnxNet::load(&onnx_dir.join(ONNX_VAE), device)?;
        vae.require(&["latent_sample".to_string()], false)?;
        let vae_config: VaeConfig = read_config(&onnx_dir.join("vae_decoder"))?;
        let enc_path = onnx_dir.join(ONNX_VAE_ENCODER);
        let vae_encoder = if enc_path.is_file() {
            let enc = OnnxNet::load(&enc_path, device)?;
            enc.require(&["sample".to_string()], false)?;
            enc.require(&["latent_mean", "latent_std"].map(String::from), true)?;
            Some(enc)
        } else {
            None
        };
        Ok(Self {
            text,
            denoiser,
            vae,
            vae_config,
            vae_encoder,
        })
    }

    /// The ControlNet + UNet pair.
    pub fn denoiser(&self) -> &OrtDenoiser {
        &self.denoiser
    }
}

impl DiffusionModels for OrtModels {
    fn unet_in_channels(&self) -> usize {
        self.denoiser.unet_in_channels()
    }

    fn encode_text(&self, ids: &Tensor) -> Result<Tensor, DiffuseError> {
        let shape: Vec<i64> = ids.dims().iter().map(|&d| d as i64).collect();
        let data = ids.to_dtype(DType::I64)?.flatten_all()?.to_vec1::<i64>()?;
        let v = ort::value::Tensor::from_array((shape, data)).map_err(ort_err)?;
        let out = self.text.run(vec![("input_ids".to_string(), v.upcast())])?;
        let i = self
            .text
            .outputs
            .iter()
            .position(|o| o == "last_hidden_state")
            .unwrap_or(0);
        out.into_iter()
            .nth(i)
            .ok_or_else(|| ort_err("text encoder graph has no output"))
    }

    fn controlnet(
        &self,
        sample: &Tensor,
        timestep: f64,
        context: &Tensor,
        cond: &Tensor,
        scale: f64,
    ) -> Result<ControlResiduals, DiffuseError> {
        self.denoiser
            .controlnet(sample, timestep, context, cond, scale)
    }

    fn unet(
        &self,
        sample: &Tensor,
        timestep: f64,
        context: &Tensor,
        residuals: Option<&ControlResiduals>,
    ) -> Result<Tensor, DiffuseError> {
        match residuals {
            Some(r) => self.denoiser.unet(sample, timestep, context, r),
            None => {
                let zeros = self.denoiser.zero_residuals(sample, context)?;
                self.denoiser.unet(sample, timestep, context, &zeros)
            }
        }
    }

    fn decode(&self, latents: &Tensor) -> Result<Tensor, DiffuseError> {
        let out = self.vae.run(vec![f32_input("latent_sample", latents)?])?;
        let img = out
            .into_iter()
            .next()
            .ok_or_else(|| ort_err("VAE decoder graph has no output"))?;
        Ok(img.to_dtype(latents.dtype())?)
    }

    fn vae_config(&self) -> &VaeConfig {
        &self.vae_config
    }

    fn encode_image(&self, images: &Tensor) -> Result<(Tensor, Tensor), DiffuseError> {
        let enc = self.vae_encoder.as_ref().ok_or_else(|| {
            DiffuseError::Config(format!(
                "no {ONNX_VAE_ENCODER} next to the other graphs: image-to-image and inpainting \
                 need it; {EXPORT_HINT} DIR --only vae_encoder"
            ))
        })?;
        let out = enc.run(vec![f32_input("sample", images)?])?;
        let pick = |name: &str| -> Result<Tensor, DiffuseError> {
            let i = enc
                .outputs
                .iter()
                .position(|o| o == name)
                .ok_or_else(|| ort_err(format!("VAE encoder has no output `{name}`")))?;
            Ok(out[i].to_dtype(images.dtype())?)
        };
        Ok((pick("latent_mean")?, pick("latent_std")?))
    }
}
