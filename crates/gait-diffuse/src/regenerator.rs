//! [`ImageRegenerator`] on the ControlNet pipeline: frames and their edge maps
//! in, regenerated frames of the same size and index out.

use candle_core::{Device, Tensor};
use gait_core::{
    Backend, EdgeMap, Frame, ImageRegenerator, Pose, Resize, StageContext, StageError,
};

use crate::config::{ControlnetConfig, Init, Region};
use crate::leg_mask::LegMask;
use crate::model_config::INPAINT_UNET_CHANNELS;
use crate::modes::RegenMode;
use crate::noise::NoiseRng;
use crate::pipeline::{ControlnetPipeline, DenoiseParams};
use crate::warp::{canvas_to_frame, edge_to_canvas, frame_to_canvas};
use crate::{DiffuseError, ort_models, previous, weights};

/// Regenerates each frame from its edge map with SD 1.5 + ControlNet.
pub struct ControlnetRegenerator {
    pipeline: ControlnetPipeline,
    context: Tensor,
    config: ControlnetConfig,
    /// Notes for run.json, handed out by `take_warnings`.
    warnings: Vec<String>,
    /// `init = "previous"`: the last frame's final latent `(1, 4, h, w)`.
    previous: Option<Tensor>,
}

impl ControlnetRegenerator {
    /// Loads the models named in `config` (paths relative to the models folder):
    /// the diffusers folders on candle, the ONNX exports on ort.
    pub fn new(config: &ControlnetConfig, ctx: &StageContext) -> Result<Self, DiffuseError> {
        config.validate().map_err(DiffuseError::Config)?;
        let pipeline = match config.backend {
            Backend::Candle | Backend::Auto => {
                let device = candle_device(ctx.device)?;
                if config.dtype == crate::Dtype::Bf16 && device.is_cpu() {
                    // candle 0.11.1 has no bf16 matmul on CPU.
                    return Err(DiffuseError::Config(
                        "regenerator.dtype = \"bf16\" needs [run] device = \"cuda\"; on CPU use \"f32\" or \"f16\""
                            .into(),
                    ));
                }
                let sd = ctx.model_path(&config.sd_path);
                let cn = ctx.model_path(&config.controlnet_path);
                weights::check_files(&sd, &cn)?;
                if config.mode.uses_frame() {
                    ControlnetPipeline::load_with_encoder(&sd, &cn, config.dtype.candle(), &device)?
                } else {
                    ControlnetPipeline::load(&sd, &cn, config.dtype.candle(), &device)?
                }
            }
            Backend::Ort => {
                let encoder = ctx
                    .model_path(&config.onnx_path)
                    .join(ort_models::ONNX_VAE_ENCODER);
                if config.mode.uses_frame() && !encoder.is_file() {
                    return Err(DiffuseError::Missing {
                        files: vec![encoder],
                        hint: format!(
                            "regenerator.mode = \"{}\" needs the VAE encoder: export it with \
                             `python tools/diffuse/export_onnx.py ... --only vae_encoder`, or use mode = \"text2img\"",
                            config.mode.name()
                        ),
                    });
                }
                if config.dtype != crate::Dtype::F32 {
                    return Err(DiffuseError::Config(format!(
                        "regenerator.dtype = \"{}\" is not available with backend = \"ort\" (the ONNX exports run in f32); use \"f32\"",
                        config.dtype.name()
                    )));
                }
                let dir = ctx.model_path(&config.onnx_path);
                ort_models::check_onnx_files(&dir)?;
                ControlnetPipeline::load_ort_on(
                    &dir,
                    &dir.join(ort_models::ONNX_MERGES),
                    ctx.device,
                )?
            }
        };
        Self::from_pipeline(pipeline, config)
    }

