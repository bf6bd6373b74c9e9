//! Tests of the analysis chain (`analyse`) on synthetic walkers.

use super::*;

/// Walk 3 s, stand 2 s, walk 3 s: two bouts, events only inside them, and no accepted
/// stride across the standing.
#[test]
fn events_and_cycles_stay_inside_the_bouts() {
    let pos = |i: usize| {
        let moving = i.min(90) + i.saturating_sub(150);
        100.0 + 400.0 * moving as f64 / 30.0
    };
    let seq = testing::walker(30.0, 240, pos).to_sequence();
    let kin = KinematicsConfig::default();
    let r = analyse(&seq, &PostprocessConfig::default(), &kin).unwrap();
    assert_eq!(r.bouts.len(), 2, "{:?}", r.bouts);
    assert!(
        r.bouts[0].last < 100 && r.bouts[1].first > 140,
        "{:?}",
        r.bouts
    );
    assert!(!r.events.is_empty());
    assert!(
        r.events
            .iter()
            .all(|e| bouts::bout_of(&r.bouts, e.frame).is_some())
    );
    for q in &r.cycle_quality {
        assert_eq!(q.accepted, q.bout.is_some(), "{q:?}");
    }
    assert!(
        r.cycles_accepted.left >= 2 && r.cycles_accepted.right >= 2,
        "{r:?}"
    );
    assert_eq!(r.cycles.len(), 6);

    // Standing only: no bout, no events, and the warning says so.
    let still = testing::walker(30.0, 90, |_| 500.0).to_sequence();
    let r = analyse(&still, &PostprocessConfig::default(), &kin).unwrap();
    assert!(r.bouts.is_empty() && r.events.is_empty() && r.cycle_quality.is_empty());
    assert!(
        r.warnings
            .iter()
            .any(|w| w == "no walking bout found: no events or cycles"),
        "{:?}",
        r.warnings
    );
}

/// The pose model drawing both legs on one leg right at the right foot's toe-offs (where
/// BlazePose did it on the sample): the frames are dropped and filled, no label is
/// "corrected", and every event stays within a frame of where it was.
#[test]
fn collapses_at_toe_off_leave_the_events() {
    let clean = testing::walker(30.0, 180, |i| 100.0 + 13.0 * i as f64);
    let (post, kin) = (PostprocessConfig::default(), KinematicsConfig::default());
    let before = analyse(&clean.to_sequence(), &post, &kin).unwrap();
    let toe_offs: Vec<usize> = before
        .events
        .iter()
        .filter(|e| e.side == Side::Right && e.event == EventKind::ToeOff)
        .map(|e| e.frame)
        .collect();
    assert!(toe_offs.len() >= 3, "{:?}", before.events);
    let mut t = clean.clone();
    for &f in &toe_offs {
        for p in tracks::LOWER_LEG {
            let (l, r) = (
                t.leg_index(Side::Left, p).unwrap(),
                t.leg_index(Side::Right, p).unwrap(),
            );
            t.x[r][f] = t.x[l][f] + 6.0;
            t.y[r][f] = t.y[l][f] - 4.0;
        }
    }
    let after = analyse(&t.to_sequence(), &post, &kin).unwrap();
    assert_eq!(after.collapsed_frames, toe_offs.len());
    assert_eq!(after.swapped_frames, 0);
    assert_eq!(
        after.events.len(),
        before.events.len(),
        "{:?}",
        after.events
    );
    for (a, b) in before.events.iter().zip(&after.events) {
        assert!(
            a.side == b.side && a.event == b.event && a.frame.abs_diff(b.frame) <= 1,
            "{a:?} vs {b:?}"
        );
    }
    assert_eq!(after.cycles_accepted, before.cycles_accepted);
}

/// Writes `text` as a corrections file in `dir` and returns the config that applies it.
fn with_corrections(dir: &std::path::Path, text: &str) -> KinematicsConfig {
    let p = dir.join("corrections.toml");
    std::fs::write(&p, text).unwrap();
    KinematicsConfig {
        corrections: Some(p),
        ..Default::default()
    }
}

/// No smoothing: every cleaned sample of a fully seen frame is the input's own.
fn unsmoothed() -> PostprocessConfig {
    PostprocessConfig {
        filter: FilterKind::None,
        ..Default::default()
    }
}

