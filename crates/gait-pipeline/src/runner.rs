//! Runs a pipeline as a sequence of named passes: the subject pass (who is
//! followed, and where), the pose passes (original-frame poses when only poor
//! frames are regenerated, then the regeneration pass), the frames a stride
//! skipped filled in, `keypoints.csv` and `run.json` written, then the
//! kinematics.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::time::{Instant, SystemTime, UNIX_EPOCH};

use gait_core::{Pose, PoseSequence, StageContext};

use crate::input::InputInfo;
use crate::manifest::{InputRecord, RunManifest, StageRecord};
use crate::passes::{PassOutput, Passes};
use crate::plan::{self, Models};
use crate::progress::{Progress, RunHandle};
use crate::registry;
use crate::selection::{self, SelectionMode, SelectionRecord};
use crate::sharpness::Sharpness;
use crate::subject;
use crate::timings::Timings;
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
    /// Kept by a front end that stops the run or draws its own progress.
    pub handle: Option<RunHandle>,
}

/// What a finished run produced.
#[derive(Debug, Clone)]
pub struct RunSummary {
    pub poses: PoseSequence,
    pub manifest: RunManifest,
    /// Angles, events and cycles of the run.
    pub kinematics: Option<gait_kin::KinResult>,
    /// The run folder's lock, held until the summary (and every clone) is
    /// dropped, so the report and exports written after it are covered too.
    pub lock: Option<std::sync::Arc<crate::FolderLock>>,
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

/// Everything the passes need, up to and including the subject pass.
struct Prepared {
    info: InputInfo,
    fps: f64,
    stages: registry::Stages,
    names: Vec<String>,
    models: Models,
    subject: Option<gait_subject::Subject>,
    caches: plan::StageCaches,
    records: BTreeMap<String, StageRecord>,
    warnings: Vec<String>,
}

/// Opens the input, builds the stages, finds the subject and opens the stage caches.
fn prepare(
    config: &PipelineConfig,
    opts: &RunOptions,
    timings: &mut Timings,
) -> Result<Prepared, PipelineError> {
    let info = timings.time("probing the input", || InputInfo::open(&opts.input))?;
    let fps = config.input.fps.unwrap_or(info.fps);
    registry::check_devices(config)?;
    let ctx = StageContext::new(&opts.models_dir).on(config.run.device);
    let mut stages = timings.time("loading the models", || registry::build(config, &ctx))?;
    let names = stages.pose.keypoint_names();
    check_selection(config, &names)?;
    create_out_dir(&opts.out)?;
    let fingerprint = timings.time("checksum of the input", || info.fingerprint())?;
    let models = timings.time("checksums of the models", || {
        Models::new(config, &ctx, fingerprint)
    });
    let root = plan::cache_root(config, &opts.out);
    let total = range_len(config, &info);
    let bar = |pass: &str| Progress::new(opts.progress, total, pass, opts.handle.as_ref());
    let (t, read) = (Instant::now(), info.seconds_reading());
    // The pose pass reads the frames the subject pass decoded.
    if config.subject.enabled {
        info.keep_frames();
    }
    let (subject, subject_record, warnings) = subject::run_pass(
        config,
        &info,
        fps,
        (&ctx, stages.pose.as_mut()),
        &models,
        root.as_deref(),
        &bar,
    )?;
    stages.pose.reset();
    let model = subject_record.as_ref().map_or(0.0, |(_, r)| r.seconds);
    let decoding = info.seconds_reading() - read;
    timings.add_pass("subject pass", t.elapsed().as_secs_f64(), model, decoding);
    let (caches, mut records) = timings.time("opening the caches", || {
        plan::stage_caches(config, &models, subject.as_ref(), root.as_deref())
    })?;
    records.extend(subject_record);
    Ok(Prepared {
        info,
        fps,
        stages,
        names,
        models,
        subject,
        caches,
        records,
        warnings,
    })
}

/// Runs the pipeline on `opts.input` and writes the run folder: the subject
/// pass, the pose passes, the keypoints, then the kinematics.
/// A run stopped by its handle leaves a run.json that says so, and where.
pub fn run(config: &PipelineConfig, opts: &RunOptions) -> Result<RunSummary, PipelineError> {
    let started_unix = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let mut timings = Timings::from_process_start();
    let lock = crate::FolderLock::acquire(&opts.out, &holder(&opts.command))?;
    let mut summary = run_from(config, opts, started_unix, &mut timings).inspect_err(|e| {
        if let PipelineError::Interrupted { step } = e {
            write_interrupted(config, opts, started_unix, step);
        }
    })?;
    summary.lock = Some(std::sync::Arc::new(lock));
    Ok(summary)
}

/// How the lock file names the run, e.g. "gait run".
fn holder(command: &[String]) -> String {
    let program = command.first().map_or("gait", |c| {
        Path::new(c)
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or(c)
    });
    match command.get(1).filter(|_| program == "gait") {
        Some(sub) => format!("{program} {sub}"),
        None => program.to_string(),
    }
}

/// run.json of an interrupted run: what was being done, and how to repeat it
/// (the rerun resumes from the cache).
fn write_interrupted(config: &PipelineConfig, opts: &RunOptions, started_unix: u64, step: &str) {
    let json = serde_json::json!({
        "tool": "gait",
        "version": env!("CARGO_PKG_VERSION"),
        "status": "interrupted",
        "interrupted_during": step,
        "started_unix": started_unix,
        "command": opts.command,
        "input": { "path": opts.input },
        "config": serde_json::to_value(config).unwrap_or_default(),
    });
    let path = opts.out.join("run.json");
    // The interruption is what the caller reports; a folder that cannot take
    // run.json has already said so, or will at the rerun.
    let _ = atomic::write(&path, &serde_json::to_vec_pretty(&json).unwrap_or_default());
}

fn run_from(
    config: &PipelineConfig,
    opts: &RunOptions,
    started_unix: u64,
    timings: &mut Timings,
) -> Result<RunSummary, PipelineError> {
    let Prepared {
        info,
        fps,
        mut stages,
        names,
        models,
        subject,
        caches,
        mut records,
        mut warnings,
    } = prepare(config, opts, timings)?;
    let total = range_len(config, &info);
    let bar = |pass: &str| Progress::new(opts.progress, total, pass, opts.handle.as_ref());
    let model_seconds = |r: &BTreeMap<String, StageRecord>| -> f64 {
        let passes = r.iter().filter(|(k, _)| k.as_str() != plan::SUBJECT);
        passes.map(|(_, v)| v.seconds).sum()
    };
    let (t, read, model) = (
        Instant::now(),
        info.seconds_reading(),
        model_seconds(&records),
    );
    let out = Passes {
        config,
        info: &info,
        stages: &mut stages,
        caches: &caches,
        records: &mut records,
        n_keypoints: names.len(),
        names: &names,
        subject: subject.as_ref().map(|s| &s.boxes),
        range_end: subject.as_ref().map(|s| s.last_frame),
        bar: &bar,
        sharpness: Sharpness::new(&names, fps, config.input.first_frame),
    }
    .run()?;
    info.release_kept_frames();
    let (model, decoding) = (
        model_seconds(&records) - model,
        info.seconds_reading() - read,
    );
    timings.add_pass("pose pass", t.elapsed().as_secs_f64(), model, decoding);
    warnings.extend(stages.regenerator.take_warnings());
    warnings.extend(caches.take_warnings());
    warnings.extend(info.decode_warnings());
    if out.all.is_empty() {
        return Err(PipelineError::input(
            &opts.input,
            info.no_frames_in(config.input.first_frame, config.input.last_frame),
        ));
    }
    let t = Instant::now();
    let (seq, selection) = assemble(config, fps, &names, &out);
    write_keypoints(opts, &records, &seq, out.original)?;
    timings.add("keypoints.csv", t.elapsed().as_secs_f64());

    let manifest = RunManifest {
        tool: "gait",
        version: env!("CARGO_PKG_VERSION"),
        status: "done",
        reason: None,
        started_unix,
        command: opts.command.clone(),
        input: InputRecord {
            path: opts.input.clone(),
            absolute_path: std::path::absolute(&opts.input).ok(),
            sha256: models.input_key.clone(),
            width: info.width,
            height: info.height,
            fps,
            frame_timing: info.timing.clone(),
            hdr_transfer: info.hdr_transfer.clone(),
            interlaced: info.interlaced.clone(),
            first_frame: config.input.first_frame,
            last_frame: config.input.last_frame,
            exif_orientation: info.orientations.clone(),
            blur_px: out.blur_px.clone(),
            feet_contrast: out.feet_contrast.clone(),
        },
        config: serde_json::to_value(config).unwrap_or_default(),
        models: models.all(),
        stages: records,
        frames_processed: seq.poses.len(),
        frames_from_cache: out.from_cache,
        selection,
        subject,
        keypoint_names: names,
        warnings,
        extra: BTreeMap::new(),
        timings: timings.clone(),
        backend_choices: config.backend_choices.clone(),
    };
    let mut summary = RunSummary {
        poses: seq,
        manifest,
        kinematics: None,
        lock: None,
    };
    // Keypoints are on disk before the kinematics run, so a kinematics
    // failure loses none of the (possibly hours of) pose work.
    summary.write_manifest(&opts.out)?;
    let t = Instant::now();
    kinematics(config, &info, &mut summary, &opts.out)?;
    timings.add(
        "kinematics (angles, events, cycles)",
        t.elapsed().as_secs_f64(),
    );
    summary.manifest.timings = timings.clone();
    Ok(summary)
}

/// Unknown keypoint names of the poor-frame rule fail before any frame is decoded.
fn check_selection(config: &PipelineConfig, names: &[String]) -> Result<(), PipelineError> {
    if config.selection.mode == SelectionMode::Poor {
        selection::judge(&[], names, &config.selection)
            .map_err(|e| PipelineError::config("selection.keypoints", e))?;
    }
    Ok(())
}

fn create_out_dir(out: &Path) -> Result<(), PipelineError> {
    std::fs::create_dir_all(out)
        .map_err(|e| PipelineError::io(format!("creating the output folder {}", out.display()), e))
}

/// Frames in the configured range, when the input says how many it has.
fn range_len(config: &PipelineConfig, info: &InputInfo) -> Option<usize> {
    info.frames.map(|n| {
        let end = config.input.last_frame.map_or(n, |l| (l + 1).min(n));
        end.saturating_sub(config.input.first_frame)
    })
}

/// Part `part` (from 0) of `parts` of a run's regeneration, for a study spread over a
/// cluster: the subject pass and the passes on the original frames (both cached, so every part
/// finds the same), then the edge maps and regenerated images of the part's share of the
/// frames to regenerate, into the shared cache. No pose is estimated from them and the run
/// folder gets no results: a later `run` with the same config takes the images from the cache
/// and gives exactly what it gives without the parts. Returns the regenerator's record.
pub fn regenerate_part(
    config: &PipelineConfig,
    opts: &RunOptions,
    part: usize,
    parts: usize,
) -> Result<StageRecord, PipelineError> {
    if plan::cache_root(config, &opts.out).is_none() {
        return Err(PipelineError::config(
            "[run]",
            "regenerating a part of a run needs the cache (run.cache = true)",
        ));
    }
    // A part would start afresh where the frame before belongs to another part.
    if parts > 1 && config.regenerator.chains_frames() {
        return Err(PipelineError::config(
            "[regenerator]",
            "init = \"previous\" starts each frame from the one before, which splitting the \
             frames into parts would cut apart: use init = \"noise\" to split",
        ));
    }
    let mut p = prepare(config, opts, &mut Timings::default())?;
    let total = range_len(config, &p.info);
    let bar = |pass: &str| Progress::new(opts.progress, total, pass, opts.handle.as_ref());
    Passes {
        config,
        info: &p.info,
        stages: &mut p.stages,
        caches: &p.caches,
        records: &mut p.records,
        n_keypoints: p.names.len(),
        names: &p.names,
        subject: p.subject.as_ref().map(|s| &s.boxes),
        range_end: p.subject.as_ref().map(|s| s.last_frame),
        bar: &bar,
        sharpness: Sharpness::new(&p.names, p.info.fps, config.input.first_frame),
    }
    .regenerate_part(part, parts)?;
    Ok(p.records.remove("regenerator").unwrap_or_default())
}

/// The poses of every frame of the range (a stride's skipped frames
/// interpolated) and the record of which frames went where.
fn assemble(
    config: &PipelineConfig,
    fps: f64,
    names: &[String],
    out: &PassOutput,
) -> (PoseSequence, SelectionRecord) {
    let mut record = out.selection.clone();
    let (poses, interpolated) = interpolate::fill(&out.all, &out.processed, names.len());
    let processed_frames: Vec<usize> = out.processed.iter().map(|(f, _)| *f).collect();
    let poor_mode = config.selection.mode == SelectionMode::Poor;
    let poor_set: BTreeSet<usize> = record
        .poor
        .values()
        .flat_map(|rs| rs.iter().flat_map(|r| r[0]..=r[1]))
        .collect();
    let (regenerated, kept): (Vec<usize>, Vec<usize>) = processed_frames
        .iter()
        .partition(|f| !poor_mode || poor_set.contains(f));
    record.frames = out.all.len();
    record.processed = selection::ranges(processed_frames.iter().copied());
    record.regenerated_count = regenerated.len();
    record.regenerated = selection::ranges(regenerated);
    record.original_count = kept.len();
    record.original = selection::ranges(kept);
    record.interpolated_count = interpolated.len();
    record.interpolated = selection::ranges(interpolated);
    let seq = PoseSequence {
        fps,
        names: names.to_vec(),
        frames: out.all.clone(),
        poses,
    };
    (seq, record)
}

/// `keypoints.csv`, and `keypoints_original.csv` with the poses the
/// poor-frame rule judged.
fn write_keypoints(
    opts: &RunOptions,
    records: &BTreeMap<String, StageRecord>,
    seq: &PoseSequence,
    original: Option<Vec<(usize, Pose)>>,
) -> Result<(), PipelineError> {
    let scorer = format!("gait-{}", records["pose"].kind.replace('/', "-"));
    write_csv(&opts.out.join("keypoints.csv"), &scorer, seq)?;
    if let Some(original) = original {
        let (frames, poses) = original.into_iter().unzip();
        let seq = PoseSequence {
            fps: seq.fps,
            names: seq.names.clone(),
            frames,
            poses,
        };
        write_csv(&opts.out.join("keypoints_original.csv"), &scorer, &seq)?;
    }
    Ok(())
}

/// Angles, bouts, events and cycles of the run's keypoints, written beside
/// them and summarised in run.json.
fn kinematics(
    config: &PipelineConfig,
    info: &InputInfo,
    summary: &mut RunSummary,
    out: &Path,
) -> Result<(), PipelineError> {
    let mut kin_config = config.kinematics.clone();
    // Bouts need the frame's size to tell a body cut by the image edge.
    kin_config
        .frame_size
        .get_or_insert([info.width, info.height]);
    kin_config.image_blur_px = Some(summary.manifest.input.blur_px.clone());
    kin_config.image_feet_contrast = Some(summary.manifest.input.feet_contrast.clone());
    // A person's corrections saved in the run folder (by `gait review` or by
    // hand) apply to every rerun into that folder unless the config names a file.
    let saved = out.join("corrections.toml");
    if kin_config.corrections.is_none() && saved.is_file() {
        kin_config.corrections = Some(saved);
    }
    let kin = gait_kin::analyse(&summary.poses, &config.postprocess, &kin_config)
        .map_err(gait_core::StageError::from)?;
    gait_kin::write_outputs(&kin, out).map_err(gait_core::StageError::from)?;
    summary
        .manifest
        .warnings
        .extend(kin.warnings.iter().cloned());
    summary.manifest.extra.insert(
        "kinematics".into(),
        serde_json::to_value(&kin).unwrap_or_default(),
    );
    summary.manifest.reason = crate::manifest::no_result_reason(&kin);
    if summary.manifest.reason.is_some() {
        summary.manifest.status = "no_result";
    }
    summary.write_manifest(out)?;
    summary.kinematics = Some(kin);
    Ok(())
}

fn write_csv(path: &Path, scorer: &str, seq: &PoseSequence) -> Result<(), PipelineError> {
    atomic::write_with(path, |w| {
        gait_core::dlc::write(w, scorer, seq).map_err(std::io::Error::other)
    })
    .map_err(|e| PipelineError::io(format!("writing {}", path.display()), e))
}

/// What `gait run` (and Python's `gait.run`) does once the config is
/// resolved: the run, then the exports, overlay and report written from what
/// the run wrote, so they show exactly the files a reader of the folder gets.
pub fn run_and_write(
    config: &PipelineConfig,
    opts: &RunOptions,
) -> Result<(RunSummary, crate::Outputs), PipelineError> {
    let mut summary = run(config, opts)?;
    let outputs = crate::write_outputs(&crate::OutputOptions {
        dir: &opts.out,
        input: Some(opts.input.as_path()),
        config,
        fps: None,
        progress: opts.progress,
        handle: opts.handle.as_ref(),
    })
    .inspect_err(|e| {
        if let PipelineError::Interrupted { step } = e {
            write_interrupted(config, opts, summary.manifest.started_unix, step);
        }
    })?;
    let timings = &mut summary.manifest.timings;
    for step in crate::outputs::STEPS {
        if let Some(s) = outputs.seconds.get(step) {
            timings.add(*step, *s);
        }
    }
    timings.close();
    crate::outputs::record_in_manifest(&opts.out, "timings", &*timings)?;
    Ok((summary, outputs))
}

/// The models folder when none is given: `$GAIT_MODELS_DIR`, else the user
/// cache (`$XDG_CACHE_HOME/gait/models`, `~/.cache/gait/models`).
pub fn default_models_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os("GAIT_MODELS_DIR").filter(|d| !d.is_empty()) {
        return PathBuf::from(dir);
    }
    let cache = std::env::var_os("XDG_CACHE_HOME")
        .filter(|d| !d.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
        .unwrap_or_else(|| PathBuf::from("."));
    cache.join("gait").join("models")
}

/// What `gait kin` (and Python's `gait.kin`) does with keypoints: the
/// kinematics written into `out` with kin.json naming `source`, then the
/// exports, report and PDF (no overlay: there is no video).
pub fn kin_and_write(
    seq: &PoseSequence,
    config: &PipelineConfig,
    out: &Path,
    source: &crate::KinSource,
) -> Result<(gait_kin::KinResult, crate::Outputs), PipelineError> {
    let result = gait_kin::analyse(seq, &config.postprocess, &config.kinematics)
        .map_err(gait_core::StageError::from)?;
    gait_kin::write_outputs(&result, out).map_err(gait_core::StageError::from)?;
    crate::write_kin_manifest(out, source, config, &result)?;
    let outputs = crate::write_outputs(&crate::OutputOptions {
        dir: out,
        input: None,
        config,
        fps: Some(seq.fps),
        progress: false,
        handle: None,
    })?;
    Ok((result, outputs))
}
