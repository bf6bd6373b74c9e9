//! The one place that calls gait-kin: joint angles (and cycles) of a pose
//! sequence after the configured post-processing. This crate computes no
//! angle itself.

use gait_core::PoseSequence;
use gait_kin::{KinResult, KinematicsConfig, PostprocessConfig};

use crate::align::canonicalize;
use crate::angles::AngleTable;
use crate::names::Side;
use crate::plot::CycleCurve;
use crate::{EvalError, EvalOptions, Evaluation, evaluate_with_angles};

impl From<gait_kin::Side> for Side {
    fn from(s: gait_kin::Side) -> Self {
        match s {
            gait_kin::Side::Left => Side::Left,
            gait_kin::Side::Right => Side::Right,
        }
    }
}

impl From<Side> for gait_kin::Side {
    fn from(s: Side) -> Self {
        match s {
            Side::Left => gait_kin::Side::Left,
            Side::Right => gait_kin::Side::Right,
        }
    }
}

/// Angles of gait-kin's result as a table on its dense frame timeline.
pub fn angle_table(r: &KinResult) -> AngleTable {
    let (l, rt) = (&r.angles.left, &r.angles.right);
    let at = |v: &Vec<f64>, i: usize| v.get(i).copied().unwrap_or(f64::NAN);
    AngleTable {
        frames: (0..r.n_frames).map(|i| r.first_frame + i).collect(),
        values: (0..r.n_frames)
            .map(|i| {
                [
                    at(&l.hip, i),
                    at(&rt.hip, i),
                    at(&l.knee, i),
                    at(&rt.knee, i),
                    at(&l.ankle, i),
                    at(&rt.ankle, i),
                ]
            })
            .collect(),
    }
}

/// gait-kin's cycle curves in the plotting type (101 points, 0..100 %).
pub fn cycle_curves(r: &KinResult) -> Vec<CycleCurve> {
    r.cycles
        .iter()
        .map(|c| CycleCurve {
            side: c.side.into(),
            joint: c.joint.to_string(),
            percent: (0..c.mean.len())
                .map(|i| 100.0 * i as f64 / (c.mean.len().max(2) - 1) as f64)
                .collect(),
            mean: c.mean.clone(),
            sd: c.sd.clone(),
            n_cycles: c.n_cycles,
        })
        .collect()
}

/// Runs gait-kin on `seq` (post-processing, angles, events, cycles).
pub fn analyse(
    seq: &PoseSequence,
    post: &PostprocessConfig,
    kin: &KinematicsConfig,
) -> Result<KinResult, EvalError> {
    gait_kin::analyse(seq, post, kin).map_err(|e| EvalError::Kinematics(e.to_string()))
}

/// [`evaluate_with_angles`] with the angles of both sequences computed by
/// gait-kin under the same configuration; gait-kin's warnings about the
/// prediction are passed on.
pub fn evaluate(
    truth: &PoseSequence,
    pred: &PoseSequence,
    post: &PostprocessConfig,
    kin: &KinematicsConfig,
    opts: &EvalOptions,
) -> Result<Evaluation, EvalError> {
    let t = analyse(&canonicalize(truth, &opts.name_map)?, post, kin)?;
    let p = analyse(&canonicalize(pred, &opts.name_map)?, post, kin)?;
    let (ta, pa) = (angle_table(&t), angle_table(&p));
    let mut e = evaluate_with_angles(truth, pred, Some((&ta, &pa)), opts)?;
    e.warnings.extend(
        t.warnings
            .iter()
            .map(|w| format!("ground-truth kinematics: {w}")),
    );
    e.warnings.extend(
        p.warnings
            .iter()
            .map(|w| format!("predicted kinematics: {w}")),
    );
    Ok(e)
}