/// The leg keypoint indices `[left, right]` of each leg part.
fn leg_pairs(t: &Tracks) -> Vec<[usize; 2]> {
    tracks::LEG
        .iter()
        .map(|p| {
            [
                t.leg_index(Side::Left, p).unwrap(),
                t.leg_index(Side::Right, p).unwrap(),
            ]
        })
        .collect()
}

/// A person's swap comes after the automatic correction, which cannot undo it, and does not
/// count against the cycle quality; where the automatic correction had exchanged the labels
/// a person's swap gives the model's labels back, and those frames no longer count either.
#[test]
fn swaps_by_hand_come_last_and_do_not_reject_strides() {
    let walker = testing::walker(30.0, 180, |i| 100.0 + 13.0 * i as f64);
    let dir = tempfile::tempdir().unwrap();
    let kin = with_corrections(dir.path(), "[[swap]]\nfirst = 60\nlast = 67\n");
    let post = unsmoothed();
    let r = analyse(&walker.to_sequence(), &post, &kin).unwrap();
    let f = Tracks::from_sequence(&r.filtered);
    for [l, rt] in leg_pairs(&walker) {
        for i in 0..180 {
            let (a, b) = if (60..=67).contains(&i) {
                (rt, l)
            } else {
                (l, rt)
            };
            assert_eq!(f.at(a, i), walker.at(l, i), "frame {i}");
            assert_eq!(f.at(b, i), walker.at(rt, i), "frame {i}");
        }
    }
    assert_eq!(r.swapped_frames, 0);
    let over: Vec<&CycleQuality> = r
        .cycle_quality
        .iter()
        .filter(|q| q.first_frame <= 67 && 60 <= q.last_frame)
        .collect();
    assert!(!over.is_empty());
    // 8 swapped frames in a 34-frame stride would be over cycle_max_swapped_share (0.1).
    assert!(
        over.iter()
            .all(|q| q.swapped_frames == 0 && !q.reasons.contains(&Reason::Swap)),
        "{over:?}"
    );
    let s = r.corrections.as_ref().unwrap();
    assert_eq!(
        (s.swaps, s.swapped_frames, s.path.clone()),
        (1, 8, dir.path().join("corrections.toml"))
    );
    assert_eq!(
        r.warnings[0],
        format!(
            "corrections applied from {}: 1 swap (8 frames)",
            s.path.display()
        )
    );

    // The model exchanged the labels over 60-67: the automatic correction undoes it, sure of
    // it (continuity leaves no doubt), so the strides over it are kept; a person who says the
    // model was right gets the model's labels.
    let mut exchanged = walker.clone();
    for i in 60..=67 {
        swap::swap_frame(&mut exchanged, i);
    }
    let seq = exchanged.to_sequence();
    let auto = analyse(&seq, &post, &KinematicsConfig::default()).unwrap();
    assert_eq!(auto.swapped_frames, 8);
    let over = |r: &KinResult| {
        r.cycle_quality
            .iter()
            .filter(|q| q.first_frame <= 67 && 60 <= q.last_frame)
            .map(|q| (q.swapped_frames, q.unsure_frames, q.accepted))
            .collect::<Vec<_>>()
    };
    assert_eq!(over(&auto), vec![(8, 0, true); 2]);
    let fixed = analyse(&seq, &post, &kin).unwrap();
    assert_eq!(fixed.swapped_frames, 0);
    assert!(
        fixed
            .cycle_quality
            .iter()
            .all(|q| !q.reasons.contains(&Reason::Swap))
    );
    let f = Tracks::from_sequence(&fixed.filtered);
    for [l, rt] in leg_pairs(&walker) {
        for i in 60..=67 {
            assert_eq!(
                (f.at(l, i), f.at(rt, i)),
                (exchanged.at(l, i), exchanged.at(rt, i))
            );
        }
    }
}

