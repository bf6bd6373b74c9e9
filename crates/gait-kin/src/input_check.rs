//! What every analysis checks of its input before anything else.

use gait_core::PoseSequence;

use crate::{KinError, KinematicsConfig, PostprocessConfig};

/// The largest frame number an input may have: a corrupt frame column is refused before the
/// dense timeline is laid out from it.
pub const MAX_FRAME: usize = 1_000_000_000;

pub(crate) fn check_input(
    seq: &PoseSequence,
    post: &PostprocessConfig,
    kin: &KinematicsConfig,
) -> Result<(), KinError> {
    let fps = seq.fps;
    if !(fps.is_finite() && fps > 0.0) {
        return Err(KinError::BadInput(format!(
            "frame rate {fps} is not a positive number"
        )));
    }
    post.validate(fps)?;
    kin.validate()?;
    if seq.frames.len() != seq.poses.len() {
        return Err(KinError::BadInput(
            "frames and poses differ in length".into(),
        ));
    }
    if let Some(&hi) = seq.frames.iter().max()
        && hi > MAX_FRAME
    {
        return Err(KinError::BadInput(format!(
            "frame number {hi} is beyond {MAX_FRAME} (over 9 days at 1,000 fps); check the file's frame column"
        )));
    }
    if let (Some(lo), Some(hi)) = (seq.frames.iter().min(), seq.frames.iter().max())
        && hi - lo > 10 * seq.frames.len() + 10_000
    {
        return Err(KinError::BadInput(format!(
            "frame numbers {lo}..{hi} are too sparse for {} poses",
            seq.len()
        )));
    }
    Ok(())
}
