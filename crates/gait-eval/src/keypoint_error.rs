//! Euclidean keypoint errors in pixels, per keypoint and pooled per leg.

use gait_core::Keypoint;
use serde::{Deserialize, Serialize};

use crate::align::Aligned;
use crate::names::{LEG_PARTS, Side, leg_name};
use crate::options::{EvalOptions, Role};
use crate::stats::Stat;

/// Error of one keypoint over the frames where the truth has it and the
/// prediction identified it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KeypointError {
    pub name: String,
    pub side: Option<Side>,
    pub role: Option<Role>,
    pub px: Stat,
}

/// Errors of one leg's lower-limb keypoints (hip, knee, ankle, heel, toe, as
/// far as both files have them), pooled over keypoints and frames.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LegError {
    pub side: Side,
    pub role: Role,
    pub stat: Stat,
}

pub(crate) fn identified(k: &Keypoint, min_likelihood: f64) -> bool {
    k.is_found() && k.likelihood >= min_likelihood
}

pub(crate) fn distance(a: &Keypoint, b: &Keypoint) -> f64 {
    (a.x - b.x).hypot(a.y - b.y)
}

/// Per-frame errors of column `k` (frames where either side is absent are skipped).
fn errors_of(a: &Aligned, k: usize, min_likelihood: f64) -> Vec<f64> {
    a.truth
        .iter()
        .zip(&a.pred)
        .filter(|(t, p)| t[k].is_found() && identified(&p[k], min_likelihood))
        .map(|(t, p)| distance(&t[k], &p[k]))
        .collect()
}

pub(crate) fn keypoint_errors(
    a: &Aligned,
    opts: &EvalOptions,
) -> (Vec<KeypointError>, Vec<LegError>) {
    let per_kp: Vec<KeypointError> = a
        .names
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let side = Side::of(name);
            KeypointError {
                name: name.clone(),
                side,
                role: side.map(|s| opts.role(s)),
                px: Stat::of(&errors_of(a, k, opts.min_likelihood)),
            }
        })
        .collect();
    let legs = Side::BOTH
        .iter()
        .map(|&side| {
            let mut pooled = Vec::new();
            for part in LEG_PARTS {
                if let Some(k) = a.names.iter().position(|n| *n == leg_name(side, part)) {
                    pooled.extend(errors_of(a, k, opts.min_likelihood));
                }
            }
            LegError {
                side,
                role: opts.role(side),
                stat: Stat::of(&pooled),
            }
        })
        .collect();
    (per_kp, legs)
}
