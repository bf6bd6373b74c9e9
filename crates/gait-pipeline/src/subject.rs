//! The subject pass: every person in every frame of the range (the pose
//! estimator's detector, cached per frame), linked into tracks, one chosen
//! (gait-subject). The pose passes then follow that track only.

use std::path::Path;
use std::time::Instant;

use gait_core::{Frame, PoseEstimator, StageContext};
use gait_subject::{Appearance, Sighting, Subject};

use crate::cache::StageCache;
use crate::input::InputInfo;
use crate::manifest::StageRecord;
use crate::plan::{self, Models};
use crate::progress::Progress;
use crate::registry;
use crate::{PipelineConfig, PipelineError};

/// What the subject pass found: the subject, or why there is none to follow
/// (the estimator cannot list people, or the pass is off).
pub(crate) enum Found {
    Subject(Subject),
    Off(Option<String>),
}

/// A pose model (a stage, owned by the run or by the pass).
pub(crate) type Model = dyn PoseEstimator + 'static;

/// The pose models of the pass: frames are independent here, and the models
/// run single-threaded, so one per core.
pub(crate) struct Workers<'a> {
    /// The run's own pose stage, when it lists people itself (one model
    /// fewer in memory).
    pub(crate) shared: Option<&'a mut Model>,
    /// Makes another instance.
    pub(crate) build: &'a dyn Fn() -> Result<Box<dyn PoseEstimator>, PipelineError>,
    pub(crate) count: usize,
}

/// Runs the pass over the configured range of `info` on the original frames.
pub(crate) fn find(
    config: &PipelineConfig,
    info: &InputInfo,
    fps: f64,
    workers: Workers,
    cache: &StageCache,
    record: &mut StageRecord,
    bar: &Progress,
) -> Result<Found, PipelineError> {
    if !config.subject.enabled {
        return Ok(Found::Off(None));
    }
    let extra = workers.count.max(1) - usize::from(workers.shared.is_some());
    let mut owned = Vec::with_capacity(extra);
    for _ in 0..extra {
        owned.push((workers.build)()?);
    }
    let mut models: Vec<&mut Model> = workers
        .shared
        .into_iter()
        .chain(owned.iter_mut().map(|m| m.as_mut()))
        .collect();
    let Some((frames, interpolated)) = sightings(config, info, &mut models, cache, record, bar)?
    else {
        return Ok(Found::Off(Some(
            "the pose stage cannot list the people in a frame: no subject tracking, the estimator picks a person frame by frame".into(),
        )));
    };
    if frames.is_empty() {
        return Err(PipelineError::input(
            &info.path,
            info.no_frames_in(config.input.first_frame, config.input.last_frame),
        ));
    }
    let person = config.pose.person();
    gait_subject::find(
        &frames,
        person,
        &config.subject,
        fps,
        (info.width, info.height),
    )
    .map(|s| {
        Found::Subject(gait_subject::Subject {
            interpolated_frames: interpolated,
            ..s
        })
    })
    .map_err(|e| PipelineError::input(&info.path, e))
}

/// Frame index and the people seen in it, in frame order.
type FramePeople = Vec<(usize, Vec<Sighting>)>;

/// The people of every frame in range, or `None` when the estimator cannot
/// list them. Every `detect_every`-th frame is an anchor: the anchors of a
/// few frames per model are detected (or loaded from the cache) at once,
/// then the frames between each two anchors are interpolated where
/// [`gait_subject::sparse`] allows, else detected. The cache holds only
/// detections, so a repeated or resumed run decides alike.
fn sightings(
    config: &PipelineConfig,
    info: &InputInfo,
    models: &mut [&mut Model],
    cache: &StageCache,
    record: &mut StageRecord,
    bar: &Progress,
) -> Result<Option<(FramePeople, usize)>, PipelineError> {
    let (first, last) = (config.input.first_frame, config.input.last_frame);
    let every = config.subject.detect_every.max(1);
    let mut reader = info.frames()?;
    let mut pass = Sparse {
        models,
        cache,
        record,
        out: Vec::new(),
        anchor: None,
        interpolated: 0,
    };
    // Frames after the last settled anchor; one anchor per model each time.
    let mut chunk: Vec<Frame> = Vec::new();
    let mut anchors = 0;
    let mut done = false;
    while !done {
        match reader.next_frame()? {
            Some(frame) if last.is_none_or(|l| frame.index <= l) => {
                done = last == Some(frame.index);
                if frame.index < first {
                    continue;
                }
                bar.tick()?;
                anchors += usize::from((frame.index - first).is_multiple_of(every));
                chunk.push(frame);
            }
            _ => done = true,
        }
        if (anchors == pass.models.len() || done) && !chunk.is_empty() {
            if !pass.settle(std::mem::take(&mut chunk), first, every)? {
                return Ok(None);
            }
            anchors = 0;
        }
    }
    Ok(Some((pass.out, pass.interpolated)))
}

