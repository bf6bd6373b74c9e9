//! Drives frames through the stages, taking each stage's results from the
//! cache when it can, and keeps a tracking pose estimator's state consistent
//! with the order in which it sees frames.

use std::collections::{BTreeMap, BTreeSet};
use std::time::Instant;

use crate::progress::Progress;
use gait_core::{EdgeMap, Frame, PersonBox, Pose};

use crate::cache::StageCache;
use crate::input::InputInfo;
use crate::manifest::StageRecord;
use crate::registry::Stages;
use crate::{PipelineConfig, PipelineError};

/// The frames one pass hands the pose estimator, and which of them follow
/// each other closely enough for a tracker to carry over. The estimator
/// tracks from a frame's predecessor; where there is none it starts afresh.
#[derive(Debug, Clone)]
pub(crate) enum Order {
    /// `first`, `first + stride`, ... and the last frame of the range.
    Grid { first: usize, stride: usize },
    /// A sorted subset of the grid (the poor frames): consecutive members
    /// at most `stride` apart are neighbours in the grid and track.
    Subset { frames: Vec<usize>, stride: usize },
}

impl Order {
    /// The frame the estimator saw just before `frame` and tracks from.
    pub(crate) fn previous(&self, frame: usize) -> Option<usize> {
        match self {
            Order::Grid { first, stride } => {
                if frame <= *first {
                    None
                } else {
                    // Grid frames step back by `stride`; the extra last
                    // frame steps back to the grid frame below it.
                    Some(first + (frame - 1 - first) / stride * stride)
                }
            }
            Order::Subset { frames, stride } => {
                let at = frames.binary_search(&frame).ok()?;
                let prev = *frames.get(at.checked_sub(1)?)?;
                (frame - prev <= *stride).then_some(prev)
            }
        }
    }
}

/// Stage caches of one pass.
pub(crate) struct Caches<'a> {
    pub(crate) edge: &'a StageCache,
    pub(crate) regenerator: &'a StageCache,
    pub(crate) pose: &'a StageCache,
}

/// Processes batches, taking each stage's results from the cache when it can.
pub(crate) struct Driver<'a> {
    pub(crate) config: &'a PipelineConfig,
    pub(crate) stages: &'a mut Stages,
    pub(crate) caches: Caches<'a>,
    pub(crate) records: &'a mut BTreeMap<String, StageRecord>,
    pub(crate) n_keypoints: usize,
    /// False for the pass over the original frames (straight to pose).
    pub(crate) regenerate: bool,
    /// False: regenerate (and cache) only, estimate no pose.
    pub(crate) estimate: bool,
    /// The stage record the pose results count under.
    pub(crate) pose_record: &'static str,
    pub(crate) order: Order,
    /// Index of the last frame the pose stage saw, to reset trackers on gaps.
    pub(crate) last_estimated: Option<usize>,
    /// Frames whose pose came from the cache.
    pub(crate) cached_frames: BTreeSet<usize>,
    /// Poses on the original frames, for regenerators that need them
    /// (inpainting a leg mask); `None` when the regenerator does not.
    pub(crate) original_poses: Option<BTreeMap<usize, Pose>>,
    /// Where the subject is in each frame; frames without it get an empty
    /// pose and skip every stage. `None`: no subject tracking.
    pub(crate) subject: Option<&'a BTreeMap<usize, PersonBox>>,
    /// (the subject's last frame, the range's last frame): frames after the
    /// first get empty poses without being decoded.
    pub(crate) stop_after: Option<(usize, usize)>,
    /// The frame a stateful regenerator redrew last (its state follows it).
    pub(crate) last_regenerated: Option<usize>,
    /// The current batch and the one before: a stateful stage's state lost to
    /// a corrupt cache entry is rebuilt from these frames.
    pub(crate) recent: Vec<Frame>,
    /// The blur of the subject's legs, measured on the frames estimated.
    pub(crate) sharpness: &'a mut crate::sharpness::Sharpness,
}

