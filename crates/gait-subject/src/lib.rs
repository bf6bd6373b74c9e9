//! The subject of a run: the people found in every frame (by the pose
//! estimator's [`gait_core::PoseEstimator::people`]) are linked into tracks
//! ([`link`]), each track gets a walking score ([`walking`]), and one track is
//! chosen by `[pose] person` ([`choose`]). The pose pass then follows that
//! track only: where the subject is not in view, its frames stay empty.

pub mod appearance;
mod bridge;
mod choose;
pub mod link;
mod lookahead;
mod returns;
pub mod sparse;
mod stitch;
mod track;
pub mod walking;

use std::collections::BTreeMap;

use gait_core::{PersonBox, PersonChoice, ranges};
use serde::{Deserialize, Serialize};

pub use appearance::Appearance;
pub use track::{LinkLimits, Sighting, Track};
pub use walking::Walk;

/// The `[subject]` table: how people are linked into tracks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SubjectConfig {
    /// Find every person in every frame and follow one track (false: the pose
    /// estimator picks a person frame by frame, as before).
    pub enabled: bool,
    /// Longest time a person may be hidden or out of view and still be taken
    /// up again as the same track, seconds.
    pub max_gap_s: f64,
    /// Gaps of up to this long (seconds) inside the subject's track are
    /// bridged: the pose model still looks where the subject should be
    /// (between the sightings either side), except in frames where someone
    /// else is seen there. The detector misses people the landmark model
    /// still finds (half hidden, side on, motion blur).
    pub bridge_gap_s: f64,
    /// Time (seconds) before the subject's first and after its last sighting
    /// in which the pose model still looks where it was heading: the
    /// detector finds a person coming out from behind something a few frames
    /// later than the landmark model does, and when varies with the encoding.
    pub lead_s: f64,
    /// Largest change of body size between sightings of one person.
    pub max_size_ratio: f32,
    /// Largest mean colour difference (RGB in [0, 1]) of torso and legs to
    /// take a track up again after a gap.
    pub max_colour_distance: f32,
    /// The detector runs on every k-th frame, and on the frames between
    /// wherever the people either side do not pair up clearly (see
    /// [`sparse`]); elsewhere their people are interpolated. 1 (default):
    /// every frame. 2 spares the detector on 39 of the sample's 230 frames,
    /// but moves 4 of its 14 events by a frame: the pose model's choice to
    /// crop afresh from the box tips on the box's size (BENCHMARKS.md).
    pub detect_every: usize,
    /// With `person = "walker"`: other walks across the view by a person of
    /// the subject's colours and size, wholly before or after the subject's
    /// (the walk back after a turn out of view), are followed too.
    pub returns: bool,
}

impl Default for SubjectConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            max_gap_s: 2.0,
            bridge_gap_s: 1.0,
            lead_s: 0.2,
            max_size_ratio: 1.4,
            max_colour_distance: 0.1,
            detect_every: 1,
            returns: true,
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SubjectError {
    #[error(
        "no person was found in any frame: check the video shows the subject (and the pose model's detection_threshold)"
    )]
    NoPerson,
    #[error("pose.person: frame {frame} is not in the analysed frames {first}-{last}")]
    FrameOutside {
        frame: usize,
        first: usize,
        last: usize,
    },
    #[error("pose.person: point ({x}, {y}) lies outside the {width}x{height} frame")]
    PointOutside {
        x: f32,
        y: f32,
        width: u32,
        height: u32,
    },
    #[error("pose.person: nobody is seen in frame {0}; pick a frame where the subject is in view")]
    NobodyAt(usize),
    #[error("subject.{0}")]
    Config(String),
}

impl SubjectConfig {
    pub fn validate(&self) -> Result<(), SubjectError> {
        if !(self.max_gap_s.is_finite() && self.max_gap_s >= 0.0) {
            return Err(SubjectError::Config(
                "max_gap_s: must be a non-negative number".into(),
            ));
        }
        if !(self.bridge_gap_s.is_finite() && self.bridge_gap_s >= 0.0) {
            return Err(SubjectError::Config(
                "bridge_gap_s: must be a non-negative number".into(),
            ));
        }
        if !(self.lead_s.is_finite() && (0.0..=2.0).contains(&self.lead_s)) {
            return Err(SubjectError::Config(
                "lead_s: must be a number of seconds from 0 to 2".into(),
            ));
        }
        if !(self.max_size_ratio.is_finite() && self.max_size_ratio > 1.0) {
            return Err(SubjectError::Config(
                "max_size_ratio: must be above 1".into(),
            ));
        }
        if !(self.max_colour_distance.is_finite() && self.max_colour_distance > 0.0) {
            return Err(SubjectError::Config(
                "max_colour_distance: must be a positive number".into(),
            ));
        }
        if !(1..=4).contains(&self.detect_every) {
            return Err(SubjectError::Config(
                "detect_every: must be a whole number from 1 (every frame) to 4".into(),
            ));
        }
        Ok(())
    }

