//! Builds the configured stages. Each stage crate owns its config enum
//! (`kind = ...`); this is the one place that knows all stage families.

use gait_core::{Device, EdgeDetector, ImageRegenerator, PoseEstimator, StageContext};

use crate::{PipelineConfig, PipelineError};

/// The live stages of a pipeline.
pub struct Stages {
    /// `None` for `[edge] kind = "none"`.
    pub edge: Option<Box<dyn EdgeDetector>>,
    pub regenerator: Box<dyn ImageRegenerator>,
    pub pose: Box<dyn PoseEstimator>,
}

/// Builds every stage, loading their models, each on its device
/// ([`stage_devices`]).
pub fn build(config: &PipelineConfig, ctx: &StageContext) -> Result<Stages, PipelineError> {
    let [edge, regenerator, pose] = stage_devices(config).map(|d| ctx.clone().on(d));
    Ok(Stages {
        edge: config.edge.build(&edge)?,
        regenerator: config.regenerator.build(&regenerator)?,
        pose: config.pose.build(&pose)?,
    })
}

/// A short name of each stage's choice, e.g. "canny" or "blazepose/ort".
pub fn stage_kinds(config: &PipelineConfig) -> [(&'static str, String); 3] {
    let kind = |v: serde_json::Value| {
        let k = v["kind"].as_str().unwrap_or("?").to_string();
        match v["backend"].as_str() {
            Some(b) => format!("{k}/{b}"),
            None => k,
        }
    };
    [
        (
            "edge",
            kind(serde_json::to_value(&config.edge).unwrap_or_default()),
        ),
        (
            "regenerator",
            kind(serde_json::to_value(&config.regenerator).unwrap_or_default()),
        ),
        (
            "pose",
            kind(serde_json::to_value(&config.pose).unwrap_or_default()),
        ),
    ]
}

/// Where one stage runs with `[run] device`, and whether on candle (which
/// needs a CUDA build for a GPU; ONNX Runtime brings CUDA in its library).
#[derive(Debug, Clone, Copy)]
struct Placement {
    device: Device,
    candle: bool,
}

/// Each stage's placement: model stages that can run on a GPU take
/// `[run] device`; canny, passthrough and BlazePose on candle (gait-tflite's
/// CPU kernels) stay on the CPU. Plugins get the device and may use it.
fn placements(config: &PipelineConfig) -> [Placement; 3] {
    use gait_core::Backend::Candle;
    use gait_diffuse::RegeneratorConfig as R;
    use gait_edge::EdgeConfig as E;
    use gait_pose::PoseConfig as P;
    let on = |gpu: bool, candle: bool| Placement {
        device: if gpu { config.run.device } else { Device::Cpu },
        candle: gpu && candle,
    };
    let edge = match &config.edge {
        E::Hed(c) => on(true, c.backend == Candle),
        E::Plugin(_) | E::Python(_) => on(true, false),
        _ => on(false, false),
    };
    let regenerator = match &config.regenerator {
        R::Controlnet(c) => on(true, c.backend == Candle),
        R::Plugin(_) | R::Python(_) => on(true, false),
        R::Passthrough => on(false, false),
    };
    let pose = match &config.pose {
        P::Blazepose(c) => on(c.backend != Candle, false),
        P::Openpose(c) => on(true, c.backend == Candle),
        P::Plugin(_) | P::Python(_) => on(true, false),
    };
    [edge, regenerator, pose]
}

/// Where each stage (edge, regenerator, pose) runs.
pub fn stage_devices(config: &PipelineConfig) -> [Device; 3] {
    placements(config).map(|p| p.device)
}

/// Checks `[run] device` against the pipeline before any model loads: a GPU
/// that no stage would use, or candle on a GPU in a build without CUDA.
pub fn check_devices(config: &PipelineConfig) -> Result<(), PipelineError> {
    let device = config.run.device;
    if device.is_cpu() {
        return Ok(());
    }
    let placed = placements(config);
    if placed.iter().all(|p| p.device.is_cpu()) {
        return Err(PipelineError::config(
            "[run]",
            format!(
                "device = \"{device}\", but no stage of this pipeline runs on a GPU (canny, passthrough and BlazePose on candle are CPU code); \
                 set run.device = \"cpu\", or choose a GPU stage (regenerator.kind = \"controlnet\", pose.backend = \"ort\", edge.kind = \"hed\")"
            ),
        ));
    }
    if !cfg!(feature = "cuda") && placed.iter().any(|p| p.candle) {
        return Err(gait_core::StageError::from(gait_core::NoCudaSupport).into());
    }
    Ok(())
}
