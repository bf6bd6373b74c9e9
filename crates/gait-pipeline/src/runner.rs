//! Runs the passes over the input (original-frame poses when only poor
//! frames are regenerated, then the regeneration pass), fills the frames a
//! stride skipped, and writes `keypoints.csv` and `run.json` into the run
//! folder.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

use gait_core::{Device, Pose, PoseSequence, StageContext};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::cache::{StageCache, chain_key};
use crate::driver::{Caches, Driver, Order};
use crate::input::InputInfo;
use crate::manifest::{InputRecord, RunManifest, StageRecord, model_records};
use crate::registry::{self, Stages};
use crate::selection::{self, SelectionMode, SelectionRecord};
use crate::{PipelineConfig, PipelineError, atomic, interpolate};

/// Where a run reads from and writes to.
#[derive(Debug, Clone)]
pub struct RunOptions {
    pub input: PathBuf,
    pub out: PathBuf,
    pub models_dir: PathBuf,
    /// Draw a progress bar on stderr (only shown on a terminal).
    pub progress: bool,
    /// The command line, recorded in run.json.
    pub command: Vec<String>,
}

/// What a finished run produced.
#[derive(Debug, Clone)]
pub struct RunSummary {
    pub poses: PoseSequence,
    pub manifest: RunManifest,
    /// Angles, events and cycles of the run.
    pub kinematics: Option<gait_kin::KinResult>,
}

impl RunSummary {
    /// Writes `run.json` into `out` (again, after later steps added to it).
    pub fn write_manifest(&self, out: &Path) -> Result<(), PipelineError> {
        let path = out.join("run.json");
        let json = serde_json::to_vec_pretty(&self.manifest).unwrap_or_default();
        atomic::write(&path, &json)
            .map_err(|e| PipelineError::io(format!("writing {}", path.display()), e))
    }
}

/// The stage caches of a run; `original` holds the poses found on the
/// original frames (`selection.mode = "poor"`).
struct StageCaches {
    edge: StageCache,
    regenerator: StageCache,
    pose: StageCache,
    original: StageCache,
}

/// The record name of the pose pass over the original frames.
const ORIGINAL_POSE: &str = "original-pose";

