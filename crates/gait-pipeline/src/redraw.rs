//! The regenerator's part of a pass: the frames (or the crops around the
//! subject, `[regenerator] region = "subject"`) through the edge detector and
//! the regenerator, crops pasted back; a stateful regenerator (`init =
//! "previous"`) gets the frames one by one with the state of the frame before,
//! restored from the cache where that frame was redrawn by an earlier run.

use gait_core::{CropSpec, Frame, Pose, SubjectCrop};

use crate::PipelineError;
use crate::driver::{Driver, bad_output};

impl Driver<'_> {
    /// Regenerated `todo` frames, same indices and sizes.
    pub(crate) fn redraw(&mut self, todo: &[Frame]) -> Result<Vec<Frame>, PipelineError> {
        let crops = match self.config.regenerator.subject_crop() {
            Some(spec) => Some(self.crops(todo, &spec)?),
            None => None,
        };
        let inputs: Vec<Frame> = match &crops {
            Some(c) => todo
                .iter()
                .zip(c)
                .map(|(f, c)| Frame::new(f.index, c.cut(&f.image)))
                .collect(),
            None => todo.to_vec(),
        };
        let redrawn = if self.stages.regenerator.is_stateful() {
            let mut out = Vec::with_capacity(inputs.len());
            for f in &inputs {
                out.extend(self.redraw_in_order(f, todo)?);
            }
            out
        } else {
            self.redraw_batch(&inputs)?
        };
        check(&redrawn, &inputs)?;
        Ok(match &crops {
            Some(c) => redrawn
                .iter()
                .zip(c)
                .zip(todo)
                .map(|((r, c), f)| Frame::new(f.index, c.paste(&f.image, &r.image)))
                .collect(),
            None => redrawn,
        })
    }

    /// The crop around the subject in each frame.
    fn crops(&self, frames: &[Frame], spec: &CropSpec) -> Result<Vec<SubjectCrop>, PipelineError> {
        frames
            .iter()
            .map(|f| {
                let person = self.subject.and_then(|s| s.get(&f.index)).ok_or_else(|| {
                    PipelineError::Config {
                        origin: "[regenerator]".into(),
                        message: format!(
                            "region = \"subject\" needs the subject's box in frame {}, and the \
                             subject pass found no walking subject there; use region = \"frame\"",
                            f.index
                        ),
                    }
                })?;
                Ok(SubjectCrop::around(person, spec))
            })
            .collect()
    }

    /// Edge maps, then the regenerator on `frames` (with the original
    /// frames' poses when it needs them).
    fn redraw_batch(&mut self, frames: &[Frame]) -> Result<Vec<Frame>, PipelineError> {
        let edges = self.edges(frames)?;
        let poses: Option<Vec<Pose>> = self.original_poses.as_ref().map(|found| {
            frames
                .iter()
                .map(|f| {
                    found
                        .get(&f.index)
                        .cloned()
                        .unwrap_or_else(|| Pose::empty(self.n_keypoints))
                })
                .collect()
        });
        let regen = &mut self.stages.regenerator;
        Ok(match poses {
            Some(p) => regen.regenerate_with_poses(frames, edges.as_deref(), &p)?,
            None => regen.regenerate(frames, edges.as_deref())?,
        })
    }

    /// One frame through a stateful regenerator: it carries on from the
    /// frame before in the pass's order, restored from that frame's saved
    /// state when it was not the last one redrawn here, else starts afresh.
    /// `todo`: the original frames being redrawn (a lost state is rebuilt from them).
    fn redraw_in_order(
        &mut self,
        frame: &Frame,
        todo: &[Frame],
    ) -> Result<Vec<Frame>, PipelineError> {
        let previous = self.order.previous(frame.index);
        if previous.is_none() || previous != self.last_regenerated {
            self.resume_regenerator(previous, todo)?;
        }
        let out = self.redraw_batch(std::slice::from_ref(frame))?;
        // State first: a redrawn frame on disk always has its state beside it.
        if let Some(s) = self.stages.regenerator.state() {
            self.caches.regenerator.store_state(frame.index, &s)?;
        }
        self.last_regenerated = Some(frame.index);
        Ok(out)
    }
}

/// One regenerated frame per input, with its index and size.
fn check(redrawn: &[Frame], inputs: &[Frame]) -> Result<(), PipelineError> {
    if redrawn.len() != inputs.len()
        || redrawn
            .iter()
            .zip(inputs)
            .any(|(r, f)| r.index != f.index || r.image.dimensions() != f.image.dimensions())
    {
        return Err(bad_output(
            "regenerator",
            "one frame per input frame, with its index and size",
        ));
    }
    Ok(())
}