    fn limits(&self, fps: f64) -> LinkLimits {
        LinkLimits {
            max_gap_frames: (self.max_gap_s * fps).round() as usize,
            max_size_ratio: self.max_size_ratio,
            max_colour_distance: self.max_colour_distance,
            // A detector misses people for a few frames (motion blur, a
            // limb across the face): a track unseen for 0.2 s costs more to
            // continue than one seen a frame ago.
            short_gap_frames: (0.2 * fps).round() as usize,
        }
    }
}

/// One track as run.json lists it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrackSummary {
    pub id: usize,
    pub first_frame: usize,
    pub last_frame: usize,
    /// Frames in which the person was seen.
    pub frames: usize,
    /// Mean body centre and size, pixels.
    pub mean_centre: [f32; 2],
    pub mean_size: f32,
    pub mean_score: f32,
    /// The longest walk (its displacement is the walking score).
    pub walk: Walk,
    #[serde(skip)]
    pub sightings: Vec<Sighting>,
}

impl TrackSummary {
    fn new(id: usize, track: Track, fps: f64) -> Self {
        let s = &track.sightings;
        let n = s.len() as f32;
        let mean = |f: &dyn Fn(&Sighting) -> f32| s.iter().map(f).sum::<f32>() / n;
        Self {
            id,
            first_frame: s[0].frame,
            last_frame: s[s.len() - 1].frame,
            frames: s.len(),
            mean_centre: [mean(&|x| x.person.centre[0]), mean(&|x| x.person.centre[1])],
            mean_size: mean(&|x| x.person.size()),
            mean_score: mean(&|x| x.person.score),
            walk: walking::longest_walk(&track, fps),
            sightings: track.sightings,
        }
    }

    /// The person's box in `frame`, if seen there.
    pub fn box_at(&self, frame: usize) -> Option<PersonBox> {
        self.sighting_at(frame).map(|s| s.person)
    }

    pub(crate) fn sighting_at(&self, frame: usize) -> Option<&Sighting> {
        let i = self
            .sightings
            .binary_search_by_key(&frame, |s| s.frame)
            .ok()?;
        Some(&self.sightings[i])
    }
}

/// The tracks of a run and the subject among them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Subject {
    pub tracks: Vec<TrackSummary>,
    /// Id of the subject's track.
    pub chosen: usize,
    /// Why that track (the rule and its numbers).
    pub reason: String,
    /// False when `person = "walker"` found nobody walking.
    pub walking: bool,
    /// Frames where the subject is followed, as inclusive ranges.
    pub in_view: Vec<[usize; 2]>,
    /// The subject's box per frame (sighted, or bridged over a short miss).
    #[serde(skip)]
    pub boxes: BTreeMap<usize, PersonBox>,
    /// The last frame the pass saw (the end of the analysed range).
    #[serde(skip)]
    pub last_frame: usize,
    /// Frames whose people were interpolated between detected frames
    /// (`detect_every`) instead of detected; the pass that found the
    /// people sets it.
    pub interpolated_frames: usize,
    /// Other tracks followed as the subject walking across the view again
    /// (`[subject] returns`).
    pub returns: Vec<Return>,
}

/// A track taken as the subject walking across the view again, and how it matched.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Return {
    pub track: usize,
    pub first_frame: usize,
    pub last_frame: usize,
    /// Mean colour difference from the subject's track (RGB in [0, 1]).
    pub colour_distance: f32,
    /// Ratio of the mean body sizes (at least 1).
    pub size_ratio: f32,
}

