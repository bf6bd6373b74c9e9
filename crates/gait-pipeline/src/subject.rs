//! The subject pass: every person in every frame of the range (the pose
//! estimator's detector, cached per frame), linked into tracks, one chosen
//! (gait-subject). The pose passes then follow that track only.

use gait_core::PoseEstimator;
use gait_subject::{Appearance, Sighting, Subject};
use indicatif::ProgressBar;
use std::time::Instant;

use crate::cache::StageCache;
use crate::input::InputInfo;
use crate::manifest::StageRecord;
use crate::{PipelineConfig, PipelineError};

/// What the subject pass found: the subject, or why there is none to follow
/// (the estimator cannot list people, or the pass is off).
pub(crate) enum Found {
    Subject(Subject),
    Off(Option<String>),
}

/// Runs the pass over the configured range of `info` on the original frames.
pub(crate) fn find(
    config: &PipelineConfig,
    info: &InputInfo,
    fps: f64,
    pose: &mut dyn PoseEstimator,
    cache: &StageCache,
    record: &mut StageRecord,
    bar: &ProgressBar,
) -> Result<Found, PipelineError> {
    if !config.subject.enabled {
        return Ok(Found::Off(None));
    }
    let Some(frames) = sightings(config, info, pose, cache, record, bar)? else {
        return Ok(Found::Off(Some(
            "the pose stage cannot list the people in a frame: no subject tracking, the estimator picks a person frame by frame".into(),
        )));
    };
    let person = config.pose.person();
    gait_subject::find(
        &frames,
        person,
        &config.subject,
        fps,
        (info.width, info.height),
    )
    .map(Found::Subject)
    .map_err(|e| PipelineError::input(&info.path, e))
}

/// The people of every frame in range, or `None` when the estimator cannot
/// list them.
fn sightings(
    config: &PipelineConfig,
    info: &InputInfo,
    pose: &mut dyn PoseEstimator,
    cache: &StageCache,
    record: &mut StageRecord,
    bar: &ProgressBar,
) -> Result<Option<Vec<(usize, Vec<Sighting>)>>, PipelineError> {
    let (first, last) = (config.input.first_frame, config.input.last_frame);
    let mut reader = info.frames()?;
    let mut out = Vec::new();
    while let Some(frame) = reader.next_frame()? {
        if last.is_some_and(|l| frame.index > l) {
            break;
        }
        if frame.index < first {
            continue;
        }
        bar.inc(1);
        if let Some(seen) = cache.load_json::<Vec<Sighting>>(frame.index) {
            record.cached += 1;
            out.push((frame.index, seen));
            continue;
        }
        let t = Instant::now();
        let Some(people) = pose.people(&frame)? else {
            return Ok(None);
        };
        let seen: Vec<Sighting> = people
            .into_iter()
            .map(|person| Sighting {
                frame: frame.index,
                person,
                appearance: Appearance::of(&frame.image, &person),
            })
            .collect();
        record.seconds += t.elapsed().as_secs_f64();
        record.computed += 1;
        cache.store_json(frame.index, &seen)?;
        out.push((frame.index, seen));
        if last == Some(frame.index) {
            break;
        }
    }
    Ok(Some(out))
}
