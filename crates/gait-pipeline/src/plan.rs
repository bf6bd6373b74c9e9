//! The cache keys, caches and stage records of a run: every stage's key
//! chains the input's checksum and the configs (and model checksums) of the
//! stages before it, so a change recomputes exactly what it affects.

use std::collections::BTreeMap;
use std::path::Path;

use gait_core::{Device, PersonBox, StageContext};
use gait_subject::Subject;

use crate::cache::{StageCache, chain_key};
use crate::manifest::{ModelRecord, StageRecord, model_records};
use crate::registry;
use crate::selection::SelectionMode;
use crate::{PipelineConfig, PipelineError};

/// The record name of the pose pass over the original frames.
pub(crate) const ORIGINAL_POSE: &str = "original-pose";
/// The record name of the subject pass.
pub(crate) const SUBJECT: &str = "subject";

/// The stage caches of a run; `original` holds the poses found on the
/// original frames (`selection.mode = "poor"`, inpainting).
pub(crate) struct StageCaches {
    pub(crate) edge: StageCache,
    pub(crate) regenerator: StageCache,
    pub(crate) pose: StageCache,
    pub(crate) original: StageCache,
}

impl StageCaches {
    /// Warnings for entries found corrupt (and recomputed) in any of them.
    pub(crate) fn take_warnings(&self) -> Vec<String> {
        [&self.edge, &self.regenerator, &self.pose, &self.original]
            .iter()
            .flat_map(|c| c.take_warnings())
            .collect()
    }
}

/// Model checksums and the input key, known before any frame is decoded.
pub(crate) struct Models {
    pub(crate) input_key: String,
    pub(crate) edge: Vec<ModelRecord>,
    pub(crate) regenerator: Vec<ModelRecord>,
    pub(crate) pose: Vec<ModelRecord>,
    pub(crate) devices: [Device; 3],
}

impl Models {
    pub(crate) fn new(config: &PipelineConfig, ctx: &StageContext, input_key: String) -> Self {
        Self {
            input_key,
            edge: model_records(config.edge.model_files(ctx)),
            regenerator: model_records(config.regenerator.model_files(ctx)),
            pose: model_records(config.pose.model_files(ctx)),
            devices: registry::stage_devices(config),
        }
    }

    /// Every model file of the run, for run.json.
    pub(crate) fn all(&self) -> Vec<ModelRecord> {
        [
            self.edge.clone(),
            self.regenerator.clone(),
            self.pose.clone(),
        ]
        .concat()
    }
}

/// The cache root of a run, or `None` when caching is off.
pub(crate) fn cache_root(config: &PipelineConfig, out: &Path) -> Option<std::path::PathBuf> {
    config.run.cache.then(|| {
        config
            .run
            .cache_dir
            .clone()
            .unwrap_or_else(|| out.join("cache"))
    })
}

/// The cache of the subject pass: the people in each frame depend on the
/// input and the pose model's detector, not on whom the run follows.
pub(crate) fn subject_cache(
    finder: &gait_pose::PoseConfig,
    models: &Models,
    root: Option<&Path>,
) -> Result<(StageCache, String), PipelineError> {
    let mut pose = serde_json::to_value(finder).unwrap_or_default();
    if let Some(t) = pose.as_object_mut() {
        t.remove("person");
    }
    let stage = on_device(SUBJECT, models.devices[2]);
    let key = chain_key(&models.input_key, &stage, &(&pose, &models.pose));
    let cache = match root {
        Some(r) => StageCache::open(r, SUBJECT, &key, &pose)?,
        None => StageCache::disabled(),
    };
    Ok((cache, key))
}

