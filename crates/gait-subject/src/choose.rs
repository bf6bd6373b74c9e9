//! Picks the subject's track by the configured [`PersonChoice`].

use gait_core::{PersonAt, PersonChoice, PersonRule};

use crate::TrackSummary;

/// Tracks shorter than this fraction of the longest one are passing
/// detections (a face on a poster, one frame of a passer-by), not candidates,
/// unless nothing else is there.
const MIN_SHARE: f32 = 0.1;
/// A walk shorter than this many body sizes is a shuffle, not a walk across
/// the view. Body sizes are the detector's crops, about 1.5 body heights:
/// one stride of a normal walk is about half of one.
pub const MIN_WALK: f32 = 0.5;

/// The index of the chosen track and why, or `None` when `at` names a frame
/// in which nobody is seen.
pub fn choose(
    tracks: &[TrackSummary],
    choice: PersonChoice,
    centre: [f32; 2],
) -> Option<(usize, String)> {
    let longest = tracks.iter().map(|t| t.frames).max()?;
    let candidates: Vec<usize> = (0..tracks.len())
        .filter(|&i| tracks[i].frames as f32 >= MIN_SHARE * longest as f32)
        .collect();
    let best = |key: &dyn Fn(&TrackSummary) -> f32| {
        candidates
            .iter()
            .copied()
            .max_by(|&a, &b| key(&tracks[a]).total_cmp(&key(&tracks[b])).then(b.cmp(&a)))
    };
    let rule = match choice {
        PersonChoice::At(at) => return at_point(tracks, at),
        PersonChoice::Rule(r) => r,
    };
    let pick = match rule {
        PersonRule::Walker => return Some(walker(tracks, &candidates)),
        PersonRule::Largest => best(&|t| t.mean_size),
        PersonRule::Leftmost => best(&|t| -t.mean_centre[0]),
        PersonRule::Rightmost => best(&|t| t.mean_centre[0]),
        PersonRule::MostCentral => {
            best(&|t| -(t.mean_centre[0] - centre[0]).hypot(t.mean_centre[1] - centre[1]))
        }
        PersonRule::MostConfident => best(&|t| t.mean_score),
    }?;
    let name = serde_plain(rule);
    Some((
        pick,
        format!(
            "{name}: of the tracks seen in at least {:.0} % of the longest one's frames",
            MIN_SHARE * 100.0
        ),
    ))
}

/// The track with the longest walk across the view. Without a walk of
/// [`MIN_WALK`] body sizes (a short clip, or nobody walking) the track moving
/// most across the view, and without any steady movement the longest track.
fn walker(tracks: &[TrackSummary], candidates: &[usize]) -> (usize, String) {
    let by = |key: &dyn Fn(&TrackSummary) -> f32| {
        candidates
            .iter()
            .copied()
            .max_by(|&a, &b| key(&tracks[a]).total_cmp(&key(&tracks[b])).then(b.cmp(&a)))
            .unwrap_or(0)
    };
    let i = by(&|t| t.walk.displacement);
    let w = &tracks[i].walk;
    let numbers = format!(
        "{:.1} body sizes in {:.1} s, frames {}-{}",
        w.displacement, w.seconds, w.first_frame, w.last_frame
    );
    if w.displacement >= MIN_WALK {
        (
            i,
            format!("walker: the longest walk across the view ({numbers})"),
        )
    } else if w.displacement > 0.0 {
        (
            i,
            format!(
                "walker: nobody walks {MIN_WALK} body sizes or more; the person moving most across the view ({numbers})"
            ),
        )
    } else {
        let i = by(&|t| t.frames as f32);
        (
            i,
            "walker: nobody walks across the view; the longest track instead".into(),
        )
    }
}

/// The track whose box in `at.frame` is nearest `(at.x, at.y)`.
fn at_point(tracks: &[TrackSummary], at: PersonAt) -> Option<(usize, String)> {
    let (i, d) = tracks
        .iter()
        .enumerate()
        .filter_map(|(i, t)| {
            let b = t.box_at(at.frame)?;
            Some((i, (b.centre[0] - at.x).hypot(b.centre[1] - at.y)))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    Some((
        i,
        format!(
            "the person nearest ({}, {}) in frame {} ({d:.0} px from the body centre)",
            at.x, at.y, at.frame
        ),
    ))
}

fn serde_plain(rule: PersonRule) -> &'static str {
    match rule {
        PersonRule::Walker => "walker",
        PersonRule::Largest => "largest",
        PersonRule::Leftmost => "leftmost",
        PersonRule::Rightmost => "rightmost",
        PersonRule::MostCentral => "most_central",
        PersonRule::MostConfident => "most_confident",
    }
}
