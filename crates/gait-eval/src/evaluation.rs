//! One prediction evaluated against ground truth.

use gait_core::PoseSequence;
use serde::{Deserialize, Serialize};

use crate::EvalError;
use crate::align::align;
use crate::angles::{AngleTable, KinematicsErrors, angle_errors};
use crate::failure::{Failures, failures};
use crate::keypoint_error::{KeypointError, LegError, keypoint_errors};
use crate::options::EvalOptions;

/// Everything [`evaluate`] measures; serialised as `metrics.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Evaluation {
    pub options: EvalOptions,
    /// Frames compared (present in both files).
    pub frames_compared: usize,
    pub keypoints: Vec<KeypointError>,
    pub legs: Vec<LegError>,
    /// `None` when no angles were given or computed.
    pub kinematics: Option<KinematicsErrors>,
    pub failures: Failures,
    /// Things a reader should know (unmatched frames or names, swapped frames, ...).
    pub warnings: Vec<String>,
}

fn list(frames: &[usize]) -> String {
    let shown: Vec<String> = frames.iter().take(10).map(usize::to_string).collect();
    let more = if frames.len() > 10 {
        format!(", ... ({} in all)", frames.len())
    } else {
        String::new()
    };
    format!("{}{more}", shown.join(", "))
}

/// Evaluates `pred` against `truth`: keypoint errors, failure modes and, when
/// both angle tables are given, kinematics errors.
pub fn evaluate_with_angles(
    truth: &PoseSequence,
    pred: &PoseSequence,
    angles: Option<(&AngleTable, &AngleTable)>,
    opts: &EvalOptions,
) -> Result<Evaluation, EvalError> {
    opts.validate()?;
    let a = align(truth, pred, &opts.name_map)?;
    let (keypoints, legs) = keypoint_errors(&a, opts);
    let failures = failures(&a, opts)?;
    let kinematics = angles.map(|(t, p)| angle_errors(t, p, opts)).transpose()?;
    let mut warnings = Vec::new();
    if !a.truth_only_frames.is_empty() {
        warnings.push(format!(
            "ground-truth frames without a prediction (not evaluated): {}",
            list(&a.truth_only_frames)
        ));
    }
    if !a.pred_only_frames.is_empty() {
        warnings.push(format!(
            "{} predicted frames have no ground truth and were not evaluated",
            a.pred_only_frames.len()
        ));
    }
    if !a.unmatched_names.is_empty() {
        warnings.push(format!(
            "keypoints not compared (no counterpart): {}",
            a.unmatched_names.join(", ")
        ));
    }
    if !failures.swapped_frames.is_empty() {
        warnings.push(format!(
            "left/right legs swapped in frames {}",
            list(&failures.swapped_frames)
        ));
    }
    Ok(Evaluation {
        options: opts.clone(),
        frames_compared: a.frames.len(),
        keypoints,
        legs,
        kinematics,
        failures,
        warnings,
    })
}