/// A keypoint set by hand is in the output's labels, with likelihood 1, before gap filling
/// (a gap of the model's is filled around it) and smoothing.
#[test]
fn keypoints_by_hand_replace_the_models() {
    let mut walker = testing::walker(30.0, 120, |i| 100.0 + 13.0 * i as f64);
    let ankle = walker.index("right_ankle").unwrap();
    for i in 48..=52 {
        walker.likelihood[ankle][i] = 0.1;
    }
    let dir = tempfile::tempdir().unwrap();
    let kin = with_corrections(
        dir.path(),
        "[[keypoint]]\nframe = 50\nname = \"right_ankle\"\nx = 812.5\ny = 601.0\n",
    );
    let r = analyse(&walker.to_sequence(), &unsmoothed(), &kin).unwrap();
    let f = Tracks::from_sequence(&r.filtered);
    assert_eq!(f.at(ankle, 50), Some((812.5, 601.0)));
    assert_eq!(f.likelihood[ankle][50], 1.0);
    // The gated frames either side are filled, now through the person's point.
    let before = analyse(
        &walker.to_sequence(),
        &unsmoothed(),
        &KinematicsConfig::default(),
    )
    .unwrap();
    let b = Tracks::from_sequence(&before.filtered);
    assert!(f.at(ankle, 49).is_some() && f.at(ankle, 49) != b.at(ankle, 49));
    assert_eq!(f.at(ankle, 20), b.at(ankle, 20));
    assert_eq!(r.corrections.as_ref().unwrap().keypoints, 1);
}

/// Walk 3 s, then stand: events removed, added (also where nobody walks) and excluded
/// exactly as written, and strides over excluded frames rejected.
#[test]
fn events_by_hand_and_excluded_frames() {
    let pos = |i: usize| 100.0 + 400.0 * i.min(150) as f64 / 30.0;
    let seq = testing::walker(30.0, 200, pos).to_sequence();
    let post = PostprocessConfig::default();
    let before = analyse(&seq, &post, &KinematicsConfig::default()).unwrap();
    let hs = |r: &KinResult, side: Side| -> Vec<usize> {
        r.events
            .iter()
            .filter(|e| e.side == side && e.event == EventKind::HeelStrike)
            .map(|e| e.frame)
            .collect()
    };
    let left = hs(&before, Side::Left);
    assert!(left.len() >= 4, "{:?}", before.events);
    assert!(before.bouts.iter().all(|b| !b.contains(190)));
    // Remove the second left heel strike (named 2 frames late), exclude the third one's
    // frame, add a right toe-off at 190 where she stands.
    let (second, third) = (left[1], left[2]);
    let text = format!(
        "[[event]]\nside = \"left\"\nkind = \"heel_strike\"\nframe = {}\naction = \"remove\"\n\
         [[event]]\nside = \"right\"\nkind = \"toe_off\"\nframe = 190\naction = \"add\"\n\
         [[exclude]]\nfirst = {third}\nlast = {third}\n",
        second + 2
    );
    let dir = tempfile::tempdir().unwrap();
    let kin = with_corrections(dir.path(), &text);
    let r = analyse(&seq, &post, &kin).unwrap();
    let mut expect: Vec<Event> = before
        .events
        .iter()
        .copied()
        .filter(|e| {
            !(e.side == Side::Left && e.event == EventKind::HeelStrike && e.frame == second)
                && e.frame != third
        })
        .collect();
    expect.push(Event::on_frame(Side::Right, EventKind::ToeOff, 190));
    events::sort(&mut expect);
    assert_eq!(r.events, expect);
    // The left strides now run first -> fourth heel strike (too long: no candidate) and
    // fourth -> fifth; every stride over the excluded frame is rejected for it.
    for q in &r.cycle_quality {
        let over = (q.first_frame..=q.last_frame).contains(&third);
        assert_eq!(q.reasons.contains(&Reason::Excluded), over, "{q:?}");
    }
    assert!(
        r.cycle_quality
            .iter()
            .any(|q| q.reasons.contains(&Reason::Excluded))
    );
    assert!(
        !r.cycle_quality
            .iter()
            .any(|q| q.side == Side::Left && q.first_frame == second)
    );

    // A removal that finds nothing stops the analysis, naming the file and the entry.
    let kin = with_corrections(
        dir.path(),
        "[[event]]\nside = \"left\"\nkind = \"toe_off\"\nframe = 195\naction = \"remove\"\n",
    );
    let e = analyse(&seq, &post, &kin).unwrap_err().to_string();
    assert!(
        e.starts_with(&format!(
            "{}: [[event]] #1 (remove left toe_off at frame 195): no left toe_off within 3 frames to remove",
            dir.path().join("corrections.toml").display()
        )),
        "{e}"
    );
    // So does an invalid file.
    let kin = with_corrections(dir.path(), "[[swap]]\nfirst = 150\nlast = 250\n");
    let e = analyse(&seq, &post, &kin).unwrap_err().to_string();
    assert!(
        e.ends_with("[[swap]] #1 (frames 150-250): frame 250 is outside the run (frames 0-199)"),
        "{e}"
    );
}