/// The subject pass's frames settled so far, and what settles the next.
struct Sparse<'m, 'a, 'b> {
    models: &'m mut [&'a mut Model],
    cache: &'b StageCache,
    record: &'b mut StageRecord,
    out: FramePeople,
    /// Index into `out` of the last anchor.
    anchor: Option<usize>,
    interpolated: usize,
}

impl Sparse<'_, '_, '_> {
    /// Settles `chunk` (frames in order, ending on an anchor or at the end
    /// of the range, which is taken as one): false when the estimator cannot
    /// list people.
    fn settle(
        &mut self,
        chunk: Vec<Frame>,
        first: usize,
        every: usize,
    ) -> Result<bool, PipelineError> {
        let n = chunk.len();
        let is_anchor = |i: usize, f: &Frame| (f.index - first).is_multiple_of(every) || i + 1 == n;
        let anchors: Vec<&Frame> = chunk
            .iter()
            .enumerate()
            .filter(|(i, f)| is_anchor(*i, f))
            .map(|(_, f)| f)
            .collect();
        let Some(anchor_people) = self.detected(&anchors)? else {
            return Ok(false);
        };
        let mut people: Vec<Option<Vec<Sighting>>> = vec![None; n];
        let mut k = 0;
        for (i, f) in chunk.iter().enumerate() {
            if is_anchor(i, f) {
                people[i] = Some(anchor_people[k].clone());
                k += 1;
            }
        }
        // The frames between two anchors: interpolated, else detected.
        let mut before = self.anchor.map(|a| self.out[a].clone());
        let mut gap_start = 0;
        let mut to_detect: Vec<usize> = Vec::new();
        for i in 0..n {
            let Some(here) = people[i].clone() else {
                continue;
            };
            let gap = gap_start..i;
            let fill = before.as_ref().and_then(|(fa, sa)| {
                gait_subject::sparse::between((*fa, sa), (chunk[i].index, &here))
            });
            match fill {
                Some(found) => {
                    for ((_, boxes), j) in found.into_iter().zip(gap) {
                        self.interpolated += 1;
                        people[j] = Some(with_appearance(&chunk[j], boxes));
                    }
                }
                None => to_detect.extend(gap),
            }
            before = Some((chunk[i].index, here));
            gap_start = i + 1;
        }
        let frames: Vec<&Frame> = to_detect.iter().map(|&i| &chunk[i]).collect();
        let Some(found) = self.detected(&frames)? else {
            return Ok(false);
        };
        for (i, seen) in to_detect.into_iter().zip(found) {
            people[i] = Some(seen);
        }
        for (f, seen) in chunk.iter().zip(people) {
            self.out.push((f.index, seen.unwrap_or_default()));
        }
        self.anchor = Some(self.out.len() - 1);
        Ok(true)
    }

    /// The detected people of `frames`, from the cache or the models (and
    /// then cached); `None` when the estimator cannot list people.
    fn detected(&mut self, frames: &[&Frame]) -> Result<Option<Vec<Vec<Sighting>>>, PipelineError> {
        let mut out: Vec<Option<Vec<Sighting>>> = frames
            .iter()
            .map(|f| self.cache.load_json::<Vec<Sighting>>(f.index))
            .collect();
        self.record.cached += out.iter().filter(|s| s.is_some()).count();
        let pending: Vec<&Frame> = frames
            .iter()
            .zip(&out)
            .filter(|(_, s)| s.is_none())
            .map(|(f, _)| *f)
            .collect();
        if !pending.is_empty() {
            let t = Instant::now();
            let Some(found) = people(self.models, &pending)? else {
                return Ok(None);
            };
            self.record.seconds += t.elapsed().as_secs_f64();
            self.record.computed += pending.len();
            let mut found = found.into_iter();
            for (frame, slot) in frames.iter().zip(out.iter_mut()) {
                if slot.is_none() {
                    let seen = found.next().unwrap_or_default();
                    self.cache.store_json(frame.index, &seen)?;
                    *slot = Some(seen);
                }
            }
        }
        Ok(Some(
            out.into_iter().map(Option::unwrap_or_default).collect(),
        ))
    }
}

