//! Drives frames through the stages in batches, using the per-frame cache,
//! and writes `keypoints.csv` and `run.json` into the run folder.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::{Instant, SystemTime, UNIX_EPOCH};

use gait_core::{EdgeMap, Frame, Pose, PoseSequence, StageContext};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::cache::{StageCache, chain_key};
use crate::input::InputInfo;
use crate::manifest::{InputRecord, RunManifest, StageRecord, model_records};
use crate::registry::{self, Stages};
use crate::{PipelineConfig, PipelineError, atomic};

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

struct Caches {
    edge: StageCache,
    regenerator: StageCache,
    pose: StageCache,
}

/// Runs the pipeline on `opts.input` and writes the run folder.
pub fn run(config: &PipelineConfig, opts: &RunOptions) -> Result<RunSummary, PipelineError> {
    let started_unix = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let info = InputInfo::open(&opts.input)?;
    let fps = config.input.fps.unwrap_or(info.fps);
    let ctx = StageContext::new(&opts.models_dir);
    let mut stages = registry::build(config, &ctx)?;
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
    let edge_key = chain_key(&input_key, "edge", &(&config.edge, &edge_models));
    let regen_key = chain_key(
        &edge_key,
        "regenerator",
        &(&config.regenerator, &regen_models),
    );
    let pose_key = chain_key(&regen_key, "pose", &(&config.pose, &pose_models));
    let caches = if config.run.cache {
        let root = config
            .run
            .cache_dir
            .clone()
            .unwrap_or_else(|| opts.out.join("cache"));
        Caches {
            edge: StageCache::open(&root, "edge", &edge_key, &config.edge)?,
            regenerator: StageCache::open(&root, "regenerator", &regen_key, &config.regenerator)?,
            pose: StageCache::open(&root, "pose", &pose_key, &config.pose)?,
        }
    } else {
        Caches {
            edge: StageCache::disabled(),
            regenerator: StageCache::disabled(),
            pose: StageCache::disabled(),
        }
    };
    let mut records: BTreeMap<String, StageRecord> = BTreeMap::new();
    for ((stage, kind), key) in registry::stage_kinds(config)
        .into_iter()
        .zip([&edge_key, &regen_key, &pose_key])
    {
        records.insert(
            stage.to_string(),
            StageRecord {
                kind,
                cache_key: key[..16].to_string(),
                ..StageRecord::default()
            },
        );
    }

    let names = stages.pose.keypoint_names();
    let total = info.frames.map(|n| {
        let end = config.input.last_frame.map_or(n, |l| (l + 1).min(n));
        end.saturating_sub(config.input.first_frame)
    });
    let bar = progress_bar(opts.progress, total);
    let mut driver = Driver {
        config,
        stages: &mut stages,
        caches: &caches,
        records: &mut records,
        n_keypoints: names.len(),
        last_estimated: None,
        from_cache: 0,
    };
    let mut reader = info.frames()?;
    let mut batch = Vec::with_capacity(config.run.batch_size);
    let mut seq = PoseSequence {
        fps,
        names: names.clone(),
        frames: Vec::new(),
        poses: Vec::new(),
    };
    loop {
        let next = reader.next_frame()?;
        let done = match &next {
            None => true,
            Some(f) => config.input.last_frame.is_some_and(|l| f.index > l),
        };
        if let Some(frame) = next.filter(|f| f.index >= config.input.first_frame && !done) {
            batch.push(frame);
        }
        if batch.len() == config.run.batch_size || (done && !batch.is_empty()) {
            let poses = driver.process(&batch)?;
            bar.inc(batch.len() as u64);
            seq.frames.extend(batch.iter().map(|f| f.index));
            seq.poses.extend(poses);
            batch.clear();
        }
        if done {
            break;
        }
    }
    bar.finish_and_clear();
    drop(reader);
    if seq.poses.is_empty() {
        return Err(PipelineError::input(
            &opts.input,
            format!(
                "no frames in the selected range (first_frame = {})",
                config.input.first_frame
            ),
        ));
    }
    let from_cache = driver.from_cache;

    let csv_path = opts.out.join("keypoints.csv");
    let scorer = format!("gait-{}", records["pose"].kind.replace('/', "-"));
    atomic::write_with(&csv_path, |w| {
        gait_core::dlc::write(w, &scorer, &seq).map_err(std::io::Error::other)
    })
    .map_err(|e| PipelineError::io(format!("writing {}", csv_path.display()), e))?;

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
        keypoint_names: names,
        warnings: Vec::new(),
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

fn progress_bar(enabled: bool, total: Option<usize>) -> ProgressBar {
    if !enabled {
        return ProgressBar::hidden();
    }
    let bar = match total {
        Some(n) => ProgressBar::with_draw_target(Some(n as u64), ProgressDrawTarget::stderr()),
        None => ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr()),
    };
    let style = ProgressStyle::with_template(
        "{spinner} [{elapsed_precise}] {wide_bar} {pos}/{len} frames {per_sec} ETA {eta}",
    )
    .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style);
    bar
}

