//! The corrections at their places in the analysis chain (called from `crate::analyse_with`).

use std::path::Path;

use super::format::{error, event_entry};
use super::{Corrections, CorrectionsSummary, EventAction, FrameRange, REMOVE_WITHIN_FRAMES};
use crate::KinError;
use crate::events::{self, Event};
use crate::swap::swap_frame;
use crate::tracks::Tracks;

/// Timeline indices of `r` in `t` (clipped to it).
fn timeline(t: &Tracks, r: &FrameRange) -> std::ops::Range<usize> {
    let a = r.first.saturating_sub(t.first_frame).min(t.len());
    let b = (r.last + 1).saturating_sub(t.first_frame).min(t.len());
    a..b.max(a)
}

/// `[[swap]]`, after the automatic swap correction: exchanges the leg labels over each range in
/// `t` and in `raw` (the copy before the gate, whose likelihoods the quality rules read).
///
/// A person's swap is a confirmed fix, not a sign of unsure labels: the automatic correction's
/// verdicts per timeline frame (exchanged, and in doubt, which `cycle_max_swapped_share`
/// judges strides by) are cleared over the range, also where the automatic correction had
/// exchanged the labels, since the labels there are now the person's.
pub(crate) fn apply_swaps(
    c: &Corrections,
    t: &mut Tracks,
    raw: &mut Tracks,
    verdicts: [&mut [bool]; 2],
) {
    for r in &c.swap {
        for i in timeline(t, r) {
            swap_frame(t, i);
            swap_frame(raw, i);
        }
    }
    for flags in verdicts {
        for r in &c.swap {
            for i in timeline(t, r) {
                flags[i] = false;
            }
        }
    }
}

/// `[[keypoint]]`: sets each keypoint to (x, y) with likelihood 1 in `t` and `raw`. Called after
/// both swap corrections, so the name is the keypoint's label in the output.
pub(crate) fn apply_keypoints(c: &Corrections, t: &mut Tracks, raw: &mut Tracks) {
    for p in &c.keypoint {
        let (Some(j), Some(i)) = (
            t.index(&p.name),
            p.frame.checked_sub(t.first_frame).filter(|&i| i < t.len()),
        ) else {
            continue;
        };
        for tr in [&mut *t, &mut *raw] {
            tr.x[j][i] = p.x;
            tr.y[j][i] = p.y;
            tr.likelihood[j][i] = 1.0;
        }
    }
}

/// `[[event]]` and `[[exclude]]` on the events left after detection and the bout filter:
/// removals (the nearest event of that side and kind within [`REMOVE_WITHIN_FRAMES`], in the
/// file's order), then events in excluded frames dropped, then additions (kept wherever they
/// are; one that is already there is not doubled). The events end sorted by frame. `path` names
/// the file in the error of a removal that finds nothing.
pub(crate) fn apply_events(
    c: &Corrections,
    events: &mut Vec<Event>,
    path: &Path,
) -> Result<(), KinError> {
    for (k, e) in c.event.iter().enumerate() {
        if e.action != EventAction::Remove {
            continue;
        }
        let nearest = events
            .iter()
            .enumerate()
            .filter(|(_, x)| x.side == e.side && x.event == e.kind)
            .min_by_key(|(_, x)| (x.frame.abs_diff(e.frame), x.frame))
            .map(|(i, x)| (i, x.frame));
        match nearest {
            Some((i, f)) if f.abs_diff(e.frame) <= REMOVE_WITHIN_FRAMES => {
                events.remove(i);
            }
            other => {
                let nearest = match other {
                    Some((_, f)) => format!("the nearest is at frame {f}"),
                    None => "there is none".into(),
                };
                return Err(error(
                    path,
                    format!(
                        "{}: no {} {} within {REMOVE_WITHIN_FRAMES} frames to remove ({nearest})",
                        event_entry(k, e),
                        e.side.name(),
                        e.kind.name()
                    ),
                ));
            }
        }
    }
    events.retain(|x| !c.exclude.iter().any(|r| r.contains(x.frame)));
    events.extend(
        c.event
            .iter()
            .filter(|e| e.action == EventAction::Add)
            .map(|e| Event::on_frame(e.side, e.kind, e.frame)),
    );
    events::sort(events);
    // An added event where one was detected keeps the detected one (sorted first).
    events.dedup_by_key(|e| e.key());
    Ok(())
}

/// Whether input frames `first..=last` share a frame with an `[[exclude]]` range.
pub(crate) fn excluded_overlap(excluded: &[FrameRange], first: usize, last: usize) -> bool {
    excluded.iter().any(|r| r.overlaps(first, last))
}

/// Frames in the union of `ranges`.
fn union_frames(ranges: &[FrameRange]) -> usize {
    let mut sorted = ranges.to_vec();
    sorted.sort_by_key(|r| r.first);
    let (mut total, mut next) = (0, 0);
    for r in sorted {
        let from = r.first.max(next);
        if r.last >= from {
            total += r.last - from + 1;
            next = r.last + 1;
        }
    }
    total
}