impl Driver<'_> {
    pub(crate) fn record(&mut self, stage: &str) -> &mut StageRecord {
        self.records.entry(stage.to_string()).or_default()
    }

    /// Poses of `frames` (consecutive members of the pass's order).
    pub(crate) fn process(&mut self, frames: &[Frame]) -> Result<Vec<Pose>, PipelineError> {
        if !self.estimate {
            return self.regenerate_only(frames);
        }
        let record = self.pose_record;
        let mut poses: Vec<Option<Pose>> = frames
            .iter()
            .map(|f| self.caches.pose.load_pose(f.index, self.n_keypoints))
            .collect();
        let cached: Vec<usize> = frames
            .iter()
            .zip(&poses)
            .filter(|(_, p)| p.is_some())
            .map(|(f, _)| f.index)
            .collect();
        self.record(record).cached += cached.len();
        self.cached_frames.extend(cached);
        let subject = self.subject;
        let in_view = |f: &Frame| subject.is_none_or(|s| s.contains_key(&f.index));
        for (slot, frame) in poses.iter_mut().zip(frames) {
            if slot.is_none() && !in_view(frame) {
                *slot = Some(Pose::empty(self.n_keypoints));
            }
        }
        let todo: Vec<&Frame> = frames
            .iter()
            .zip(&poses)
            .filter(|(_, p)| p.is_none())
            .map(|(f, _)| f)
            .collect();
        if !todo.is_empty() {
            // The pose model reads the frames as they are: no copy when it sees the whole batch.
            // The passthrough regenerator (the default, without an edge stage) hands them on
            // unchanged, so they do not go through it: three copies of every frame (6 MB at
            // 1080p) saved. With an edge stage configured the edges are still made (and cached).
            let identity = self.config.regenerator.is_identity() && self.stages.edge.is_none();
            if self.regenerate && identity {
                self.record("regenerator").computed += todo.len();
            }
            let seen: std::borrow::Cow<[Frame]> = if self.regenerate && !identity {
                self.regenerated(&todo)?.into()
            } else if todo.len() == frames.len() {
                frames.into()
            } else {
                todo.into_iter().cloned().collect::<Vec<_>>().into()
            };
            // The pose stage may track across frames: hand it runs that
            // follow each other in the pass's order, and restore or reset it
            // where the run does not continue the last frame it saw.
            let mut start = 0;
            while start < seen.len() {
                let mut end = start + 1;
                while end < seen.len()
                    && self.order.previous(seen[end].index) == Some(seen[end - 1].index)
                {
                    end += 1;
                }
                let run = &seen[start..end];
                let previous = self.order.previous(run[0].index);
                if previous.is_none() || self.last_estimated != previous {
                    // Resuming: the tracker as it was after the previous
                    // frame, so results equal an uninterrupted run.
                    self.resume_tracker(previous, frames)?;
                }
                // A stateful estimator goes frame by frame so that its state
                // after every frame can be saved with that frame's pose.
                let step = if self.stages.pose.state().is_some() {
                    1
                } else {
                    run.len()
                };
                for chunk in run.chunks(step) {
                    let t = Instant::now();
                    let found = match subject {
                        Some(s) => {
                            let at: Vec<Option<PersonBox>> =
                                chunk.iter().map(|f| s.get(&f.index).copied()).collect();
                            self.stages.pose.estimate_subject(chunk, &at)?
                        }
                        None => self.stages.pose.estimate(chunk)?,
                    };
                    self.record(record).seconds += t.elapsed().as_secs_f64();
                    self.record(record).computed += chunk.len();
                    if found.len() != chunk.len()
                        || found.iter().any(|p| p.keypoints.len() != self.n_keypoints)
                    {
                        return Err(bad_output(
                            "pose",
                            "a pose per frame with one entry per keypoint name",
                        ));
                    }
                    let state = self.stages.pose.state();
                    for (frame, pose) in chunk.iter().zip(found) {
                        // State first: a pose on disk always has its state beside it.
                        if let Some(s) = &state {
                            self.caches.pose.store_state(frame.index, s)?;
                        }
                        self.caches.pose.store_pose(frame.index, &pose)?;
                        let slot = frames
                            .iter()
                            .position(|f| f.index == frame.index)
                            .unwrap_or(0);
                        poses[slot] = Some(pose);
                    }
                }
                self.last_estimated = Some(run[run.len() - 1].index);
                start = end;
            }
        }
        Ok(poses
            .into_iter()
            .map(|p| p.unwrap_or_else(|| Pose::empty(self.n_keypoints)))
            .collect())
    }

    /// Regenerates (or finds cached) the frames with the subject in view and
    /// estimates nothing: empty poses.
    fn regenerate_only(&mut self, frames: &[Frame]) -> Result<Vec<Pose>, PipelineError> {
        let subject = self.subject;
        let todo: Vec<&Frame> = frames
            .iter()
            .filter(|f| subject.is_none_or(|s| s.contains_key(&f.index)))
            .collect();
        if !todo.is_empty() && self.regenerate {
            self.regenerated(&todo)?;
        }
        Ok(vec![Pose::empty(self.n_keypoints); frames.len()])
    }

    /// The frames the pose model should see: regenerated (or cached) ones.
    pub(crate) fn regenerated(&mut self, frames: &[&Frame]) -> Result<Vec<Frame>, PipelineError> {
        let identity = self.config.regenerator.is_identity();
        let mut out: Vec<Option<Frame>> = frames
            .iter()
            .map(|f| {
                self.caches
                    .regenerator
                    .load_rgb(f.index)
                    .filter(|img| img.dimensions() == f.image.dimensions() && !identity)
                    .map(|img| Frame::new(f.index, img))
            })
            .collect();
        let cached = out.iter().filter(|f| f.is_some()).count();
        self.record("regenerator").cached += cached;
        let todo: Vec<Frame> = frames
            .iter()
            .zip(&out)
            .filter(|(_, o)| o.is_none())
            .map(|(f, _)| (*f).clone())
            .collect();
        if todo.is_empty() {
            return Ok(out.into_iter().flatten().collect());
        }
        let t = Instant::now();
        let redrawn = self.redraw(&todo)?;
        self.record("regenerator").seconds += t.elapsed().as_secs_f64();
        self.record("regenerator").computed += todo.len();
        let mut redrawn = redrawn.into_iter();
        for slot in out.iter_mut().filter(|o| o.is_none()) {
            let frame = redrawn
                .next()
                .ok_or_else(|| bad_output("regenerator", "one frame per input frame"))?;
            if !identity {
                self.caches
                    .regenerator
                    .store_rgb(frame.index, &frame.image)?;
            }
            *slot = Some(frame);
        }
        Ok(out.into_iter().flatten().collect())
    }

    /// Edge maps for `frames`, or `None` when the pipeline has no edge stage.
    pub(crate) fn edges(
        &mut self,
        frames: &[Frame],
    ) -> Result<Option<Vec<EdgeMap>>, PipelineError> {
        if self.stages.edge.is_none() {
            return Ok(None);
        }
        let mut maps: Vec<Option<EdgeMap>> = frames
            .iter()
            .map(|f| {
                self.caches
                    .edge
                    .load_edge(f.index)
                    .map(|(image, resize)| EdgeMap {
                        index: f.index,
                        image,
                        resize,
                    })
            })
            .collect();
        let cached = maps.iter().filter(|m| m.is_some()).count();
        self.record("edge").cached += cached;
        let todo: Vec<Frame> = frames
            .iter()
            .zip(&maps)
            .filter(|(_, m)| m.is_none())
            .map(|(f, _)| f.clone())
            .collect();
        if !todo.is_empty() {
            let t = Instant::now();
            let detector = self
                .stages
                .edge
                .as_mut()
                .ok_or_else(|| bad_output("edge", "a detector"))?;
            let found = detector.detect(&todo)?;
            self.record("edge").seconds += t.elapsed().as_secs_f64();
            self.record("edge").computed += todo.len();
            if found.len() != todo.len() || found.iter().zip(&todo).any(|(m, f)| m.index != f.index)
            {
                return Err(bad_output("edge", "one edge map per frame, with its index"));
            }
            let mut found = found.into_iter();
            for slot in maps.iter_mut().filter(|m| m.is_none()) {
                let map = found
                    .next()
                    .ok_or_else(|| bad_output("edge", "one edge map per frame"))?;
                self.caches
                    .edge
                    .store_edge(map.index, &map.image, &map.resize)?;
                *slot = Some(map);
            }
        }
        Ok(Some(maps.into_iter().flatten().collect()))
    }
}

