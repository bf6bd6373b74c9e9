//! A tracking pose estimator resumed mid-pass. Its state after the previous
//! frame comes from the cache; when that saved state fails its checksum, it
//! is rebuilt by estimating the previous frame again (from its own
//! predecessor's state), so the poses equal those of an uninterrupted run.

use gait_core::Frame;

use crate::PipelineError;
use crate::cache::Saved;
use crate::driver::Driver;

impl Driver<'_> {
    /// Puts the pose tracker where it was after frame `previous` (`None`: start
    /// afresh). `near` are the frames of the current batch.
    pub(crate) fn resume_tracker(
        &mut self,
        previous: Option<usize>,
        near: &[Frame],
    ) -> Result<(), PipelineError> {
        let Some(p) = previous else {
            self.stages.pose.reset();
            return Ok(());
        };
        match self.caches.pose.saved_state(p) {
            Saved::Ok(s) if self.stages.pose.restore(&s) => return Ok(()),
            Saved::Corrupt => {
                let frame = near.iter().chain(&self.recent).find(|f| f.index == p);
                if let Some(frame) = frame.cloned() {
                    return self.estimate_again(frame, near);
                }
            }
            // Never saved: the frame had no estimate (out of view), so the
            // uninterrupted run started afresh after it too.
            _ => {}
        }
        self.stages.pose.reset();
        Ok(())
    }

    /// Estimates `frame` again from its predecessor's state, to rebuild (and
    /// save again) the tracking state after it; the pose itself is cached.
    fn estimate_again(&mut self, frame: Frame, near: &[Frame]) -> Result<(), PipelineError> {
        // Each step goes one frame back in the pass's order, so this ends.
        self.resume_tracker(self.order.previous(frame.index), near)?;
        let index = frame.index;
        let seen = if self.regenerate {
            self.regenerated(&[&frame])?
        } else {
            vec![frame]
        };
        match self.subject {
            Some(s) => {
                let at = [s.get(&index).copied()];
                self.stages.pose.estimate_subject(&seen, &at)?
            }
            None => self.stages.pose.estimate(&seen)?,
        };
        if let Some(state) = self.stages.pose.state() {
            self.caches.pose.store_state(index, &state)?;
        }
        Ok(())
    }
}
