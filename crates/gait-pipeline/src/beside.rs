//! The run a keypoints file came from: a run folder's keypoints.csv has run.json beside it,
//! which holds what the keypoints alone do not (the frame rate, the frame size the bout rules
//! need, the run's analysis settings). `gait kin` and `gait review --keypoints` read it, so a
//! run's keypoints repeat its kinematics.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::PipelineError;

/// What run.json beside a keypoints file says about the video.
#[derive(Debug, Clone, PartialEq)]
pub struct RunBeside {
    /// The run.json read.
    pub manifest: PathBuf,
    pub fps: Option<f64>,
    /// Width and height of the frames, in pixels.
    pub frame_size: Option<[u32; 2]>,
    /// The blur of the subject's legs per frame measured (`input.blur_px`), which the stride
    /// checks judge (`kinematics.image_blur_px`).
    pub blur_px: Option<BTreeMap<usize, f64>>,
    /// Each foot's outline contrast per frame (`input.feet_contrast`), which the motion-blur
    /// check judges (`kinematics.image_feet_contrast`).
    pub feet_contrast: Option<gait_kin::FeetContrast>,
}

impl RunBeside {
    /// run.json in the folder of `keypoints`, when there is one; an unreadable one is an error
    /// (it would otherwise be silently ignored and the analysis differ from the run's).
    pub fn find(keypoints: &Path) -> Result<Option<Self>, PipelineError> {
        let manifest = keypoints.with_file_name("run.json");
        if !manifest.is_file() {
            return Ok(None);
        }
        let bad = |why: String| {
            PipelineError::config(
                manifest.display().to_string(),
                format!("{why}; repair or remove it, or give --fps and --config"),
            )
        };
        let text = std::fs::read_to_string(&manifest)
            .map_err(|e| bad(format!("cannot read the file ({e})")))?;
        let json: Value =
            serde_json::from_str(&text).map_err(|e| bad(format!("not JSON ({e})")))?;
        let size = |k: &str| {
            json.pointer(&format!("/input/{k}"))
                .and_then(Value::as_u64)
                .and_then(|v| u32::try_from(v).ok())
        };
        Ok(Some(Self {
            fps: json
                .pointer("/input/fps")
                .and_then(Value::as_f64)
                .filter(|f| f.is_finite() && *f > 0.0),
            frame_size: size("width").zip(size("height")).map(|(w, h)| [w, h]),
            blur_px: json.pointer("/input/blur_px").and_then(blur_table),
            feet_contrast: json.pointer("/input/feet_contrast").and_then(feet_table),
            manifest,
        }))
    }
}

/// `{"frame": px, ...}` as written by the run; entries that are not a frame number and a
/// number are left out.
fn blur_table(v: &Value) -> Option<BTreeMap<usize, f64>> {
    let table = v.as_object()?;
    Some(
        table
            .iter()
            .filter_map(|(k, v)| Some((k.parse().ok()?, v.as_f64()?)))
            .collect(),
    )
}

/// `{"frame": [left, right], ...}` as written by the run (`null` where a foot was not
/// measured); malformed entries are left out.
fn feet_table(v: &Value) -> Option<gait_kin::FeetContrast> {
    let table = v.as_object()?;
    Some(
        table
            .iter()
            .filter_map(|(k, v)| {
                let pair = v.as_array().filter(|a| a.len() == 2)?;
                Some((k.parse().ok()?, [pair[0].as_f64(), pair[1].as_f64()]))
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_fps_and_size_and_refuses_a_broken_file() {
        let dir = tempfile::tempdir().unwrap();
        let kp = dir.path().join("keypoints.csv");
        assert_eq!(RunBeside::find(&kp).unwrap(), None);
        let manifest = dir.path().join("run.json");
        std::fs::write(
            &manifest,
            r#"{"input": {"fps": 30.0, "width": 1768, "height": 994, "blur_px": {"60": 1.5, "65": 1.75}, "feet_contrast": {"60": [25.0, null], "61": [24.5, 12.0], "62": 3}}}"#,
        )
        .unwrap();
        let found = RunBeside::find(&kp).unwrap().unwrap();
        assert_eq!(found.fps, Some(30.0));
        assert_eq!(found.frame_size, Some([1768, 994]));
        assert_eq!(found.blur_px, Some(BTreeMap::from([(60, 1.5), (65, 1.75)])));
        assert_eq!(
            found.feet_contrast,
            Some(BTreeMap::from([
                (60, [Some(25.0), None]),
                (61, [Some(24.5), Some(12.0)])
            ]))
        );
        std::fs::write(&manifest, "{").unwrap();
        let e = RunBeside::find(&kp).unwrap_err().to_string();
        assert!(e.contains("run.json") && e.contains("not JSON"), "{e}");
    }
}
