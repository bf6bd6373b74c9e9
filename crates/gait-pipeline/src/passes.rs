//! The pose passes over the input: poses on the original frames where the
//! run needs them (poor-frame selection, inpainting masks), then the pass
//! through edges -> regenerator -> pose. Each pass starts the estimator
//! afresh and hands it that pass's frames in order.

use std::collections::{BTreeMap, BTreeSet};

use crate::progress::Progress;
use gait_core::{PersonBox, Pose};

use crate::driver::{Caches, Driver, Order, PassResult};
use crate::input::InputInfo;
use crate::manifest::StageRecord;
use crate::plan::{ORIGINAL_POSE, StageCaches};
use crate::registry::Stages;
use crate::selection::{self, SelectionMode, SelectionRecord};
use crate::sharpness::Sharpness;
use crate::{PipelineConfig, PipelineError};
use gait_kin::FeetContrast;

/// What the passes found.
pub(crate) struct PassOutput {
    /// Every frame index of the range.
    pub(crate) all: Vec<usize>,
    /// The poses of the processed frames, in frame order.
    pub(crate) processed: Vec<(usize, Pose)>,
    /// How many of them came from the cache.
    pub(crate) from_cache: usize,
    /// Poses on the original frames, when a pass found them.
    pub(crate) original: Option<Vec<(usize, Pose)>>,
    /// Why frames were judged poor (poor mode).
    pub(crate) selection: SelectionRecord,
    /// The blur of the subject's legs (px) in the frames measured.
    pub(crate) blur_px: BTreeMap<usize, f64>,
    /// Each foot's outline contrast per frame.
    pub(crate) feet_contrast: FeetContrast,
}

/// Which frames a pass hands on: `regenerate` = through edges and regenerator
/// into the pose cache, else the original frames into the original-pose
/// cache; `estimate` = false stops after the regenerator (a part of a split
/// run only fills the image cache).
#[derive(Clone, Copy)]
struct Through {
    regenerate: bool,
    estimate: bool,
}

const ORIGINAL: Through = Through {
    regenerate: false,
    estimate: true,
};
const REGENERATED: Through = Through {
    regenerate: true,
    estimate: true,
};
const REGENERATED_ONLY: Through = Through {
    regenerate: true,
    estimate: false,
};

/// What every pass shares: the stages, caches and per-stage records.
pub(crate) struct Passes<'a> {
    pub(crate) config: &'a PipelineConfig,
    pub(crate) info: &'a InputInfo,
    pub(crate) stages: &'a mut Stages,
    pub(crate) caches: &'a StageCaches,
    pub(crate) records: &'a mut BTreeMap<String, StageRecord>,
    pub(crate) n_keypoints: usize,
    pub(crate) names: &'a [String],
    /// Where the subject is in each frame; `None` without subject tracking.
    pub(crate) subject: Option<&'a BTreeMap<usize, PersonBox>>,
    /// The last frame of the range, when the subject pass saw it.
    pub(crate) range_end: Option<usize>,
    /// Makes a progress bar for a pass named by its argument.
    pub(crate) bar: &'a dyn Fn(&str) -> Progress,
    /// Measures the blur of the subject's legs as the frames go by.
    pub(crate) sharpness: Sharpness,
}