pub(crate) fn summary(c: &Corrections, path: &Path, sha256: String) -> CorrectionsSummary {
    let actions = |a: EventAction| c.event.iter().filter(|e| e.action == a).count();
    CorrectionsSummary {
        path: path.to_path_buf(),
        sha256,
        swaps: c.swap.len(),
        swapped_frames: union_frames(&c.swap),
        events_added: actions(EventAction::Add),
        events_removed: actions(EventAction::Remove),
        excludes: c.exclude.len(),
        excluded_frames: union_frames(&c.exclude),
        keypoints: c.keypoint.len(),
    }
}

/// `corrections applied from corrections.toml: 1 swap (12 frames), 1 event added, 1 removed,
/// 1 exclude (44 frames), 1 keypoint`; tables without entries are left out.
pub(crate) fn warning(s: &CorrectionsSummary) -> String {
    let n = |k: usize, one: &str| {
        if k == 1 {
            format!("1 {one}")
        } else {
            format!("{k} {one}s")
        }
    };
    let frames = |k: usize| {
        if k == 1 {
            "1 frame".into()
        } else {
            format!("{k} frames")
        }
    };
    let mut parts = Vec::new();
    if s.swaps > 0 {
        parts.push(format!(
            "{} ({})",
            n(s.swaps, "swap"),
            frames(s.swapped_frames)
        ));
    }
    match (s.events_added, s.events_removed) {
        (0, 0) => {}
        (a, 0) => parts.push(format!("{} added", n(a, "event"))),
        (0, r) => parts.push(format!("{} removed", n(r, "event"))),
        (a, r) => parts.push(format!("{} added, {r} removed", n(a, "event"))),
    }
    if s.excludes > 0 {
        parts.push(format!(
            "{} ({})",
            n(s.excludes, "exclude"),
            frames(s.excluded_frames)
        ));
    }
    if s.keypoints > 0 {
        parts.push(n(s.keypoints, "keypoint"));
    }
    let what = if parts.is_empty() {
        "nothing to apply".into()
    } else {
        parts.join(", ")
    };
    format!("corrections applied from {}: {what}", s.path.display())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Side;
    use crate::events::EventKind;
    use crate::testing;
    use crate::tracks::LEG;

    fn ev(side: Side, event: EventKind, frame: usize) -> Event {
        Event::on_frame(side, event, frame)
    }

    fn edit(
        side: Side,
        kind: EventKind,
        frame: usize,
        action: EventAction,
    ) -> super::super::EventEdit {
        super::super::EventEdit {
            side,
            kind,
            frame,
            action,
        }
    }

    fn range(first: usize, last: usize) -> FrameRange {
        FrameRange { first, last }
    }

    #[test]
    fn swaps_exchange_both_copies_and_clear_the_automatic_verdict() {
        let clean = testing::walker(30.0, 60, |i| 100.0 + 13.0 * i as f64);
        let (mut t, mut raw) = (clean.clone(), clean.clone());
        let lk = raw.index("left_knee").unwrap();
        raw.likelihood[lk][12] = 0.3;
        let mut swapped = vec![false; 60];
        swapped[11] = true;
        swapped[30] = true;
        let c = Corrections {
            swap: vec![range(10, 12)],
            ..Default::default()
        };
        let mut unsure = swapped.clone();
        unsure[12] = false;
        unsure[40] = true;
        apply_swaps(&c, &mut t, &mut raw, [&mut swapped, &mut unsure]);
        for p in LEG {
            let (l, r) = (
                t.leg_index(Side::Left, p).unwrap(),
                t.leg_index(Side::Right, p).unwrap(),
            );
            for i in 0..60 {
                let (a, b) = if (10..=12).contains(&i) {
                    (r, l)
                } else {
                    (l, r)
                };
                assert_eq!((t.x[a][i], t.y[a][i]), (clean.x[l][i], clean.y[l][i]));
                assert_eq!((t.x[b][i], t.y[b][i]), (clean.x[r][i], clean.y[r][i]));
            }
        }
        let rk = raw.index("right_knee").unwrap();
        assert_eq!((raw.likelihood[rk][12], raw.likelihood[lk][12]), (0.3, 1.0));
        let mid = t.index("mid_hip").unwrap();
        assert_eq!(t.x[mid], clean.x[mid]);
        // A person's swap is a confirmed fix: no longer "swapped" for the cycle quality.
        let flagged = |v: &[bool]| (0..60).filter(|&i| v[i]).collect::<Vec<usize>>();
        assert_eq!(flagged(&swapped), vec![30]);
        assert_eq!(flagged(&unsure), vec![30, 40]);
    }

    #[test]
    fn keypoints_are_set_with_likelihood_one() {
        let mut t = testing::walker(30.0, 60, |i| 100.0 + 13.0 * i as f64);
        t.first_frame = 100;
        let j = t.index("right_ankle").unwrap();
        t.x[j][40] = f64::NAN;
        t.likelihood[j][40] = 0.0;
        let mut raw = t.clone();
        let c = Corrections {
            keypoint: vec![super::super::KeypointEdit {
                frame: 140,
                name: "right_ankle".into(),
                x: 812.5,
                y: 901.0,
            }],
            ..Default::default()
        };
        let before = t.clone();
        apply_keypoints(&c, &mut t, &mut raw);
        for tr in [&t, &raw] {
            assert_eq!(tr.at(j, 40), Some((812.5, 901.0)));
            assert_eq!(tr.likelihood[j][40], 1.0);
        }
        assert_eq!(t.at(j, 39), before.at(j, 39));
    }

    #[test]
    fn event_edits_remove_exclude_add_and_sort() {
        use EventAction::{Add, Remove};
        use EventKind::{HeelStrike as Hs, ToeOff as To};
        use Side::{Left as L, Right as R};
        let detected = vec![
            ev(L, Hs, 10),
            ev(R, To, 14),
            ev(R, Hs, 28),
            ev(L, To, 32),
            ev(L, Hs, 46),
            ev(R, To, 50),
            ev(R, Hs, 64),
        ];
        let c = Corrections {
            event: vec![
                edit(L, Hs, 49, Remove), // 46 is 3 frames away: removed
                edit(R, Hs, 5, Add),     // outside everything: kept
                edit(R, To, 14, Add),    // already there: not doubled
                edit(L, To, 20, Add),
            ],
            exclude: vec![range(60, 70)], // drops the right heel strike at 64
            ..Default::default()
        };
        let mut e = detected.clone();
        apply_events(&c, &mut e, Path::new("c.toml")).unwrap();
        assert_eq!(
            e,
            vec![
                ev(R, Hs, 5),
                ev(L, Hs, 10),
                ev(R, To, 14),
                ev(L, To, 20),
                ev(R, Hs, 28),
                ev(L, To, 32),
                ev(R, To, 50),
            ]
        );

        // The nearest of that side and kind only, the earlier one on a tie.
        let c = Corrections {
            event: vec![edit(R, Hs, 46, Remove)],
            ..Default::default()
        };
        let mut e = vec![ev(R, Hs, 44), ev(L, Hs, 46), ev(R, Hs, 48)];
        apply_events(&c, &mut e, Path::new("c.toml")).unwrap();
        assert_eq!(e, vec![ev(L, Hs, 46), ev(R, Hs, 48)]);

        // Nothing within 3 frames: an error naming the entry.
        let c = Corrections {
            event: vec![edit(L, Hs, 10, Remove), edit(R, To, 18, Remove)],
            ..Default::default()
        };
        let mut e = detected.clone();
        let err = apply_events(&c, &mut e, Path::new("c.toml"))
            .unwrap_err()
            .to_string();
        assert_eq!(
            err,
            "c.toml: [[event]] #2 (remove right toe_off at frame 18): no right toe_off within 3 frames to remove (the nearest is at frame 14)"
        );
        let mut none = Vec::new();
        let err = apply_events(&c, &mut none, Path::new("c.toml"))
            .unwrap_err()
            .to_string();
        assert!(err.ends_with("(there is none)"), "{err}");
    }

    #[test]
    fn summary_and_warning() {
        let c = Corrections {
            swap: vec![range(120, 131)],
            event: vec![
                edit(Side::Left, EventKind::HeelStrike, 152, EventAction::Add),
                edit(Side::Left, EventKind::ToeOff, 160, EventAction::Remove),
            ],
            exclude: vec![range(186, 229), range(200, 209), range(190, 230)],
            keypoint: vec![super::super::KeypointEdit {
                frame: 140,
                name: "right_ankle".into(),
                x: 1.0,
                y: 2.0,
            }],
        };
        let s = summary(&c, Path::new("corrections.toml"), "ab".into());
        assert_eq!((s.swaps, s.swapped_frames), (1, 12));
        assert_eq!((s.events_added, s.events_removed), (1, 1));
        assert_eq!((s.excludes, s.excluded_frames, s.keypoints), (3, 45, 1));
        assert_eq!(
            warning(&s),
            "corrections applied from corrections.toml: 1 swap (12 frames), 1 event added, \
             1 removed, 3 excludes (45 frames), 1 keypoint"
        );
        let s = summary(&Corrections::default(), Path::new("c.toml"), String::new());
        assert_eq!(
            warning(&s),
            "corrections applied from c.toml: nothing to apply"
        );
        assert_eq!(union_frames(&[range(5, 5), range(1, 3), range(2, 4)]), 5);
    }
}
