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

/// Builds every stage, loading their models.
pub fn build(config: &PipelineConfig, ctx: &StageContext) -> Result<Stages, PipelineError> {
    Ok(Stages {
        edge: config.edge.build(ctx)?,
        regenerator: config.regenerator.build(ctx)?,
        pose: config.pose.build(ctx)?,
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

/// Where each stage (edge, regenerator, pose) runs with `[run] device`.
/// Only the ControlNet regenerator on candle takes the GPU so far; the other
/// stages (and every stage without a model) run on the CPU.
pub fn stage_devices(config: &PipelineConfig) -> [Device; 3] {
    let on_gpu = matches!(
        &config.regenerator,
        gait_diffuse::RegeneratorConfig::Controlnet(c) if c.backend == gait_core::Backend::Candle
    );
    let regenerator = if on_gpu {
        config.run.device
    } else {
        Device::Cpu
    };
    [Device::Cpu, regenerator, Device::Cpu]
}