/// Processes batches, taking each stage's results from the cache when it can.
struct Driver<'a> {
    config: &'a PipelineConfig,
    stages: &'a mut Stages,
    caches: &'a Caches,
    records: &'a mut BTreeMap<String, StageRecord>,
    n_keypoints: usize,
    /// Index of the last frame the pose stage saw, to reset trackers on gaps.
    last_estimated: Option<usize>,
    from_cache: usize,
}

impl Driver<'_> {
    fn record(&mut self, stage: &str) -> &mut StageRecord {
        self.records.entry(stage.to_string()).or_default()
    }

    fn process(&mut self, frames: &[Frame]) -> Result<Vec<Pose>, PipelineError> {
        let mut poses: Vec<Option<Pose>> = frames
            .iter()
            .map(|f| self.caches.pose.load_pose(f.index, self.n_keypoints))
            .collect();
        let cached = poses.iter().filter(|p| p.is_some()).count();
        self.from_cache += cached;
        self.record("pose").cached += cached;
        let todo: Vec<&Frame> = frames
            .iter()
            .zip(&poses)
            .filter(|(_, p)| p.is_none())
            .map(|(f, _)| f)
            .collect();
        if !todo.is_empty() {
            let redrawn = self.regenerated(&todo)?;
            // The pose stage may track across frames: hand it contiguous runs
            // and reset it where the sequence jumps (frames taken from cache).
            let mut start = 0;
            while start < redrawn.len() {
                let mut end = start + 1;
                while end < redrawn.len() && redrawn[end].index == redrawn[end - 1].index + 1 {
                    end += 1;
                }
                let run = &redrawn[start..end];
                if self.last_estimated.is_none_or(|l| l + 1 != run[0].index) {
                    // Resuming: restore the tracker as it was after the
                    // previous frame, so results equal an uninterrupted run.
                    let saved = run[0]
                        .index
                        .checked_sub(1)
                        .and_then(|p| self.caches.pose.load_state(p));
                    if !saved.is_some_and(|s| self.stages.pose.restore(&s)) {
                        self.stages.pose.reset();
                    }
                }
                // A stateful estimator goes frame by frame so that its state
                // after every frame can be saved with that frame's pose.
                let step = if self.stages.pose.state().is_some() {
                    1
                } else {
                    run.len()
                };
                for chunk in run.chunks(step) {
                    let t = Instant::now();
                    let found = self.stages.pose.estimate(chunk)?;
                    self.record("pose").seconds += t.elapsed().as_secs_f64();
                    self.record("pose").computed += chunk.len();
                    if found.len() != chunk.len()
                        || found.iter().any(|p| p.keypoints.len() != self.n_keypoints)
                    {
                        return Err(bad_output(
                            "pose",
                            "a pose per frame with one entry per keypoint name",
                        ));
                    }
                    let state = self.stages.pose.state();
                    for (frame, pose) in chunk.iter().zip(found) {
                        // State first: a pose on disk always has its state beside it.
                        if let Some(s) = &state {
                            self.caches.pose.store_state(frame.index, s)?;
                        }
                        self.caches.pose.store_pose(frame.index, &pose)?;
                        let slot = frames
                            .iter()
                            .position(|f| f.index == frame.index)
                            .unwrap_or(0);
                        poses[slot] = Some(pose);
                    }
                }
                self.last_estimated = Some(run[run.len() - 1].index);
                start = end;
            }
        }
        Ok(poses
            .into_iter()
            .map(|p| p.unwrap_or_else(|| Pose::empty(self.n_keypoints)))
            .collect())
    }

    /// The frames the pose model should see: regenerated (or cached) ones.
    fn regenerated(&mut self, frames: &[&Frame]) -> Result<Vec<Frame>, PipelineError> {
        let identity = self.config.regenerator.is_identity();
        let mut out: Vec<Option<Frame>> = frames
            .iter()
            .map(|f| {
                self.caches
                    .regenerator
                    .load_rgb(f.index)
                    .filter(|img| img.dimensions() == f.image.dimensions() && !identity)
                    .map(|img| Frame::new(f.index, img))
            })
            .collect();
        let cached = out.iter().filter(|f| f.is_some()).count();
        self.record("regenerator").cached += cached;
        let todo: Vec<Frame> = frames
            .iter()
            .zip(&out)
            .filter(|(_, o)| o.is_none())
            .map(|(f, _)| (*f).clone())
            .collect();
        if todo.is_empty() {
            return Ok(out.into_iter().flatten().collect());
        }
        let edges = self.edges(&todo)?;
        let t = Instant::now();
        let redrawn = self
            .stages
            .regenerator
            .regenerate(&todo, edges.as_deref())?;
        self.record("regenerator").seconds += t.elapsed().as_secs_f64();
        self.record("regenerator").computed += todo.len();
        if redrawn.len() != todo.len()
            || redrawn
                .iter()
                .zip(&todo)
                .any(|(r, f)| r.index != f.index || r.image.dimensions() != f.image.dimensions())
        {
            return Err(bad_output(
                "regenerator",
                "one frame per input frame, with its index and size",
            ));
        }
        let mut redrawn = redrawn.into_iter();
        for slot in out.iter_mut().filter(|o| o.is_none()) {
            let frame = redrawn
                .next()
                .ok_or_else(|| bad_output("regenerator", "one frame per input frame"))?;
            if !identity {
                self.caches
                    .regenerator
                    .store_rgb(frame.index, &frame.image)?;
            }
            *slot = Some(frame);
        }
        Ok(out.into_iter().flatten().collect())
    }

    /// Edge maps for `frames`, or `None` when the pipeline has no edge stage.
    fn edges(&mut self, frames: &[Frame]) -> Result<Option<Vec<EdgeMap>>, PipelineError> {
        if self.stages.edge.is_none() {
            return Ok(None);
        }
        let mut maps: Vec<Option<EdgeMap>> = frames
            .iter()
            .map(|f| {
                self.caches
                    .edge
                    .load_edge(f.index)
                    .map(|(image, resize)| EdgeMap {
                        index: f.index,
                        image,
                        resize,
                    })
            })
            .collect();
        let cached = maps.iter().filter(|m| m.is_some()).count();
        self.record("edge").cached += cached;
        let todo: Vec<Frame> = frames
            .iter()
            .zip(&maps)
            .filter(|(_, m)| m.is_none())
            .map(|(f, _)| f.clone())
            .collect();
        if !todo.is_empty() {
            let t = Instant::now();
            let detector = self
                .stages
                .edge
                .as_mut()
                .ok_or_else(|| bad_output("edge", "a detector"))?;
            let found = detector.detect(&todo)?;
            self.record("edge").seconds += t.elapsed().as_secs_f64();
            self.record("edge").computed += todo.len();
            if found.len() != todo.len() || found.iter().zip(&todo).any(|(m, f)| m.index != f.index)
            {
                return Err(bad_output("edge", "one edge map per frame, with its index"));
            }
            let mut found = found.into_iter();
            for slot in maps.iter_mut().filter(|m| m.is_none()) {
                let map = found
                    .next()
                    .ok_or_else(|| bad_output("edge", "one edge map per frame"))?;
                self.caches
                    .edge
                    .store_edge(map.index, &map.image, &map.resize)?;
                *slot = Some(map);
            }
        }
        Ok(Some(maps.into_iter().flatten().collect()))
    }
}

fn bad_output(stage: &str, expected: &str) -> PipelineError {
    PipelineError::Stage(gait_core::StageError::backend(
        stage,
        format!("the {stage} stage returned malformed results (expected {expected})"),
    ))
}
