use gait_core::{EdgeMap, Frame, ImageRegenerator, StageError};

/// Hands the original frames on unchanged: the paper's baseline, where the
/// pose model sees the real video.
#[derive(Debug, Default, Clone, Copy)]
pub struct Passthrough;

impl ImageRegenerator for Passthrough {
    fn regenerate(
        &mut self,
        frames: &[Frame],
        _edges: Option<&[EdgeMap]>,
    ) -> Result<Vec<Frame>, StageError> {
        Ok(frames.to_vec())
    }
}
