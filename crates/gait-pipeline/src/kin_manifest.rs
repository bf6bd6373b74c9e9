//! kin.json: what `gait review DIR` needs to open a `gait kin` (or Python `gait.kin`) folder as
//! the analysis it is: the keypoints file, its frame rate and the resolved settings. With it
//! the checklist's `gait review DIR --frame N` links work for those folders as for runs.

use std::path::Path;

use crate::{PipelineConfig, PipelineError};

/// What the folder was made from.
pub struct KinSource<'a> {
    /// The keypoints file the analysis read (made absolute where it exists).
    pub keypoints: &'a Path,
    pub fps: f64,
    /// A multi-animal DeepLabCut file's individual, when one was chosen.
    pub individual: Option<&'a str>,
    /// What wrote it, e.g. `gait kin 0.1.0`.
    pub tool: &'a str,
}

/// Writes `dir/kin.json` for `source` analysed with `config` into `result`: its warnings (the
/// report lists them, as it lists a run's from run.json) and its view decision (the checklist
/// reads the walk's angle there, as from a run's run.json).
pub fn write_kin_manifest(
    dir: &Path,
    source: &KinSource,
    config: &PipelineConfig,
    result: &gait_kin::KinResult,
) -> Result<(), PipelineError> {
    let keypoints =
        std::fs::canonicalize(source.keypoints).unwrap_or(source.keypoints.to_path_buf());
    let manifest = serde_json::json!({
        "tool": source.tool,
        "keypoints": keypoints,
        "fps": source.fps,
        "individual": source.individual,
        "config": config,
        "warnings": result.warnings,
        "view": result.view,
    });
    let path = dir.join("kin.json");
    let text = serde_json::to_string_pretty(&manifest)
        .map_err(|e| PipelineError::io(format!("writing {}", path.display()), e.into()))?;
    crate::atomic::write(&path, text.as_bytes())
        .map_err(|e| PipelineError::io(format!("writing {}", path.display()), e))
}

/// Writes `seq` as `dir/keypoints.csv` (DeepLabCut layout): keypoints given as a table in
/// memory (Python's `gait.kin`) kept for kin.json to name.
pub fn write_kin_keypoints(
    dir: &Path,
    seq: &gait_core::PoseSequence,
) -> Result<std::path::PathBuf, PipelineError> {
    let path = dir.join("keypoints.csv");
    crate::atomic::write_with(&path, |w| {
        gait_core::dlc::write(w, "gait.kin", seq).map_err(std::io::Error::other)
    })
    .map_err(|e| PipelineError::io(format!("writing {}", path.display()), e))?;
    Ok(path)
}
