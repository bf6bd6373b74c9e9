//! What a review shows and recomputes: the keypoints as the pose stage gave them, the
//! analysis settings, and where the frames and the corrections file are.

use std::path::{Path, PathBuf};

use gait_core::PoseSequence;
use gait_kin::{Corrections, KinematicsConfig, PostprocessConfig};
use gait_pipeline::PipelineConfig;

use crate::checklist::ChecklistSettings;
use gait_pipeline::input::InputInfo;
use serde_json::Value;

use crate::ReviewError;

/// A run folder, or a keypoints file with its video, ready to review.
pub struct ReviewSource {
    pub title: String,
    /// The pose stage's keypoints (a run's keypoints.csv), before any cleaning.
    pub seq: PoseSequence,
    pub post: PostprocessConfig,
    /// The run's kinematics settings, with the frame size set and no corrections file (the
    /// review passes its corrections itself).
    pub kin: KinematicsConfig,
    /// The only file a review writes.
    pub corrections_path: PathBuf,
    /// The corrections saved there when the review started (empty when there is no file).
    pub corrections: Corrections,
    /// The video to show, or why there is none (the page then shows plots only).
    pub video: Result<PathBuf, String>,
    /// The run's regenerated frames (`{frame:06}.png`), when its cache is inside the run folder.
    pub regenerated: Option<PathBuf>,
    /// Width and height of the frames, when known.
    pub frame_size: Option<[u32; 2]>,
    /// run.json's `subject` (tracks, the chosen one and why), when there is one.
    pub subject: Option<Value>,
    /// The command that writes the run's outputs again with the saved corrections.
    pub rerun: String,
    /// How the page's checklist is judged (the run's settings).
    pub checklist: ChecklistSettings,
}

fn read_json(path: &Path) -> Result<Value, ReviewError> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        ReviewError::run(
            path,
            format!("cannot read ({e}); is this a `gait run` folder?"),
        )
    })?;
    serde_json::from_str(&text).map_err(|e| ReviewError::run(path, format!("not valid JSON ({e})")))
}

fn read_keypoints(path: &Path, fps: f64) -> Result<PoseSequence, ReviewError> {
    let file = std::fs::File::open(path)
        .map_err(|e| ReviewError::run(path, format!("cannot open ({e})")))?;
    gait_core::dlc::read(std::io::BufReader::new(file), None, fps).map_err(|e| {
        let message = e
            .to_string()
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        ReviewError::run(path, message)
    })
}

/// The corrections saved at `path`, checked against `seq` (a bad file stops the review with the
/// same message `gait kin` gives).
fn saved_corrections(path: &Path, seq: &PoseSequence) -> Result<Corrections, ReviewError> {
    if !path.is_file() {
        return Ok(Corrections::default());
    }
    let c = Corrections::read(path)?;
    c.validate_file(seq, path)?;
    Ok(c)
}

/// The video if it can be opened and has the frame size the keypoints were found in.
fn check_video(path: &Path, size: Option<[u32; 2]>) -> Result<PathBuf, String> {
    if !path.exists() {
        return Err(format!(
            "the video {} is not there (moved or deleted): plots only; give it with --video FILE",
            path.display()
        ));
    }
    let info = InputInfo::open(path).map_err(|e| format!("the video cannot be opened: {e}"))?;
    match size {
        Some([w, h]) if [info.width, info.height] != [w, h] => Err(format!(
            "the video {} is {}x{} but the run's frames were {w}x{h}: plots only",
            path.display(),
            info.width,
            info.height
        )),
        _ => Ok(path.to_path_buf()),
    }
}