/// The people at `boxes` in `frame`, with their appearance measured there.
fn with_appearance(frame: &Frame, boxes: Vec<gait_core::PersonBox>) -> Vec<Sighting> {
    boxes
        .into_iter()
        .map(|person| Sighting {
            frame: frame.index,
            person,
            appearance: Appearance::of(&frame.image, &person),
        })
        .collect()
}

/// The people of each of `frames`, the frames shared out among `models`
/// (one thread each); `None` when the estimator cannot list people.
fn people(
    models: &mut [&mut Model],
    frames: &[&Frame],
) -> Result<Option<Vec<Vec<Sighting>>>, PipelineError> {
    let per = frames.len().div_ceil(models.len()).max(1);
    let results: Vec<Result<Option<Vec<Vec<Sighting>>>, PipelineError>> = std::thread::scope(|s| {
        let handles: Vec<_> = models
            .iter_mut()
            .zip(frames.chunks(per))
            .map(|(model, chunk)| s.spawn(move || of_frames(&mut **model, chunk)))
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join().unwrap_or_else(|_| {
                    Err(PipelineError::Stage(gait_core::StageError::backend(
                        "pose",
                        "the pose model failed while finding people",
                    )))
                })
            })
            .collect()
    });
    let mut all = Vec::with_capacity(frames.len());
    for r in results {
        match r? {
            Some(found) => all.extend(found),
            None => return Ok(None),
        }
    }
    Ok(Some(all))
}

/// The people in each frame, with their appearance.
fn of_frames(
    model: &mut dyn PoseEstimator,
    frames: &[&Frame],
) -> Result<Option<Vec<Vec<Sighting>>>, PipelineError> {
    let mut out = Vec::with_capacity(frames.len());
    for frame in frames {
        let Some(people) = model.people(frame)? else {
            return Ok(None);
        };
        out.push(with_appearance(frame, people));
    }
    Ok(Some(out))
}

/// The subject pass (cached per frame), its stage record and the warnings it
/// leaves for run.json. `pose` is the run's pose stage: it lists the people
/// itself when it can (no second copy of the model in memory).
pub(crate) fn run_pass(
    config: &PipelineConfig,
    info: &InputInfo,
    fps: f64,
    (ctx, pose): (&StageContext, &mut Model),
    models: &Models,
    root: Option<&Path>,
    bar: &dyn Fn(&str) -> Progress,
) -> Result<SubjectPass, PipelineError> {
    // A stage that cannot list people (Python) has them listed by the built-in detector.
    let finder = config.pose.people_finder();
    let pose_ctx = ctx.clone().on(models.devices[2]);
    let mut kind = registry::stage_kinds(config)[2].1.clone();
    if let Some(f) = &finder {
        if let Err(e) = f.build(&pose_ctx) {
            let why = format!(
                "the {kind} pose stage cannot list the people in a frame and the built-in BlazePose detector that lists them for it is not there ({}): no subject tracking, the estimator picks a person frame by frame; run `gait models fetch blazepose`",
                crate::one_line(&e.to_string())
            );
            return Ok((None, None, vec![why]));
        }
        kind = format!("blazepose detector (people for the {kind} pose stage)");
    }
    let people_from = finder.as_ref().unwrap_or(&config.pose);
    let (cache, key) = plan::subject_cache(people_from, models, root)?;
    let mut record = plan::record(kind, models.devices[2], &key);
    let bar = bar("finding the subject");
    let build = || people_from.build(&pose_ctx).map_err(PipelineError::from);
    // One model per core on the CPU; a GPU runs one at a time anyway.
    let workers = match models.devices[2] {
        gait_core::Device::Cpu => {
            std::thread::available_parallelism().map_or(1, |n| n.get().min(4))
        }
        _ => 1,
    };
    let workers = Workers {
        shared: finder.is_none().then_some(pose),
        build: &build,
        count: workers,
    };
    let found = find(config, info, fps, workers, &cache, &mut record, &bar)?;
    bar.finish_and_clear();
    let corrupt = cache.take_warnings();
    Ok(match found {
        Found::Subject(s) => {
            let mut warnings = corrupt;
            if !s.walking {
                warnings.push(format!("no walking subject found: {}", s.reason));
            }
            (Some(s), Some((plan::SUBJECT.to_string(), record)), warnings)
        }
        Found::Off(why) => (None, None, corrupt.into_iter().chain(why).collect()),
    })
}

pub(crate) type SubjectPass = (
    Option<gait_subject::Subject>,
    Option<(String, StageRecord)>,
    Vec<String>,
);