impl Driver<'_> {
    /// The first frame of the range `first..=last` with a subject to follow (`first` without
    /// subject tracking, or when the subject is not in view within the range).
    fn first_wanted(&self, first: usize, last: Option<usize>) -> usize {
        let seen = self
            .subject
            .and_then(|s| s.range(first..).next().map(|(f, _)| *f));
        seen.filter(|&f| last.is_none_or(|l| f <= l))
            .unwrap_or(first)
    }
}

/// A pass's result: every frame index of the range, the poses of the frames
/// it processed, and those of them that came from the cache.
pub(crate) type PassResult = (Vec<usize>, Vec<(usize, Pose)>, BTreeSet<usize>);

impl Driver<'_> {
    /// Decodes the configured range and hands the frames `pick(index,
    /// is_last)` chooses to the stages in batches.
    pub(crate) fn stream(
        mut self,
        info: &InputInfo,
        bar: &Progress,
        pick: &dyn Fn(usize, bool) -> bool,
    ) -> Result<PassResult, PipelineError> {
        let (first, last) = (self.config.input.first_frame, self.config.input.last_frame);
        let batch_size = self.config.run.batch_size;
        let mut all = Vec::new();
        let mut out = Vec::new();
        // Before the range, or before the subject comes into view (every pose empty there),
        // frames are not read: ffmpeg decodes them but neither converts nor sends them.
        let start = self.first_wanted(first, last);
        for f in first..start {
            bar.tick()?;
            all.push(f);
            if pick(f, false) {
                out.push((f, Pose::empty(self.n_keypoints)));
            }
        }
        let mut reader = info.frames_from(start)?;
        let mut batch = Vec::with_capacity(batch_size);
        // One frame of look-ahead tells whether a frame is the range's last.
        let mut ahead = reader.next_frame()?;
        while let Some(frame) = ahead.take() {
            if last.is_some_and(|l| frame.index > l) {
                break;
            }
            ahead = if last == Some(frame.index) {
                None
            } else {
                reader.next_frame()?
            };
            if frame.index < first {
                continue;
            }
            let is_last = ahead.is_none();
            // After the subject's last frame every pose is empty: no need to decode on.
            let stop = self.stop_after.filter(|s| s.0 == frame.index);
            bar.tick()?;
            all.push(frame.index);
            if pick(frame.index, is_last) {
                batch.push(frame);
            }
            if batch.len() == batch_size || ((is_last || stop.is_some()) && !batch.is_empty()) {
                let poses = self.process(&batch)?;
                if self.estimate {
                    self.sharpness.measure(&batch, &poses);
                }
                out.extend(batch.iter().map(|f| f.index).zip(poses));
                // The frames a stateful stage may have to see again (a corrupt saved state):
                // the batch before (the current one is handed to it as well), moved, not copied.
                self.recent.clear();
                self.recent.append(&mut batch);
            }
            if is_last {
                break;
            }
            if let Some((stop, end)) = stop {
                // The rest, as an uninterrupted pass would give it: empty poses (nobody to follow).
                let picked = (stop + 1..=end).filter(|&f| pick(f, f == end));
                out.extend(picked.map(|f| (f, Pose::empty(self.n_keypoints))));
                all.extend(stop + 1..=end);
                break;
            }
        }
        Ok((all, out, self.cached_frames))
    }
}

pub(crate) fn bad_output(stage: &str, expected: &str) -> PipelineError {
    PipelineError::Stage(gait_core::StageError::backend(
        stage,
        format!("the {stage} stage returned malformed results (expected {expected})"),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_frames_track_from_the_grid_frame_before() {
        let g = Order::Grid {
            first: 10,
            stride: 3,
        };
        assert_eq!(g.previous(10), None);
        assert_eq!(g.previous(13), Some(10));
        assert_eq!(g.previous(16), Some(13));
        // The range's last frame, off the grid, follows the grid frame below.
        assert_eq!(g.previous(18), Some(16));
        let every = Order::Grid {
            first: 0,
            stride: 1,
        };
        assert_eq!(every.previous(5), Some(4));
    }

    #[test]
    fn a_subset_tracks_only_across_grid_neighbours() {
        let s = Order::Subset {
            frames: vec![3, 6, 12, 13],
            stride: 3,
        };
        assert_eq!(s.previous(3), None);
        assert_eq!(s.previous(6), Some(3));
        // 9 was good: 12 starts afresh.
        assert_eq!(s.previous(12), None);
        assert_eq!(s.previous(13), Some(12));
        assert_eq!(s.previous(7), None);
    }
}