/// The input video run.json names: its absolute path when that exists, else the path as given
/// on the command line, tried from here and from the run folder and each folder above it
/// (`gait run` was run from one of them, usually).
fn named_video(manifest: &Value, dir: &Path) -> Option<PathBuf> {
    let get = |k: &str| {
        manifest
            .pointer(k)
            .and_then(Value::as_str)
            .map(PathBuf::from)
    };
    let given = get("/input/path")?;
    let found = get("/input/absolute_path")
        .into_iter()
        .chain([given.clone()])
        .chain(dir.ancestors().map(|a| a.join(&given)))
        .find(|p| p.exists());
    Some(found.unwrap_or(given))
}

/// What to do with a `gait visit` folder: review one of its passes (each a run folder).
fn visit_passes(dir: &Path) -> String {
    let mut passes: Vec<PathBuf> = std::fs::read_dir(dir.join("passes"))
        .into_iter()
        .flatten()
        .filter_map(|e| Some(e.ok()?.path()))
        .filter(|p| p.join("run.json").is_file())
        .collect();
    passes.sort();
    let commands: Vec<String> = passes
        .iter()
        .map(|p| format!("`gait review {}`", p.display()))
        .collect();
    match commands.is_empty() {
        true => "a visit folder without a finished pass: nothing to review".into(),
        false => format!(
            "a visit folder: review one of its passes, {} (the visit report names the pass and frame of each finding)",
            commands.join(" or ")
        ),
    }
}

/// `dir` holds `inner` (both made absolute and free of `..`).
fn inside(dir: &Path, inner: &Path) -> bool {
    match (dir.canonicalize(), inner.canonicalize()) {
        (Ok(d), Ok(i)) => i.starts_with(d),
        _ => false,
    }
}

impl ReviewSource {
    /// A `gait run` folder: run.json (settings, input, subject), keypoints.csv, the input video
    /// (`video` overrides the one run.json names) and corrections.toml.
    pub fn from_run_dir(dir: &Path, video: Option<&Path>) -> Result<Self, ReviewError> {
        if !dir.is_dir() {
            return Err(ReviewError::run(
                dir,
                "no such folder; give a `gait run` output folder",
            ));
        }
        let manifest_path = dir.join("run.json");
        if !manifest_path.exists() && dir.join("kin.json").exists() {
            return Self::from_kin_dir(dir, video);
        }
        if !manifest_path.exists() && dir.join("visit.json").exists() {
            return Err(ReviewError::run(dir, visit_passes(dir)));
        }
        let manifest = read_json(&manifest_path)?;
        let config = PipelineConfig::load(Some(&manifest_path), &[])?;
        let fps = manifest
            .pointer("/input/fps")
            .and_then(Value::as_f64)
            .ok_or_else(|| ReviewError::run(&manifest_path, "has no input.fps"))?;
        let seq = read_keypoints(&dir.join("keypoints.csv"), fps)?;
        let size = |k: &str| {
            manifest
                .pointer(&format!("/input/{k}"))
                .and_then(Value::as_u64)
                .map(|v| v as u32)
        };
        let frame_size = size("width").zip(size("height")).map(|(w, h)| [w, h]);
        let named = named_video(&manifest, dir);
        let video = match (video, &named) {
            (Some(v), _) => check_video(v, frame_size),
            (None, Some(v)) => check_video(v, frame_size),
            (None, None) => Err("run.json names no input video: plots only".into()),
        };
        let regenerated = gait_pipeline::regenerated_dir(dir, &config).filter(|r| inside(dir, r));
        let corrections_path = dir.join("corrections.toml");
        let corrections = saved_corrections(&corrections_path, &seq)?;
        let mut kin = config.kinematics.clone();
        kin.corrections = None;
        if kin.frame_size.is_none() {
            kin.frame_size = frame_size;
        }
        let beside = gait_pipeline::RunBeside::find(&dir.join("keypoints.csv"))?;
        kin.image_blur_px = beside.as_ref().and_then(|b| b.blur_px.clone());
        kin.image_feet_contrast = beside.and_then(|b| b.feet_contrast);
        let input = video
            .as_ref()
            .ok()
            .or(named.as_ref())
            .map_or("VIDEO".into(), |p| p.display().to_string());
        Ok(ReviewSource {
            title: dir.display().to_string(),
            seq,
            post: config.postprocess.clone(),
            kin,
            corrections_path,
            corrections,
            video,
            regenerated,
            frame_size,
            subject: manifest.get("subject").filter(|s| !s.is_null()).cloned(),
            checklist: ChecklistSettings::of(&config),
            rerun: format!(
                "gait run --config {0}/run.json --input {input} --out {0}",
                dir.display()
            ),
        })
    }