    /// Wraps an already loaded pipeline; the prompt embeddings are computed once.
    pub fn from_pipeline(
        pipeline: ControlnetPipeline,
        config: &ControlnetConfig,
    ) -> Result<Self, DiffuseError> {
        let inpainting_unet = pipeline.models.unet_in_channels() == INPAINT_UNET_CHANNELS;
        if inpainting_unet && config.mode != RegenMode::Inpaint {
            return Err(DiffuseError::Config(format!(
                "the UNet has {INPAINT_UNET_CHANNELS} input channels (an inpainting checkpoint), \
                 which only regenerator.mode = \"inpaint\" can drive (mode is \"{}\"); use SD 1.5's \
                 4-channel UNet for the other modes",
                config.mode.name()
            )));
        }
        pipeline.models.check_savings(&config.savings(0))?;
        let context = pipeline.context(
            &config.prompt,
            &config.negative_prompt,
            config.guidance_scale,
        )?;
        Ok(Self {
            pipeline,
            context,
            config: config.clone(),
            warnings: Vec::new(),
            previous: None,
        })
    }

    /// Initial latent noise for a frame (seed + index, or the shared seed).
    pub fn initial_noise(&self, index: usize, shape: (usize, usize, usize)) -> Vec<f32> {
        NoiseRng::new(self.frame_seed(index)).normals(shape.0 * shape.1 * shape.2)
    }

    /// The seed of frame `index`: seed + index, or the shared seed.
    fn frame_seed(&self, index: usize) -> u64 {
        if self.config.shared_noise {
            self.config.seed
        } else {
            self.config.seed.wrapping_add(index as u64)
        }
    }

    /// Initial latent noise and the VAE sample's normals for a frame: one
    /// stream of `2n` normals from the frame's seed; its first half is the
    /// text-to-image noise, so the modes share a frame's noise.
    fn frame_noise(&self, index: usize, n: usize) -> (Vec<f32>, Vec<f32>) {
        let mut v = self.initial_noise(index, (2, n, 1));
        let eps = v.split_off(n);
        (v, eps)
    }

