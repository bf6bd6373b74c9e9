//! Putting ground truth and prediction side by side: frames by frame index,
//! keypoints by canonical name.

use std::collections::{BTreeMap, HashMap};

use gait_core::{CANONICAL, Keypoint, PoseSequence};

use crate::EvalError;
use crate::names::to_canonical;

/// Ground truth and prediction on common frames and common canonical names.
#[derive(Debug, Clone)]
pub struct Aligned {
    /// Frame indices present in both, in the truth's order.
    pub frames: Vec<usize>,
    /// Canonical names present in both, in [`CANONICAL`] order.
    pub names: Vec<String>,
    /// `truth[f][k]`: keypoint `names[k]` in frame `frames[f]`.
    pub truth: Vec<Vec<Keypoint>>,
    pub pred: Vec<Vec<Keypoint>>,
    /// Frames of the truth that the prediction lacks, and the other way round.
    pub truth_only_frames: Vec<usize>,
    pub pred_only_frames: Vec<usize>,
    /// Names of either file that were left out (no canonical name, or not in the other file).
    pub unmatched_names: Vec<String>,
}

/// Canonical name -> column, rejecting two columns that map to one name.
fn columns(
    seq: &PoseSequence,
    map: &BTreeMap<String, String>,
    what: &str,
) -> Result<BTreeMap<String, (usize, String)>, EvalError> {
    let mut out: BTreeMap<String, (usize, String)> = BTreeMap::new();
    for (i, name) in seq.names.iter().enumerate() {
        if let Some(c) = to_canonical(name, map) {
            if let Some((_, prev)) = out.get(&c) {
                return Err(EvalError::Mismatch(format!(
                    "{what} keypoints `{prev}` and `{name}` both map to `{c}`; map one of them elsewhere"
                )));
            }
            out.insert(c, (i, name.clone()));
        }
    }
    Ok(out)
}

/// `seq` with its keypoints renamed to canonical names where they have one
/// (see [`to_canonical`]), so that gait-kin finds them.
pub fn canonicalize(
    seq: &PoseSequence,
    map: &BTreeMap<String, String>,
) -> Result<PoseSequence, EvalError> {
    let cols = columns(seq, map, "input")?;
    let mut out = seq.clone();
    for (canonical, (i, _)) in cols {
        out.names[i] = canonical;
    }
    Ok(out)
}

fn frame_index(seq: &PoseSequence, what: &str) -> Result<HashMap<usize, usize>, EvalError> {
    let mut idx = HashMap::with_capacity(seq.frames.len());
    for (row, &f) in seq.frames.iter().enumerate() {
        if idx.insert(f, row).is_some() {
            return Err(EvalError::Mismatch(format!("{what} has frame {f} twice")));
        }
    }
    Ok(idx)
}

fn span(frames: &[usize]) -> String {
    match (frames.iter().min(), frames.iter().max()) {
        (Some(a), Some(b)) => format!("frames {a}..={b} ({} frames)", frames.len()),
        _ => "no frames".into(),
    }
}