impl Passes<'_> {
    /// Runs the passes the configuration asks for.
    pub(crate) fn run(&mut self) -> Result<PassOutput, PipelineError> {
        let mut out = if self.config.selection.mode == SelectionMode::Poor {
            self.poor_frames()?
        } else if self.config.regenerator.needs_poses() {
            self.inpainting()?
        } else {
            let (all, processed, cached) = self.pass(REGENERATED, self.grid(), None, &|_| true)?;
            PassOutput {
                all,
                from_cache: cached.len(),
                processed,
                original: None,
                selection: SelectionRecord::default(),
                blur_px: BTreeMap::new(),
                feet_contrast: BTreeMap::new(),
            }
        };
        out.blur_px = std::mem::take(&mut self.sharpness.blur_px);
        out.feet_contrast = std::mem::take(&mut self.sharpness.feet_contrast);
        Ok(out)
    }

    fn grid(&self) -> Order {
        Order::Grid {
            first: self.config.input.first_frame,
            stride: self.config.selection.stride,
        }
    }

    /// One pass (see [`Through`]). Frames on the grid (and the last) are
    /// processed if `wanted`.
    fn pass(
        &mut self,
        Through {
            regenerate,
            estimate,
        }: Through,
        order: Order,
        original_poses: Option<BTreeMap<usize, Pose>>,
        wanted: &dyn Fn(usize) -> bool,
    ) -> Result<PassResult, PipelineError> {
        let label = match (regenerate, self.config.selection.mode) {
            (false, _) => "original frames",
            (true, SelectionMode::Poor) => "regenerating poor frames",
            (true, _) => "poses",
        };
        let bar = (self.bar)(label);
        let (first, stride) = (self.config.input.first_frame, self.config.selection.stride);
        let on_grid = |index: usize, last: bool| last || (index - first).is_multiple_of(stride);
        let driver = Driver {
            config: self.config,
            stages: self.stages,
            caches: Caches {
                edge: &self.caches.edge,
                regenerator: &self.caches.regenerator,
                pose: if regenerate {
                    &self.caches.pose
                } else {
                    &self.caches.original
                },
            },
            records: self.records,
            n_keypoints: self.n_keypoints,
            regenerate,
            estimate,
            pose_record: if regenerate { "pose" } else { ORIGINAL_POSE },
            order,
            last_estimated: None,
            last_regenerated: None,
            recent: Vec::new(),
            cached_frames: BTreeSet::new(),
            original_poses,
            sharpness: &mut self.sharpness,
            subject: self.subject,
            // After the subject's last frame every pose is empty: no need to decode on.
            stop_after: self
                .subject
                .and_then(|s| s.keys().next_back().copied())
                .zip(self.range_end),
        };
        let found = driver.stream(self.info, &bar, &|f, last| on_grid(f, last) && wanted(f))?;
        bar.finish_and_clear();
        Ok(found)
    }

    /// Part `part` of `parts` of the frames the run regenerates, through the
    /// regenerator only (see [`crate::runner::regenerate_part`]). The frames
    /// are dealt out in turn, so every part gets an even share of the walk.
    pub(crate) fn regenerate_part(
        &mut self,
        part: usize,
        parts: usize,
    ) -> Result<(), PipelineError> {
        let needs_poses = self.config.regenerator.needs_poses();
        let stride = self.config.selection.stride;
        let first = self.config.input.first_frame;
        let original = if self.config.selection.mode == SelectionMode::Poor || needs_poses {
            Some(self.pass(ORIGINAL, self.grid(), None, &|_| true)?.1)
        } else {
            None
        };
        let masks = |o: &Vec<(usize, Pose)>| needs_poses.then(|| o.iter().cloned().collect());
        match original {
            Some(o) if self.config.selection.mode == SelectionMode::Poor => {
                let poor = self.judge(&o, &mut SelectionRecord::default())?;
                let mine: BTreeSet<usize> =
                    poor.iter().copied().skip(part).step_by(parts).collect();
                let order = Order::Subset {
                    frames: poor,
                    stride,
                };
                self.pass(REGENERATED_ONLY, order, masks(&o), &|f| mine.contains(&f))?;
            }
            o => {
                let m = o.as_ref().and_then(masks);
                let mine = |f: usize| ((f - first) / stride) % parts == part;
                self.pass(REGENERATED_ONLY, self.grid(), m, &mine)?;
            }
        }
        Ok(())
    }

    /// Poses on the original frames, then the regeneration pass over the
    /// frames whose pose is poor; the rest keep their original pose.
    fn poor_frames(&mut self) -> Result<PassOutput, PipelineError> {
        let (all, original, cached_original) = self.pass(ORIGINAL, self.grid(), None, &|_| true)?;
        let mut selection = SelectionRecord::default();
        let poor = self.judge(&original, &mut selection)?;
        let mut regenerated: BTreeMap<usize, Pose> = BTreeMap::new();
        let mut cached_regenerated = BTreeSet::new();
        if !poor.is_empty() {
            let wanted: BTreeSet<usize> = poor.iter().copied().collect();
            let order = Order::Subset {
                frames: poor,
                stride: self.config.selection.stride,
            };
            let masks = self
                .config
                .regenerator
                .needs_poses()
                .then(|| original.iter().cloned().collect());
            let (_, found, cached) =
                self.pass(REGENERATED, order, masks, &|f| wanted.contains(&f))?;
            regenerated.extend(found);
            cached_regenerated = cached;
        }
        let mut from_cache = 0;
        let processed = original
            .iter()
            .map(|(f, p)| match regenerated.remove(f) {
                Some(r) => {
                    from_cache += usize::from(cached_regenerated.contains(f));
                    (*f, r)
                }
                None => {
                    from_cache += usize::from(cached_original.contains(f));
                    (*f, p.clone())
                }
            })
            .collect();
        Ok(PassOutput {
            all,
            processed,
            from_cache,
            original: Some(original),
            selection,
            blur_px: BTreeMap::new(),
            feet_contrast: BTreeMap::new(),
        })
    }

    /// The poor frames among the original-frame poses, recorded per reason.
    /// Frames without the subject in view are not poor: there is nobody to
    /// regenerate.
    fn judge(
        &self,
        original: &[(usize, Pose)],
        record: &mut SelectionRecord,
    ) -> Result<Vec<usize>, PipelineError> {
        let sel = &self.config.selection;
        let poses: Vec<Pose> = original.iter().map(|(_, p)| p.clone()).collect();
        let verdict = selection::judge(&poses, self.names, sel)
            .map_err(|e| PipelineError::config("selection.keypoints", e))?;
        let in_view = |f: usize| self.subject.is_none_or(|s| s.contains_key(&f));
        let mut poor = Vec::new();
        for ((f, _), reason) in original.iter().zip(&verdict.reasons) {
            if let Some(r) = reason.filter(|_| in_view(*f)) {
                poor.push(*f);
                record.poor.entry(r).or_default().push([*f, *f]);
                *record.poor_counts.entry(r).or_default() += 1;
            }
        }
        for frames in record.poor.values_mut() {
            *frames = selection::ranges(frames.iter().map(|r| r[0]));
        }
        record.segment_medians_px = Some(verdict.medians);
        Ok(poor)
    }

    /// Inpainting without selection: poses on the original frames for the
    /// leg masks, then every grid frame through the regenerator.
    fn inpainting(&mut self) -> Result<PassOutput, PipelineError> {
        let (_, original, _) = self.pass(ORIGINAL, self.grid(), None, &|_| true)?;
        let masks = original.iter().cloned().collect();
        let (all, processed, cached) =
            self.pass(REGENERATED, self.grid(), Some(masks), &|_| true)?;
        Ok(PassOutput {
            all,
            processed,
            from_cache: cached.len(),
            original: Some(original),
            selection: SelectionRecord::default(),
            blur_px: BTreeMap::new(),
            feet_contrast: BTreeMap::new(),
        })
    }
}