/// Runs the pipeline on `opts.input` and writes the run folder.
pub fn run(config: &PipelineConfig, opts: &RunOptions) -> Result<RunSummary, PipelineError> {
    let started_unix = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let info = InputInfo::open(&opts.input)?;
    let fps = config.input.fps.unwrap_or(info.fps);
    registry::check_devices(config)?;
    let ctx = StageContext::new(&opts.models_dir).on(config.run.device);
    let mut stages = registry::build(config, &ctx)?;
    let names = stages.pose.keypoint_names();
    let sel = &config.selection;
    let poor_mode = sel.mode == SelectionMode::Poor;
    if poor_mode {
        // Unknown keypoint names fail before any frame is decoded.
        selection::judge(&[], &names, sel).map_err(|e| PipelineError::config("[selection]", e))?;
    }
    std::fs::create_dir_all(&opts.out).map_err(|e| {
        PipelineError::io(
            format!("creating the output folder {}", opts.out.display()),
            e,
        )
    })?;

    let input_key = info.fingerprint()?;
    // Keys cover each stage's config and the checksums of its model files,
    // so new weights (or a rebuilt plugin at the same path) recompute.
    let edge_models = model_records(config.edge.model_files(&ctx));
    let regen_models = model_records(config.regenerator.model_files(&ctx));
    let pose_models = model_records(config.pose.model_files(&ctx));
    // A model gives (slightly) different numbers on a GPU, so the keys of
    // stages on one name the device; CPU keys stay as they were.
    let devices = registry::stage_devices(config);
    let edge_stage = on_device("edge", devices[0]);
    let regen_stage = on_device("regenerator", devices[1]);
    let pose_stage = on_device("pose", devices[2]);
    let original_stage = on_device(ORIGINAL_POSE, devices[2]);
    let edge_key = chain_key(&input_key, &edge_stage, &(&config.edge, &edge_models));
    let start = config.input.first_frame;
    let original_key = chain_key(
        &input_key,
        &original_stage,
        &(&config.pose, &pose_models, sel.stride, start),
    );
    // An inpainting regenerator draws inside a mask made from the original
    // frame's pose, so its images depend on that pose too.
    let needs_poses = config.regenerator.needs_poses();
    let regen_key = chain_key(
        &edge_key,
        &regen_stage,
        &(
            &config.regenerator,
            &regen_models,
            needs_poses.then_some(&original_key),
        ),
    );
    // A tracking estimator's result depends on the frames it saw before,
    // so the pose key covers the first frame, the stride and, with selective
    // regeneration, the rule that picks the frames. Edge maps and regenerated
    // images do not: changing the rule reuses every image already regenerated.
    let pose_key = match sel.tracking_key() {
        None => chain_key(
            &regen_key,
            &pose_stage,
            &(&config.pose, &pose_models, start),
        ),
        Some(t) => chain_key(
            &regen_key,
            &pose_stage,
            &(&config.pose, &pose_models, &t, start),
        ),
    };
    let original_pass = poor_mode || needs_poses;
    let caches = if config.run.cache {
        let root = config
            .run
            .cache_dir
            .clone()
            .unwrap_or_else(|| opts.out.join("cache"));
        StageCaches {
            edge: StageCache::open(&root, "edge", &edge_key, &config.edge)?,
            regenerator: StageCache::open(&root, "regenerator", &regen_key, &config.regenerator)?,
            pose: StageCache::open(&root, "pose", &pose_key, &config.pose)?,
            original: if original_pass {
                StageCache::open(&root, ORIGINAL_POSE, &original_key, &config.pose)?
            } else {
                StageCache::disabled()
            },
        }
    } else {
        StageCaches {
            edge: StageCache::disabled(),
            regenerator: StageCache::disabled(),
            pose: StageCache::disabled(),
            original: StageCache::disabled(),
        }
    };
    let mut records: BTreeMap<String, StageRecord> = BTreeMap::new();
    for (((stage, kind), key), device) in registry::stage_kinds(config)
        .into_iter()
        .zip([&edge_key, &regen_key, &pose_key])
        .zip(devices)
    {
        records.insert(
            stage.to_string(),
            StageRecord {
                kind,
                device: device.to_string(),
                cache_key: key[..16].to_string(),
                ..StageRecord::default()
            },
        );
    }
    if original_pass {
        let kind = records["pose"].kind.clone();
        records.insert(
            ORIGINAL_POSE.to_string(),
            StageRecord {
                kind,
                device: devices[2].to_string(),
                cache_key: original_key[..16].to_string(),
                ..StageRecord::default()
            },
        );
    }

    let total = info.frames.map(|n| {
        let end = config.input.last_frame.map_or(n, |l| (l + 1).min(n));
        end.saturating_sub(config.input.first_frame)
    });
    let first = config.input.first_frame;
    let stride = sel.stride;
    let grid = Order::Grid { first, stride };
    let on_grid = |index: usize, last: bool| last || (index - first).is_multiple_of(stride);
    let mut tools = Tools {
        config,
        stages: &mut stages,
        records: &mut records,
        n_keypoints: names.len(),
    };

    // Pass 1 (poor mode): poses on the original frames of the grid.
    // Pass 2: the regeneration pass over the grid, or over the poor frames.
    // The estimator starts each pass afresh and sees that pass's frames in
    // order, tracking only between neighbours in the grid.
    let mut record = SelectionRecord::default();
    let (all, processed, from_cache, original) = if poor_mode {
        let bar = progress_bar(opts.progress, total, "original frames");
        let first_pass = tools.pass(&caches, &caches.original, false, grid);
        let (all, original, cached_original) = first_pass.stream(&info, &bar, &on_grid)?;
        bar.finish_and_clear();
        let poses: Vec<Pose> = original.iter().map(|(_, p)| p.clone()).collect();
        let verdict = selection::judge(&poses, &names, sel)
            .map_err(|e| PipelineError::config("[selection]", e))?;
        let poor: Vec<usize> = original
            .iter()
            .zip(&verdict.reasons)
            .filter(|(_, r)| r.is_some())
            .map(|((f, _), _)| *f)
            .collect();
        for ((f, _), reason) in original.iter().zip(&verdict.reasons) {
            if let Some(r) = reason {
                record.poor.entry(*r).or_default().push([*f, *f]);
                *record.poor_counts.entry(*r).or_default() += 1;
            }
        }
        for frames in record.poor.values_mut() {
            *frames = selection::ranges(frames.iter().map(|r| r[0]));
        }
        record.segment_medians_px = Some(verdict.medians);
        let mut regenerated: BTreeMap<usize, Pose> = BTreeMap::new();
        let mut cached_regenerated = BTreeSet::new();
        if !poor.is_empty() {
            let wanted: BTreeSet<usize> = poor.iter().copied().collect();
            let bar = progress_bar(opts.progress, total, "regenerating poor frames");
            let order = Order::Subset {
                frames: poor,
                stride,
            };
            let mut second_pass = tools.pass(&caches, &caches.pose, true, order);
            if needs_poses {
                second_pass.original_poses = Some(original.iter().cloned().collect());
            }
            let (_, found, cached) =
                second_pass.stream(&info, &bar, &|f, _| wanted.contains(&f))?;
            bar.finish_and_clear();
            regenerated.extend(found);
            cached_regenerated = cached;
        }
        let mut from_cache = 0;
        let processed: Vec<(usize, Pose)> = original
            .iter()
            .map(|(f, p)| match regenerated.remove(f) {
                Some(r) => {
                    from_cache += usize::from(cached_regenerated.contains(f));
                    (*f, r)
                }
                None => {
                    from_cache += usize::from(cached_original.contains(f));
                    (*f, p.clone())
                }
            })
            .collect();
        (all, processed, from_cache, Some(original))
    } else if needs_poses {
        // Inpainting without selection: poses on the original frames for
        // the leg masks, then every grid frame through the regenerator.
        let bar = progress_bar(opts.progress, total, "original frames");
        let first_pass = tools.pass(&caches, &caches.original, false, grid.clone());
        let (_, original, _) = first_pass.stream(&info, &bar, &on_grid)?;
        bar.finish_and_clear();
        let bar = progress_bar(opts.progress, total, "");
        let mut second_pass = tools.pass(&caches, &caches.pose, true, grid);
        second_pass.original_poses = Some(original.iter().cloned().collect());
        let (all, processed, cached) = second_pass.stream(&info, &bar, &on_grid)?;
        bar.finish_and_clear();
        (all, processed, cached.len(), Some(original))
    } else {
        let bar = progress_bar(opts.progress, total, "");
        let only_pass = tools.pass(&caches, &caches.pose, true, grid);
        let (all, processed, cached) = only_pass.stream(&info, &bar, &on_grid)?;
        bar.finish_and_clear();
        (all, processed, cached.len(), None)
    };
    let regenerator_warnings = tools.stages.regenerator.take_warnings();
    if all.is_empty() {
        return Err(PipelineError::input(
            &opts.input,
            format!("no frames in the selected range (first_frame = {first})"),
        ));
    }
    let (poses, interpolated) = interpolate::fill(&all, &processed, names.len());
    let processed_frames: Vec<usize> = processed.iter().map(|(f, _)| *f).collect();
    let poor_set: BTreeSet<usize> = record
        .poor
        .values()
        .flat_map(|rs| rs.iter().flat_map(|r| r[0]..=r[1]))
        .collect();
    let (regenerated, kept): (Vec<usize>, Vec<usize>) = processed_frames
        .iter()
        .partition(|f| !poor_mode || poor_set.contains(f));
    record.frames = all.len();
    record.processed = selection::ranges(processed_frames.iter().copied());
    record.regenerated_count = regenerated.len();
    record.regenerated = selection::ranges(regenerated);
    record.original_count = kept.len();
    record.original = selection::ranges(kept);
    record.interpolated_count = interpolated.len();
    record.interpolated = selection::ranges(interpolated);
    let seq = PoseSequence {
        fps,
        names: names.clone(),
        frames: all,
        poses,
    };

    let scorer = format!("gait-{}", records["pose"].kind.replace('/', "-"));
    write_csv(&opts.out.join("keypoints.csv"), &scorer, &seq)?;
    if let Some(original) = original {
        // The poses the poor-frame rule judged, for checking and comparing.
        let (frames, poses) = original.into_iter().unzip();
        let seq = PoseSequence {
            fps,
            names: names.clone(),
            frames,
            poses,
        };
        write_csv(&opts.out.join("keypoints_original.csv"), &scorer, &seq)?;
    }

    let manifest = RunManifest {
        tool: "gait",
        version: env!("CARGO_PKG_VERSION"),
        started_unix,
        command: opts.command.clone(),
        input: InputRecord {
            path: opts.input.clone(),
            sha256: input_key,
            width: info.width,
            height: info.height,
            fps,
            first_frame: config.input.first_frame,
            last_frame: config.input.last_frame,
        },
        config: serde_json::to_value(config).unwrap_or_default(),
        models: [edge_models, regen_models, pose_models].concat(),
        stages: records,
        frames_processed: seq.poses.len(),
        frames_from_cache: from_cache,
        selection: record,
        keypoint_names: names,
        warnings: regenerator_warnings,
        extra: BTreeMap::new(),
    };
    let mut summary = RunSummary {
        poses: seq,
        manifest,
        kinematics: None,
    };
    // Keypoints are on disk before the kinematics run, so a kinematics
    // failure loses none of the (possibly hours of) pose work.
    summary.write_manifest(&opts.out)?;
    let kin = gait_kin::analyse(&summary.poses, &config.postprocess, &config.kinematics)
        .map_err(gait_core::StageError::from)?;
    gait_kin::write_outputs(&kin, &opts.out).map_err(gait_core::StageError::from)?;
    summary
        .manifest
        .warnings
        .extend(kin.warnings.iter().cloned());
    summary.manifest.extra.insert(
        "kinematics".into(),
        serde_json::to_value(&kin).unwrap_or_default(),
    );
    summary.write_manifest(&opts.out)?;
    summary.kinematics = Some(kin);
    Ok(summary)
}