    /// A keypoints CSV (DeepLabCut layout) with its video; the analysis settings come from
    /// `config` (else the built-in default) and the corrections file is `corrections`
    /// (else corrections.toml beside the keypoints).
    /// A `gait kin` folder: kin.json names the keypoints and their frame rate and holds the
    /// settings the folder was made with; corrections are saved beside them in the folder.
    fn from_kin_dir(dir: &Path, video: Option<&Path>) -> Result<Self, ReviewError> {
        let path = dir.join("kin.json");
        let manifest = read_json(&path)?;
        let keypoints = manifest
            .get("keypoints")
            .and_then(Value::as_str)
            .map(PathBuf::from)
            .ok_or_else(|| ReviewError::run(&path, "names no keypoints file"))?;
        let fps = manifest
            .get("fps")
            .and_then(Value::as_f64)
            .ok_or_else(|| ReviewError::run(&path, "has no fps"))?;
        let corrections = dir.join("corrections.toml");
        let mut src =
            Self::from_keypoints(&keypoints, video, fps, Some(&path), Some(&corrections))?;
        src.title = dir.display().to_string();
        Ok(src)
    }

    pub fn from_keypoints(
        keypoints: &Path,
        video: Option<&Path>,
        fps: f64,
        config: Option<&Path>,
        corrections: Option<&Path>,
    ) -> Result<Self, ReviewError> {
        let seq = read_keypoints(keypoints, fps)?;
        // A run's keypoints.csv: its run.json gives the run's settings and frame size, so the
        // page shows the run's events and cycles (as `gait kin` on the same file does).
        let beside = gait_pipeline::RunBeside::find(keypoints)?;
        let config = config.or(beside.as_ref().map(|b| b.manifest.as_path()));
        let config = PipelineConfig::load(config, &[])?;
        let video = match video {
            Some(v) => check_video(v, None),
            None => Err("no --video given: plots only".into()),
        };
        let frame_size = video
            .as_ref()
            .ok()
            .and_then(|v| InputInfo::open(v).ok())
            .map(|i| [i.width, i.height])
            .or_else(|| beside.as_ref().and_then(|b| b.frame_size));
        let corrections_path = corrections.map_or_else(
            || keypoints.with_file_name("corrections.toml"),
            Path::to_path_buf,
        );
        let saved = saved_corrections(&corrections_path, &seq)?;
        let mut kin = config.kinematics.clone();
        kin.corrections = None;
        if kin.frame_size.is_none() {
            kin.frame_size = frame_size;
        }
        kin.image_blur_px = beside.as_ref().and_then(|b| b.blur_px.clone());
        kin.image_feet_contrast = beside.and_then(|b| b.feet_contrast);
        let size_set = kin.frame_size.map_or(String::new(), |[w, h]| {
            format!(" --set 'kinematics.frame_size=[{w}, {h}]'")
        });
        Ok(ReviewSource {
            title: keypoints.display().to_string(),
            rerun: format!(
                "gait kin --keypoints {} --fps {fps} --corrections {} --out OUT{size_set}",
                keypoints.display(),
                corrections_path.display()
            ),
            seq,
            post: config.postprocess.clone(),
            kin,
            corrections_path,
            corrections: saved,
            video,
            regenerated: None,
            frame_size,
            subject: None,
            checklist: ChecklistSettings::of(&config),
        })
    }
}
