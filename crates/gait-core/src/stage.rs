//! The three pluggable stage traits. All are batch-capable: the runner hands
//! each stage a slice of consecutive frames (of the configured batch size) in
//! input order, so stateful stages (e.g. pose trackers) see frames in order.

use crate::{EdgeMap, Frame, PersonBox, Pose, StageError};

/// Turns frames into edge maps (the ControlNet condition).
pub trait EdgeDetector: Send {
    /// Returns one edge map per frame, in order.
    fn detect(&mut self, frames: &[Frame]) -> Result<Vec<EdgeMap>, StageError>;
}

/// Redraws frames, optionally conditioned on their edge maps.
///
/// `edges` is `None` when the pipeline has no edge stage (`kind = "none"`);
/// otherwise it has one map per frame. Output frames keep the input frames'
/// indices and sizes, so keypoints found on them are in original pixels.
pub trait ImageRegenerator: Send {
    fn regenerate(
        &mut self,
        frames: &[Frame],
        edges: Option<&[EdgeMap]>,
    ) -> Result<Vec<Frame>, StageError>;

    /// As [`Self::regenerate`], with the pose found on each ORIGINAL frame
    /// (one per frame, in frame pixels), for regenerators that need it, e.g.
    /// to inpaint a leg mask. The default ignores the poses.
    fn regenerate_with_poses(
        &mut self,
        frames: &[Frame],
        edges: Option<&[EdgeMap]>,
        _poses: &[Pose],
    ) -> Result<Vec<Frame>, StageError> {
        self.regenerate(frames, edges)
    }

    /// Notes for the run's warnings gathered since the last call (e.g. frames
    /// handed on unchanged because no leg was found to inpaint).
    fn take_warnings(&mut self) -> Vec<String> {
        Vec::new()
    }

    /// True when a frame's result depends on the frame before it (e.g. a
    /// start from the previous frame's latent): the runner then hands the
    /// frames one by one, in order, and keeps [`Self::state`] with each.
    fn is_stateful(&self) -> bool {
        false
    }

    /// Forgets the previous frame: the next frame starts afresh.
    fn reset(&mut self) {}

    /// What the next frame carries over from the last one, saved with it so
    /// that a resumed run goes on as if it had not stopped.
    fn state(&self) -> Option<Vec<u8>> {
        None
    }

    /// Restores a state returned by [`Self::state`]; `false` when the bytes
    /// are not understood (the runner then calls [`Self::reset`]).
    fn restore(&mut self, state: &[u8]) -> bool {
        let _ = state;
        false
    }
}

/// Finds one person's keypoints per frame.
pub trait PoseEstimator: Send {
    /// Keypoint names of every returned pose: the canonical names first
    /// (see [`crate::CANONICAL`]), then the model's extra native keypoints.
    fn keypoint_names(&self) -> Vec<String>;

    /// Returns one pose per frame, in the frame's own pixel coordinates.
    /// A frame without a person yields [`Pose::empty`], not an error.
    fn estimate(&mut self, frames: &[Frame]) -> Result<Vec<Pose>, StageError>;

    /// Every person in `frame`, for the subject pass that links people into
    /// tracks; `None` when the estimator cannot list people (the run then
    /// follows the estimator's own choice of person).
    fn people(&mut self, frame: &Frame) -> Result<Option<Vec<PersonBox>>, StageError> {
        let _ = frame;
        Ok(None)
    }

    /// As [`Self::estimate`], for the subject only: `subject[i]` is where the
    /// subject is in `frames[i]` (one of [`Self::people`]'s boxes), `None`
    /// where the subject is not in view, which yields [`Pose::empty`].
    /// The default estimates as usual and blanks the frames without subject.
    fn estimate_subject(
        &mut self,
        frames: &[Frame],
        subject: &[Option<PersonBox>],
    ) -> Result<Vec<Pose>, StageError> {
        let mut poses = self.estimate(frames)?;
        for (pose, at) in poses.iter_mut().zip(subject) {
            if at.is_none() {
                *pose = Pose::empty(pose.keypoints.len());
            }
        }
        Ok(poses)
    }

    /// Forgets any tracking state, e.g. before a run that resumes mid-video.
    fn reset(&mut self) {}

    /// The tracking state after the last frame, for stateful estimators.
    /// The runner saves it with each cached pose so that an interrupted run
    /// resumes exactly as if it had not stopped. `None` means stateless.
    fn state(&self) -> Option<Vec<u8>> {
        None
    }

    /// Restores a state returned by [`Self::state`]; `false` when the bytes
    /// are not understood (the runner then calls [`Self::reset`]).
    fn restore(&mut self, state: &[u8]) -> bool {
        let _ = state;
        false
    }
}