/// The stage name that salts a cache key: plain on the CPU (keys of CPU runs
/// are unchanged), with the device for a stage on a GPU.
fn on_device(stage: &str, device: Device) -> String {
    match device {
        Device::Cpu => stage.to_string(),
        d => format!("{stage}@{d}"),
    }
}

fn write_csv(path: &Path, scorer: &str, seq: &PoseSequence) -> Result<(), PipelineError> {
    atomic::write_with(path, |w| {
        gait_core::dlc::write(w, scorer, seq).map_err(std::io::Error::other)
    })
    .map_err(|e| PipelineError::io(format!("writing {}", path.display()), e))
}

/// What every pass shares: the stages and the per-stage records.
struct Tools<'a> {
    config: &'a PipelineConfig,
    stages: &'a mut Stages,
    records: &'a mut BTreeMap<String, StageRecord>,
    n_keypoints: usize,
}

impl<'t> Tools<'t> {
    /// A driver for one pass: `regenerate` = through edges and regenerator
    /// into `pose_cache`, else the original frames into it.
    fn pass<'a>(
        &'a mut self,
        caches: &'a StageCaches,
        pose_cache: &'a StageCache,
        regenerate: bool,
        order: Order,
    ) -> Driver<'a> {
        Driver {
            config: self.config,
            stages: self.stages,
            caches: Caches {
                edge: &caches.edge,
                regenerator: &caches.regenerator,
                pose: pose_cache,
            },
            records: self.records,
            n_keypoints: self.n_keypoints,
            regenerate,
            pose_record: if regenerate { "pose" } else { ORIGINAL_POSE },
            order,
            last_estimated: None,
            cached_frames: BTreeSet::new(),
            original_poses: None,
        }
    }
}

fn progress_bar(enabled: bool, total: Option<usize>, pass: &str) -> ProgressBar {
    if !enabled {
        return ProgressBar::hidden();
    }
    let bar = match total {
        Some(n) => ProgressBar::with_draw_target(Some(n as u64), ProgressDrawTarget::stderr()),
        None => ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr()),
    };
    let style = ProgressStyle::with_template(
        "{spinner} [{elapsed_precise}] {msg} {wide_bar} {pos}/{len} frames {per_sec} ETA {eta}",
    )
    .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style);
    bar.set_message(pass.to_string());
    bar
}