/// Aligns `truth` and `pred` by frame index and by canonical name (through
/// `map`, then common spellings; see [`to_canonical`]). Fails, saying what
/// does not match, when they share no frame or no lower-limb keypoint.
pub fn align(
    truth: &PoseSequence,
    pred: &PoseSequence,
    map: &BTreeMap<String, String>,
) -> Result<Aligned, EvalError> {
    let tc = columns(truth, map, "ground-truth")?;
    let pc = columns(pred, map, "prediction")?;
    let names: Vec<String> = CANONICAL
        .iter()
        .filter(|n| tc.contains_key(**n) && pc.contains_key(**n))
        .map(|n| n.to_string())
        .collect();
    if !names
        .iter()
        .any(|n| crate::names::Side::of(n).is_some() && !n.ends_with("shoulder"))
    {
        return Err(EvalError::Mismatch(format!(
            "no lower-limb keypoint in common; ground truth has [{}], prediction has [{}] \
             (map names with `name_map`, e.g. \"RKnee\" = \"right_knee\")",
            truth.names.join(", "),
            pred.names.join(", ")
        )));
    }
    let mut unmatched_names: Vec<String> = Vec::new();
    for (seq, cols) in [(truth, &tc), (pred, &pc)] {
        for name in &seq.names {
            let used = cols
                .iter()
                .any(|(c, (_, n))| n == name && names.contains(c));
            if !used && !unmatched_names.contains(name) {
                unmatched_names.push(name.clone());
            }
        }
    }
    let tf = frame_index(truth, "ground truth")?;
    let pf = frame_index(pred, "the prediction")?;
    let frames: Vec<usize> = truth
        .frames
        .iter()
        .copied()
        .filter(|f| pf.contains_key(f))
        .collect();
    if frames.is_empty() {
        return Err(EvalError::Mismatch(format!(
            "no common frame index: ground truth has {}, prediction has {}",
            span(&truth.frames),
            span(&pred.frames)
        )));
    }
    let truth_only_frames = truth
        .frames
        .iter()
        .copied()
        .filter(|f| !pf.contains_key(f))
        .collect();
    let pred_only_frames = pred
        .frames
        .iter()
        .copied()
        .filter(|f| !tf.contains_key(f))
        .collect();
    let pick = |seq: &PoseSequence,
                cols: &BTreeMap<String, (usize, String)>,
                row: usize|
     -> Vec<Keypoint> {
        names
            .iter()
            .map(|n| {
                let col = cols[n].0;
                seq.poses[row]
                    .keypoints
                    .get(col)
                    .copied()
                    .unwrap_or_else(Keypoint::missing)
            })
            .collect()
    };
    let truth_rows = frames.iter().map(|f| pick(truth, &tc, tf[f])).collect();
    let pred_rows = frames.iter().map(|f| pick(pred, &pc, pf[f])).collect();
    Ok(Aligned {
        frames,
        names,
        truth: truth_rows,
        pred: pred_rows,
        truth_only_frames,
        pred_only_frames,
        unmatched_names,
    })
}

#[cfg(test)]
mod tests {
    use gait_core::Pose;

    use super::*;

    fn seq(names: &[&str], frames: &[usize]) -> PoseSequence {
        PoseSequence {
            fps: 30.0,
            names: names.iter().map(|s| s.to_string()).collect(),
            frames: frames.to_vec(),
            poses: frames
                .iter()
                .map(|&f| Pose {
                    keypoints: (0..names.len())
                        .map(|k| Keypoint::new(f as f64, k as f64, 1.0))
                        .collect(),
                })
                .collect(),
        }
    }

    #[test]
    fn aligns_by_frame_and_name() {
        let truth = seq(&["RKnee", "LKnee", "tail"], &[2, 3, 4]);
        let pred = seq(&["nose", "left_knee", "right_knee"], &[0, 1, 2, 3, 4, 5]);
        let a = align(&truth, &pred, &BTreeMap::new()).unwrap();
        assert_eq!(a.frames, vec![2, 3, 4]);
        assert_eq!(a.names, vec!["left_knee", "right_knee"]);
        assert_eq!(a.truth[0][0], Keypoint::new(2.0, 1.0, 1.0));
        assert_eq!(a.pred[0][0], Keypoint::new(2.0, 1.0, 1.0));
        assert_eq!(a.pred[1][1], Keypoint::new(3.0, 2.0, 1.0));
        assert_eq!(a.pred_only_frames, vec![0, 1, 5]);
        assert!(
            a.unmatched_names.contains(&"tail".to_string())
                && a.unmatched_names.contains(&"nose".to_string())
        );
    }

    #[test]
    fn says_what_does_not_match() {
        let truth = seq(&["paw", "tail"], &[0]);
        let pred = seq(&["left_knee"], &[0]);
        let e = align(&truth, &pred, &BTreeMap::new())
            .unwrap_err()
            .to_string();
        assert!(e.contains("paw, tail") && e.contains("name_map"), "{e}");
        let map = BTreeMap::from([("paw".to_string(), "left_knee".to_string())]);
        assert!(align(&truth, &pred, &map).is_ok());
        let late = seq(&["left_knee"], &[10, 11]);
        let e = align(&pred, &late, &BTreeMap::new())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("frames 0..=0") && e.contains("frames 10..=11"),
            "{e}"
        );
        let twice = seq(&["RKnee", "knee_r"], &[0]);
        assert!(
            align(&twice, &pred, &BTreeMap::new())
                .unwrap_err()
                .to_string()
                .contains("both map")
        );
    }
}