    /// Redraws a group of frames of one canvas size; `start` (one frame
    /// only) is the previous frame's latent to start from. Returns the frames
    /// and the final latents (none for inpainting).
    fn run_group(
        &self,
        frames: &[&Frame],
        edges: &[&EdgeMap],
        masks: &[Option<&LegMask>],
        canvas: &Resize,
        start: Option<&Tensor>,
    ) -> Result<(Vec<Frame>, Option<Tensor>), DiffuseError> {
        let (w, h) = (canvas.dst_width as usize, canvas.dst_height as usize);
        let s = self.pipeline.vae_scale();
        let (lh, lw) = (h / s, w / s);
        let n = frames.len();
        let mode = self.config.mode;
        let mut control = Vec::with_capacity(n * 3 * w * h);
        let mut latents = Vec::with_capacity(n * 4 * lh * lw);
        let mut eps = Vec::new();
        let mut images = Vec::new();
        let mut mask_px = Vec::new();
        for (i, (f, e)) in frames.iter().zip(edges).enumerate() {
            let plane = edge_to_canvas(&e.image, &e.resize, canvas);
            for _ in 0..3 {
                control.extend_from_slice(&plane);
            }
            let (noise, sample) = self.frame_noise(f.index, 4 * lh * lw);
            latents.extend(noise);
            if mode.uses_frame() {
                eps.extend(sample);
                images.extend(
                    frame_to_canvas(&f.image, canvas)
                        .iter()
                        .map(|v| v * 2.0 - 1.0),
                );
            }
            if let Some(Some(m)) = masks.get(i) {
                mask_px.extend(m.on_canvas(canvas));
            }
        }
        let dev = &self.pipeline.device;
        let control = Tensor::from_vec(control, (n, 3, h, w), dev)?;
        let latents = Tensor::from_vec(latents, (n, 4, lh, lw), dev)?;
        let params = DenoiseParams {
            steps: self.config.steps,
            guidance_scale: self.config.guidance_scale,
            conditioning_scale: self.config.conditioning_scale,
            scheduler: self.config.scheduler,
            cutoffs: self.config.cutoffs(),
            // A group's frames share one UNet call, so one stream of merge picks.
            savings: self.config.savings(self.frame_seed(frames[0].index)),
        };
        let strength = self.config.strength();
        let (images, eps) = if mode.uses_frame() {
            (
                Tensor::from_vec(images, (n, 3, h, w), dev)?,
                Tensor::from_vec(eps, (n, 4, lh, lw), dev)?,
            )
        } else {
            (latents.clone(), latents.clone())
        };
        let pipe = &self.pipeline;
        let ctx = &self.context;
        let out = match (mode, start) {
            (_, Some(prev)) => {
                Some(pipe.from_latents(ctx, &control, prev, &latents, strength, &params)?)
            }
            (RegenMode::Text2img, None) => {
                Some(pipe.generate_full(ctx, &control, &latents, &params)?)
            }
            (RegenMode::Img2img, None) => {
                Some(pipe.img2img_full(ctx, &control, &images, &eps, &latents, strength, &params)?)
            }
            (RegenMode::Inpaint, None) => None,
        };
        let (images, last) = match out {
            Some(g) => (g.images, Some(g.latents)),
            None => (
                pipe.inpaint(
                    ctx,
                    &control,
                    &images,
                    &Tensor::from_vec(mask_px, (n, 1, h, w), dev)?,
                    &eps,
                    &latents,
                    strength,
                    &params,
                )?,
                None,
            ),
        };
        frames
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let chw = images.get(i)?.flatten_all()?.to_vec1::<f32>()?;
                let mut img = canvas_to_frame(&chw, canvas);
                if let (true, Some(Some(m))) = (self.config.mask.paste_back, masks.get(i)) {
                    paste_outside(&mut img, &f.image, m);
                }
                Ok(Frame::new(f.index, img))
            })
            .collect::<Result<Vec<_>, DiffuseError>>()
            .map(|frames| (frames, last))
    }

    /// Runs the frames whose `masks` entry is not `None` (all of them
    /// outside inpainting) in batches of one canvas size; the others pass.
    fn run(
        &mut self,
        frames: &[Frame],
        edges: Option<&[EdgeMap]>,
        masks: &[Option<LegMask>],
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
        let inpaint = self.config.mode == RegenMode::Inpaint;
        let mut out: Vec<Frame> = Vec::with_capacity(frames.len());
        let mut i = 0;
        while i < frames.len() {
            if inpaint && masks.get(i).is_none_or(Option::is_none) {
                self.warnings.push(format!(
                    "frame {}: no leg segment with likelihood >= {} on the original frame's pose; \
                     handed on unchanged (regenerator.mode = \"inpaint\")",
                    frames[i].index, self.config.mask.min_likelihood
                ));
                out.push(frames[i].clone());
                i += 1;
                continue;
            }
            let canvas = self.canvas(&frames[i])?;
            let mut j = i + 1;
            while j < frames.len()
                && j - i < self.batch()
                && self.canvas(&frames[j])? == canvas
                && !(inpaint && masks.get(j).is_none_or(Option::is_none))
            {
                j += 1;
            }
            let fs: Vec<&Frame> = frames[i..j].iter().collect();
            let es: Vec<&EdgeMap> = edges[i..j].iter().collect();
            let ms: Vec<Option<&LegMask>> = (i..j)
                .map(|k| masks.get(k).and_then(Option::as_ref))
                .collect();
            let start = self.start_latent(&canvas);
            let (redrawn, last) = self.run_group(&fs, &es, &ms, &canvas, start.as_ref())?;
            if self.is_stateful() {
                self.previous = last;
            }
            out.extend(redrawn);
            i = j;
        }
        Ok(out)
    }
}

impl ImageRegenerator for ControlnetRegenerator {
    fn regenerate(
        &mut self,
        frames: &[Frame],
        edges: Option<&[EdgeMap]>,
    ) -> Result<Vec<Frame>, StageError> {
        if self.config.mode == RegenMode::Inpaint {
            return Err(StageError::BadInput(
                "regenerator.mode = \"inpaint\" needs the pose of each original frame to draw \
                 the leg mask, and this pipeline did not pass any (ImageRegenerator::regenerate_with_poses)"
                    .into(),
            ));
        }
        self.run(frames, edges, &[])
    }

