//! Stateful stages resumed mid-pass: a tracking pose estimator, and a
//! regenerator that starts each frame from the one before (`init =
//! "previous"`). A stage's state after the previous frame comes from the
//! cache; when that saved state fails its checksum, it is rebuilt by running
//! the stage on the previous frame again (from its own predecessor's state),
//! so the results equal those of an uninterrupted run.

use gait_core::Frame;

use crate::PipelineError;
use crate::cache::Saved;
use crate::driver::Driver;

impl Driver<'_> {
    /// Puts the pose tracker where it was after frame `previous` (`None`: start
    /// afresh). `current`: the batch being processed (not yet in `recent`).
    pub(crate) fn resume_tracker(
        &mut self,
        previous: Option<usize>,
        current: &[Frame],
    ) -> Result<(), PipelineError> {
        let Some(p) = previous else {
            self.stages.pose.reset();
            return Ok(());
        };
        match self.caches.pose.saved_state(p) {
            Saved::Ok(s) if self.stages.pose.restore(&s) => return Ok(()),
            Saved::Corrupt => {
                if let Some(frame) = self.recent_frame(p, current) {
                    return self.estimate_again(frame, current);
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
    fn estimate_again(&mut self, frame: Frame, current: &[Frame]) -> Result<(), PipelineError> {
        // Each step goes one frame back in the pass's order, so this ends.
        self.resume_tracker(self.order.previous(frame.index), current)?;
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

    /// Puts a stateful regenerator where it was after frame `previous` (`None`: start afresh).
    pub(crate) fn resume_regenerator(
        &mut self,
        previous: Option<usize>,
        current: &[Frame],
    ) -> Result<(), PipelineError> {
        let Some(p) = previous else {
            self.stages.regenerator.reset();
            return Ok(());
        };
        match self.caches.regenerator.saved_state(p) {
            Saved::Ok(s) if self.stages.regenerator.restore(&s) => return Ok(()),
            Saved::Corrupt => {
                if let Some(frame) = self.recent_frame(p, current) {
                    // Redrawn again in order (from its predecessor's state), which saves
                    // its state anew; the redrawn image itself is cached already.
                    self.redraw(&[frame])?;
                    return Ok(());
                }
            }
            _ => {}
        }
        self.stages.regenerator.reset();
        Ok(())
    }

    /// Frame `index`, when it is still in memory (this batch or the one before).
    fn recent_frame(&self, index: usize, current: &[Frame]) -> Option<Frame> {
        let mut all = current.iter().chain(&self.recent);
        all.find(|f| f.index == index).cloned()
    }
}
