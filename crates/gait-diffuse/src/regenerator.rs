//! [`ImageRegenerator`] on the ControlNet pipeline: frames and their edge maps
//! in, regenerated frames of the same size and index out.

use candle_core::{Device, Tensor};
use gait_core::{Backend, EdgeMap, Frame, ImageRegenerator, Resize, StageContext, StageError};

use crate::config::ControlnetConfig;
use crate::noise::NoiseRng;
use crate::pipeline::{ControlnetPipeline, DenoiseParams};
use crate::warp::{canvas_to_frame, edge_to_canvas};
use crate::{DiffuseError, ort_models, weights};

/// Regenerates each frame from its edge map with SD 1.5 + ControlNet.
pub struct ControlnetRegenerator {
    pipeline: ControlnetPipeline,
    context: Tensor,
    config: ControlnetConfig,
}

impl ControlnetRegenerator {
    /// Loads the models named in `config` (paths relative to the models folder):
    /// the diffusers folders on candle, the ONNX exports on ort.
    pub fn new(config: &ControlnetConfig, ctx: &StageContext) -> Result<Self, DiffuseError> {
        config.validate().map_err(DiffuseError::Config)?;
        let pipeline = match config.backend {
            Backend::Candle => {
                if config.dtype == crate::Dtype::Bf16 {
                    // candle 0.11.1 has no bf16 matmul on CPU; GPU builds come with issue 10.
                    return Err(DiffuseError::Config(
                        "regenerator.dtype = \"bf16\" needs a GPU build; on CPU use \"f32\" or \"f16\""
                            .into(),
                    ));
                }
                let sd = ctx.model_path(&config.sd_path);
                let cn = ctx.model_path(&config.controlnet_path);
                weights::check_files(&sd, &cn)?;
                ControlnetPipeline::load(&sd, &cn, config.dtype.candle(), &Device::Cpu)?
            }
            Backend::Ort => {
                if config.dtype != crate::Dtype::F32 {
                    return Err(DiffuseError::Config(format!(
                        "regenerator.dtype = \"{}\" is not available with backend = \"ort\" (the ONNX exports run in f32); use \"f32\"",
                        config.dtype.name()
                    )));
                }
                let dir = ctx.model_path(&config.onnx_path);
                ort_models::check_onnx_files(&dir)?;
                ControlnetPipeline::load_ort(&dir, &dir.join(ort_models::ONNX_MERGES))?
            }
        };
        Self::from_pipeline(pipeline, config)
    }

    /// Wraps an already loaded pipeline; the prompt embeddings are computed once.
    pub fn from_pipeline(
        pipeline: ControlnetPipeline,
        config: &ControlnetConfig,
    ) -> Result<Self, DiffuseError> {
        let context = pipeline.context(
            &config.prompt,
            &config.negative_prompt,
            config.guidance_scale,
        )?;
        Ok(Self {
            pipeline,
            context,
            config: config.clone(),
        })
    }

    /// Initial latent noise for a frame (seed + index, or the shared seed).
    pub fn initial_noise(&self, index: usize, shape: (usize, usize, usize)) -> Vec<f32> {
        let seed = if self.config.shared_noise {
            self.config.seed
        } else {
            self.config.seed.wrapping_add(index as u64)
        };
        NoiseRng::new(seed).normals(shape.0 * shape.1 * shape.2)
    }

    fn run_group(
        &self,
        frames: &[&Frame],
        edges: &[&EdgeMap],
        canvas: &Resize,
    ) -> Result<Vec<Frame>, DiffuseError> {
        let (w, h) = (canvas.dst_width as usize, canvas.dst_height as usize);
        let s = self.pipeline.vae_scale();
        let (lh, lw) = (h / s, w / s);
        let mut control = Vec::with_capacity(frames.len() * 3 * w * h);
        let mut latents = Vec::with_capacity(frames.len() * 4 * lh * lw);
        for (f, e) in frames.iter().zip(edges) {
            let plane = edge_to_canvas(&e.image, &e.resize, canvas);
            for _ in 0..3 {
                control.extend_from_slice(&plane);
            }
            latents.extend(self.initial_noise(f.index, (4, lh, lw)));
        }
        let dev = &self.pipeline.device;
        let n = frames.len();
        let control = Tensor::from_vec(control, (n, 3, h, w), dev)?;
        let latents = Tensor::from_vec(latents, (n, 4, lh, lw), dev)?;
        let params = DenoiseParams {
            steps: self.config.steps,
            guidance_scale: self.config.guidance_scale,
            conditioning_scale: self.config.conditioning_scale,
            scheduler: self.config.scheduler,
        };
        let images = self
            .pipeline
            .generate(&self.context, &control, &latents, &params)?;
        frames
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let chw = images.get(i)?.flatten_all()?.to_vec1::<f32>()?;
                Ok(Frame::new(f.index, canvas_to_frame(&chw, canvas)))
            })
            .collect()
    }
}

impl ImageRegenerator for ControlnetRegenerator {
    fn regenerate(
        &mut self,
        frames: &[Frame],
        edges: Option<&[EdgeMap]>,
    ) -> Result<Vec<Frame>, StageError> {
        let edges = edges.ok_or_else(|| {
            StageError::BadInput("the controlnet regenerator needs edge maps: set an [edge] kind other than \"none\"".into())
        })?;
        if edges.len() != frames.len() {
            return Err(StageError::BadInput(format!(
                "{} frames but {} edge maps",
                frames.len(),
                edges.len()
            )));
        }
        let mut out = Vec::with_capacity(frames.len());
        let mut i = 0;
        while i < frames.len() {
            let canvas = canvas_for(&frames[i], self.config.resolution);
            let mut j = i + 1;
            while j < frames.len()
                && j - i < self.config.batch
                && canvas_for(&frames[j], self.config.resolution) == canvas
            {
                j += 1;
            }
            let fs: Vec<&Frame> = frames[i..j].iter().collect();
            let es: Vec<&EdgeMap> = edges[i..j].iter().collect();
            out.extend(self.run_group(&fs, &es, &canvas)?);
            i = j;
        }
        Ok(out)
    }
}

/// The generation canvas of a frame: short side `resolution`, sides multiples of 64.
pub fn canvas_for(frame: &Frame, resolution: u32) -> Resize {
    Resize::short_side(frame.width(), frame.height(), resolution, 64)
}