/// Links the people of `frames` (frame index, people in it; in frame order)
/// into tracks and picks the subject by `choice`.
pub fn find(
    frames: &[(usize, Vec<Sighting>)],
    choice: PersonChoice,
    config: &SubjectConfig,
    fps: f64,
    frame_size: (u32, u32),
) -> Result<Subject, SubjectError> {
    check_point(frames, choice, frame_size)?;
    let limits = config.limits(fps);
    let tracks: Vec<TrackSummary> = stitch::stitch(link::link(frames, &limits), &limits)
        .into_iter()
        .enumerate()
        .map(|(id, t)| TrackSummary::new(id, t, fps))
        .collect();
    if tracks.is_empty() {
        return Err(SubjectError::NoPerson);
    }
    let centre = [frame_size.0 as f32 / 2.0, frame_size.1 as f32 / 2.0];
    let (chosen, reason) = match choose::choose(&tracks, choice, centre) {
        Some(c) => c,
        None => match choice {
            PersonChoice::At(at) => return Err(SubjectError::NobodyAt(at.frame)),
            PersonChoice::Rule(_) => return Err(SubjectError::NoPerson),
        },
    };
    let walking = tracks[chosen].walk.displacement >= choose::MIN_WALK;
    let frames_of = |s: f64| (s * fps).round() as usize;
    let reach = bridge::Reach {
        fill: frames_of(config.bridge_gap_s),
        max_gap: limits.max_gap_frames,
        lead: frames_of(config.lead_s),
        range: (
            frames.first().map_or(0, |f| f.0),
            frames.last().map_or(0, |f| f.0),
        ),
    };
    let mut boxes = bridge::boxes(&tracks, chosen, &reach, config.max_colour_distance);
    let walker = choice == PersonChoice::Rule(gait_core::PersonRule::Walker);
    let mut back = Vec::new();
    if config.returns && walker && walking {
        for (track, colour_distance, size_ratio) in returns::returns(&tracks, chosen, config) {
            for (f, b) in bridge::boxes(&tracks, track, &reach, config.max_colour_distance) {
                boxes.entry(f).or_insert(b);
            }
            back.push(Return {
                track,
                first_frame: tracks[track].first_frame,
                last_frame: tracks[track].last_frame,
                colour_distance,
                size_ratio,
            });
        }
    }
    let reason = match back.len() {
        0 => reason,
        n => format!(
            "{reason}; and {n} more walk(s) across the view in the subject's colours and size ({})",
            back.iter()
                .map(|r| format!("frames {}-{}", r.first_frame, r.last_frame))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    Ok(Subject {
        last_frame: frames.last().map_or(0, |f| f.0),
        in_view: ranges(boxes.keys().copied()),
        tracks,
        chosen,
        reason,
        walking,
        boxes,
        interpolated_frames: 0,
        returns: back,
    })
}

fn check_point(
    frames: &[(usize, Vec<Sighting>)],
    choice: PersonChoice,
    (width, height): (u32, u32),
) -> Result<(), SubjectError> {
    let PersonChoice::At(at) = choice else {
        return Ok(());
    };
    let (first, last) = match (frames.first(), frames.last()) {
        (Some(a), Some(b)) => (a.0, b.0),
        _ => return Err(SubjectError::NoPerson),
    };
    if !(first..=last).contains(&at.frame) {
        return Err(SubjectError::FrameOutside {
            frame: at.frame,
            first,
            last,
        });
    }
    if !(at.x >= 0.0 && at.y >= 0.0 && at.x < width as f32 && at.y < height as f32) {
        return Err(SubjectError::PointOutside {
            x: at.x,
            y: at.y,
            width,
            height,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::tests::seen;
    use gait_core::{PersonAt, PersonRule};

    /// A standing person (large) and a walker (smaller) who is hidden for a while.
    fn scene() -> Vec<(usize, Vec<Sighting>)> {
        (0..150)
            .map(|f| {
                let mut people = vec![seen(f, 300.0, 500.0, 0.8)];
                if (20..140).contains(&f) && !(60..100).contains(&f) && f != 110 {
                    people.push(seen(f, 1600.0 - 10.0 * (f - 20) as f32, 400.0, 0.2));
                }
                (f, people)
            })
            .collect()
    }

    #[test]
    fn the_walker_is_chosen_over_the_largest() {
        let cfg = SubjectConfig::default();
        let s = find(&scene(), PersonChoice::default(), &cfg, 30.0, (1800, 1000)).unwrap();
        let t = &s.tracks[s.chosen];
        assert!(
            s.walking && t.first_frame == 20 && t.last_frame == 139,
            "{s:?}"
        );
        // The single missed frame is bridged, the 40-frame hiding is not;
        // the pose model looks 0.2 s beyond each end of her sightings, but
        // not past 139, where her way runs onto the standing person.
        assert!(s.boxes.contains_key(&110) && !s.boxes.contains_key(&75));
        assert_eq!(s.in_view, vec![[14, 65], [94, 139]]);
        let largest = PersonChoice::Rule(PersonRule::Largest);
        let s = find(&scene(), largest, &cfg, 30.0, (1800, 1000)).unwrap();
        assert_eq!(s.tracks[s.chosen].frames, 150);
    }

    #[test]
    fn a_point_picks_the_nearest_track_and_bad_points_are_errors() {
        let cfg = SubjectConfig::default();
        let at = |frame, x, y| PersonChoice::At(PersonAt { frame, x, y });
        let s = find(&scene(), at(10, 350.0, 450.0), &cfg, 30.0, (1800, 1000)).unwrap();
        assert_eq!(s.tracks[s.chosen].first_frame, 0);
        assert!(!s.walking);
        let e = |c| find(&scene(), c, &cfg, 30.0, (1800, 1000)).unwrap_err();
        assert!(matches!(
            e(at(400, 1.0, 1.0)),
            SubjectError::FrameOutside { .. }
        ));
        assert!(matches!(
            e(at(10, 1900.0, 1.0)),
            SubjectError::PointOutside { .. }
        ));
    }

    #[test]
    fn nobody_anywhere_is_an_error_and_nobody_walking_takes_the_longest() {
        let cfg = SubjectConfig::default();
        let empty: Vec<(usize, Vec<Sighting>)> = (0..10).map(|f| (f, vec![])).collect();
        assert_eq!(
            find(&empty, PersonChoice::default(), &cfg, 30.0, (100, 100)),
            Err(SubjectError::NoPerson)
        );
        let standing: Vec<_> = (0..50)
            .map(|f| (f, vec![seen(f, 300.0, 500.0, 0.8)]))
            .collect();
        let s = find(&standing, PersonChoice::default(), &cfg, 30.0, (1800, 1000)).unwrap();
        assert!(
            !s.walking && s.reason.contains("nobody walks"),
            "{}",
            s.reason
        );
    }
}