/// The caches of the edge, regenerator and pose stages, and one record per
/// stage (with its cache key).
pub(crate) fn stage_caches(
    config: &PipelineConfig,
    models: &Models,
    subject: Option<&Subject>,
    root: Option<&Path>,
) -> Result<(StageCaches, BTreeMap<String, StageRecord>), PipelineError> {
    let devices = models.devices;
    let sel = &config.selection;
    let start = config.input.first_frame;
    // The poses follow the subject's boxes, so their keys cover them.
    let boxes: Option<Vec<(usize, PersonBox)>> =
        subject.map(|s| s.boxes.iter().map(|(f, b)| (*f, *b)).collect());
    let edge_stage = on_device("edge", devices[0]);
    // Around the subject, edge maps are taken on crops that follow its boxes.
    let edge_key = match config.regenerator.subject_crop() {
        None => chain_key(
            &models.input_key,
            &edge_stage,
            &(&config.edge, &models.edge),
        ),
        Some(crop) => chain_key(
            &models.input_key,
            &edge_stage,
            &(&config.edge, &models.edge, &crop, &boxes),
        ),
    };
    let original_key = chain_key(
        &models.input_key,
        &on_device(ORIGINAL_POSE, devices[2]),
        &(&config.pose, &models.pose, sel.stride, start, &boxes),
    );
    // An inpainting regenerator draws inside a mask made from the original
    // frame's pose, so its images depend on that pose too.
    let needs_poses = config.regenerator.needs_poses();
    let regen_stage = on_device("regenerator", devices[1]);
    let regen_parts = (
        &config.regenerator,
        &models.regenerator,
        needs_poses.then_some(&original_key),
    );
    // A regenerator that starts each frame from the one before depends on
    // which frames come before it: the first frame, the stride and the rule.
    let regen_key = if config.regenerator.chains_frames() {
        let chain = (start, sel.stride, sel.tracking_key());
        chain_key(&edge_key, &regen_stage, &(regen_parts, chain))
    } else {
        chain_key(&edge_key, &regen_stage, &regen_parts)
    };
    // A tracking estimator's result depends on the frames it saw before, so
    // the pose key covers the first frame, the stride and, with selective
    // regeneration, the rule that picks the frames. Edge maps and
    // regenerated images do not: changing the rule reuses every image.
    let pose_stage = on_device("pose", devices[2]);
    let pose_key = match sel.tracking_key() {
        None => chain_key(
            &regen_key,
            &pose_stage,
            &(&config.pose, &models.pose, start, &boxes),
        ),
        Some(t) => chain_key(
            &regen_key,
            &pose_stage,
            &(&config.pose, &models.pose, &t, start, &boxes),
        ),
    };
    let original_pass = sel.mode == SelectionMode::Poor || needs_poses;
    let open = |stage: &str, key: &str, cfg: &dyn erased::Config| match root {
        Some(r) => cfg.open(r, stage, key),
        None => Ok(StageCache::disabled()),
    };
    let caches = StageCaches {
        edge: open("edge", &edge_key, &config.edge)?,
        regenerator: open("regenerator", &regen_key, &config.regenerator)?,
        pose: open("pose", &pose_key, &config.pose)?,
        original: if original_pass {
            open(ORIGINAL_POSE, &original_key, &config.pose)?
        } else {
            StageCache::disabled()
        },
    };
    let mut records = BTreeMap::new();
    for (((stage, kind), key), device) in registry::stage_kinds(config)
        .into_iter()
        .zip([&edge_key, &regen_key, &pose_key])
        .zip(devices)
    {
        records.insert(stage.to_string(), record(kind, device, key));
    }
    if original_pass {
        let kind = records["pose"].kind.clone();
        records.insert(
            ORIGINAL_POSE.to_string(),
            record(kind, devices[2], &original_key),
        );
    }
    Ok((caches, records))
}

/// A stage's record before any frame: its kind, device and key.
pub(crate) fn record(kind: String, device: Device, key: &str) -> StageRecord {
    StageRecord {
        kind,
        device: device.to_string(),
        cache_key: key[..16].to_string(),
        ..StageRecord::default()
    }
}

/// The stage name that salts a cache key: plain on the CPU (keys of CPU runs
/// are unchanged), with the device for a stage on a GPU.
pub(crate) fn on_device(stage: &str, device: Device) -> String {
    match device {
        Device::Cpu => stage.to_string(),
        d => format!("{stage}@{d}"),
    }
}

/// Stage configs are recorded beside their cache folder; this lets one
/// closure open caches for configs of different types.
mod erased {
    use std::path::Path;

    use serde::Serialize;

    use crate::PipelineError;
    use crate::cache::StageCache;

    pub(crate) trait Config {
        fn open(&self, root: &Path, stage: &str, key: &str) -> Result<StageCache, PipelineError>;
    }

    impl<T: Serialize> Config for T {
        fn open(&self, root: &Path, stage: &str, key: &str) -> Result<StageCache, PipelineError> {
            StageCache::open(root, stage, key, self)
        }
    }
}
