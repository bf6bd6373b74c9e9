//! The warnings of the stride checks: one per reason that rejected strides, and for a walker
//! too small or too blurred in the image (out of focus or smeared by motion), the measures
//! behind it.

use super::{CycleQuality, REASONS, Reason};
use crate::config::KinematicsConfig;
use crate::tracks::{Tracks, median};

/// One warning per reason that rejected a stride (blurred strides have their own, with the
/// measures: [`blurred`], [`motion_blurred`]).
pub(crate) fn per_reason(q: &[CycleQuality], kin: &KinematicsConfig) -> Vec<String> {
    REASONS
        .iter()
        .filter(|&&r| r != Reason::Blurred && r != Reason::MotionBlurred)
        .filter_map(|&r| {
            let k = q.iter().filter(|c| c.reasons.contains(&r)).count();
            (k > 0).then(|| {
                format!(
                    "{k} of {} strides rejected ({}): {} (see cycle_quality.csv)",
                    q.len(),
                    r.name(),
                    r.describe(kin)
                )
            })
        })
        .collect()
}

/// The strides rejected for `reason`, with the first and last frame they span; `None` without.
fn rejected_for(q: &[CycleQuality], reason: Reason) -> Option<(Vec<&CycleQuality>, usize, usize)> {
    let rejected: Vec<&CycleQuality> = q.iter().filter(|c| c.reasons.contains(&reason)).collect();
    let first = rejected.iter().map(|c| c.first_frame).min()?;
    let last = rejected.iter().map(|c| c.last_frame).max()?;
    Some((rejected, first, last))
}

/// A walker too blurred for the pose model: the measured blur, the leg and the strides' frames.
pub(crate) fn blurred(q: &[CycleQuality], kin: &KinematicsConfig, warnings: &mut Vec<String>) {
    let Some((blurred, a, b)) = rejected_for(q, Reason::Blurred) else {
        return;
    };
    let mut blur: Vec<f64> = blurred.iter().map(|c| c.blur_px).collect();
    let mut leg: Vec<f64> = blurred.iter().map(|c| c.leg_px).collect();
    let (blur, leg) = (median(&mut blur), median(&mut leg));
    warnings.push(format!(
        "the subject's legs are blurred in the image: edges spread over {blur:.1} px (median over the strides of frames {}-{}), {:.1} % of the legs' {leg:.0} px, over kinematics.cycle_max_blur_share = {:.1} %: too blurred for reliable keypoints, so {} strides are rejected (blurred; cycle_quality.csv, blur_px); film in focus, in more light or with a shorter exposure",
        a,
        b,
        100.0 * blur / leg,
        100.0 * kin.cycle_max_blur_share,
        blurred.len()
    ));
}

/// Feet smeared by a long exposure: how much of their outline's contrast they keep swinging,
/// and the strides' frames.
pub(crate) fn motion_blurred(
    q: &[CycleQuality],
    kin: &KinematicsConfig,
    warnings: &mut Vec<String>,
) {
    let Some((smeared, a, b)) = rejected_for(q, Reason::MotionBlurred) else {
        return;
    };
    let mut kept: Vec<f64> = smeared.iter().map(|c| c.swing_contrast).collect();
    warnings.push(format!(
        "the subject's feet are smeared by motion blur: swinging, their outline keeps {:.0} % of its contrast standing (median over the strides of frames {a}-{b}), under kinematics.cycle_min_swing_contrast = {:.0} %: the exposure is too long for reliable keypoints of a moving foot, so {} strides are rejected (motion_blurred; cycle_quality.csv, swing_contrast); film in more light or with a faster shutter (1/250 s or shorter)",
        100.0 * median(&mut kept),
        100.0 * kin.cycle_min_swing_contrast,
        smeared.len()
    ));
}

/// A walker too small in the image for the pose model: the measured leg and the frames.
pub(crate) fn small_subject(t: &Tracks, kin: &KinematicsConfig, warnings: &mut Vec<String>) {
    let leg = t.leg_length();
    if !(leg.is_finite() && leg < kin.cycle_min_leg_px) {
        return;
    }
    let seen: Vec<usize> = (0..t.len()).filter(|&i| t.pelvis(i).is_some()).collect();
    let (Some(a), Some(b)) = (seen.first(), seen.last()) else {
        return;
    };
    warnings.push(format!(
        "the subject's legs are {leg:.0} px long in the image (thigh + shank, median over frames {}-{}), under kinematics.cycle_min_leg_px = {}: too small for reliable keypoints, so strides are rejected (small_subject); film closer or at a higher resolution",
        t.first_frame + a,
        t.first_frame + b,
        kin.cycle_min_leg_px
    ));
}