    fn regenerate_with_poses(
        &mut self,
        frames: &[Frame],
        edges: Option<&[EdgeMap]>,
        poses: &[Pose],
    ) -> Result<Vec<Frame>, StageError> {
        if self.config.mode != RegenMode::Inpaint {
            return self.run(frames, edges, &[]);
        }
        if poses.len() != frames.len() {
            return Err(StageError::BadInput(format!(
                "{} frames but {} original-frame poses",
                frames.len(),
                poses.len()
            )));
        }
        let masks: Vec<Option<LegMask>> = poses
            .iter()
            .map(|p| LegMask::from_pose(p, &self.config.mask))
            .collect();
        self.run(frames, edges, &masks)
    }

    fn take_warnings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.warnings)
    }

    fn is_stateful(&self) -> bool {
        self.config.init == Init::Previous
    }

    fn reset(&mut self) {
        self.previous = None;
    }

    fn state(&self) -> Option<Vec<u8>> {
        if !self.is_stateful() {
            return None;
        }
        // An empty state: the next frame starts afresh (inpainting, or none yet).
        Some(match &self.previous {
            Some(p) => previous::to_state(p).ok()?,
            None => Vec::new(),
        })
    }

    fn restore(&mut self, state: &[u8]) -> bool {
        if state.is_empty() {
            self.previous = None;
            return true;
        }
        match previous::from_state(state) {
            Some(t) => {
                self.previous = t.to_device(&self.pipeline.device).ok();
                self.previous.is_some()
            }
            None => false,
        }
    }
}

impl ControlnetRegenerator {
    /// The generation canvas of a frame: the frame itself when it is a crop
    /// around the subject (cut at the canvas size), else short side `resolution`.
    fn canvas(&self, frame: &Frame) -> Result<Resize, StageError> {
        if self.config.region != Region::Subject {
            return Ok(canvas_for(frame, self.config.resolution));
        }
        let (w, h) = frame.image.dimensions();
        if !(w.is_multiple_of(64) && h.is_multiple_of(64)) || w == 0 || h == 0 {
            return Err(StageError::BadInput(format!(
                "region = \"subject\": frame {} is {w}x{h}, not a crop of multiples of 64 \
                 (the runner cuts crops at crop_size)",
                frame.index
            )));
        }
        Ok(Resize::identity(w, h))
    }

    /// Frames per network call: one at a time when each starts from the last.
    fn batch(&self) -> usize {
        if self.is_stateful() {
            1
        } else {
            self.config.batch
        }
    }

    /// The previous frame's latent, when this frame starts from it (same canvas).
    fn start_latent(&self, canvas: &Resize) -> Option<Tensor> {
        let s = self.pipeline.vae_scale();
        let want = (
            canvas.dst_height as usize / s,
            canvas.dst_width as usize / s,
        );
        self.previous
            .as_ref()
            .filter(|p| p.dims4().is_ok_and(|(_, _, h, w)| (h, w) == want))
            .cloned()
    }
}

/// The candle device of `[run] device`, keeping the typed no-CUDA error.
fn candle_device(device: gait_core::Device) -> Result<Device, DiffuseError> {
    device.candle().map_err(|e| match e {
        StageError::NoCuda(e) => DiffuseError::NoCuda(e),
        other => DiffuseError::Config(other.to_string()),
    })
}

/// Puts `original`'s pixels back wherever `mask` does not regenerate.
fn paste_outside(img: &mut image::RgbImage, original: &image::RgbImage, mask: &LegMask) {
    for (x, y, p) in img.enumerate_pixels_mut() {
        if !mask.contains(f64::from(x), f64::from(y))
            && let Some(o) = original.get_pixel_checked(x, y)
        {
            *p = *o;
        }
    }
}

/// The generation canvas of a frame: short side `resolution`, sides multiples of 64.
pub fn canvas_for(frame: &Frame, resolution: u32) -> Resize {
    Resize::short_side(frame.width(), frame.height(), resolution, 64)
}
