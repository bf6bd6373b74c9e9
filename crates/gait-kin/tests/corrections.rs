//! Corrections (`gait_kin::corrections`) on real pose output: BlazePose on the whole sample
//! video, subject-tracked (tests/data/sample-subject: frames 59-192 hold the walker, 30 fps),
//! analysed without and with a corrections file; the effects must be exactly the ones asked.

use std::path::{Path, PathBuf};

use gait_core::{Keypoint, PoseSequence};
use gait_kin::{
    CollapseRule, ContinuitySwap, Corrections, Event, EventAction, EventEdit, EventKind,
    FilterKind, FrameRange, KeypointEdit, KeypointGate, KinResult, KinematicsConfig,
    LikelihoodThreshold, PostprocessConfig, Reason, Side, Tracks, analyse,
};
use sha2::{Digest, Sha256};

fn sequence() -> PoseSequence {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data/sample-subject/keypoints.csv");
    let f = std::fs::File::open(path).expect("keypoints.csv");
    gait_core::dlc::read(f, None, 30.0).expect("DeepLabCut CSV")
}

/// What `gait run` does with the sample: the video's frame size, and `corrections` when given.
fn kin(corrections: Option<&Path>) -> KinematicsConfig {
    KinematicsConfig {
        frame_size: Some([1768, 994]),
        corrections: corrections.map(Path::to_path_buf),
        ..Default::default()
    }
}

/// Writes `c` as the file a person or a script would, and returns its path.
fn write(dir: &Path, c: &Corrections) -> PathBuf {
    let p = dir.join("corrections.toml");
    std::fs::write(&p, c.to_toml()).unwrap();
    assert_eq!(&Corrections::read(&p).unwrap(), c);
    p
}

fn event(side: Side, kind: EventKind, frame: usize, action: EventAction) -> EventEdit {
    EventEdit {
        side,
        kind,
        frame,
        action,
    }
}

fn ranges(r: &KinResult) -> Vec<(Side, usize, usize)> {
    let mut v: Vec<_> = r.strides.iter().map(|s| (s.side, s.start, s.end)).collect();
    v.sort_by_key(|s| (s.0 == Side::Right, s.1));
    v
}

/// Events and excluded frames with the default settings. The corrections are those a person
/// would make against the manual annotation (tests/data/sample-events): the right heel strike
/// at 60, one frame after her pose starts, that no detector can find; the right toe-off found
/// at 121 that the annotation has at 123; the frames 155-163 where BlazePose drew both legs on
/// one and exchanged them; and the frames from 186 where she leaves.
#[test]
fn events_and_excluded_frames_change_exactly_as_asked() {
    let seq = sequence();
    let post = PostprocessConfig::default();
    let before = analyse(&seq, &post, &kin(None)).unwrap();
    let has = |side, kind, frame| before.events.iter().any(|e| e.key() == (side, kind, frame));
    // What the corrections are written against.
    assert!(has(Side::Right, EventKind::ToeOff, 121) && has(Side::Right, EventKind::ToeOff, 158));
    assert!(!before.events.iter().any(|e| e.frame < 65));
    let right_134 = (Side::Right, 134, 171);
    assert!(
        ranges(&before).contains(&right_134),
        "{:?}",
        ranges(&before)
    );

    let c = Corrections {
        event: vec![
            event(Side::Right, EventKind::HeelStrike, 60, EventAction::Add),
            event(Side::Right, EventKind::ToeOff, 123, EventAction::Remove),
            event(Side::Right, EventKind::ToeOff, 123, EventAction::Add),
        ],
        exclude: vec![
            FrameRange {
                first: 155,
                last: 163,
            },
            FrameRange {
                first: 186,
                last: 229,
            },
        ],
        ..Default::default()
    };
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), &c);
    let after = analyse(&seq, &post, &kin(Some(&path))).unwrap();

    // The events: exactly the automatic ones, less the removed toe-off at 121 and those in
    // excluded frames (the right toe-off at 158), plus the two added.
    let mut expect: Vec<Event> = before
        .events
        .iter()
        .copied()
        .filter(|e| e.frame != 121 && !(155..=163).contains(&e.frame) && e.frame < 186)
        .collect();
    assert_eq!(expect.len(), before.events.len() - 2);
    expect.push(Event::on_frame(Side::Right, EventKind::HeelStrike, 60));
    expect.push(Event::on_frame(Side::Right, EventKind::ToeOff, 123));
    gait_kin::events::sort(&mut expect);
    assert_eq!(after.events, expect);

    // The strides: one more (from the added heel strike at 60); the one over 155-163 rejected
    // for that alone, every other one judged as before.
    let mut strides = ranges(&before);
    strides.insert(0, (Side::Right, 60, 99));
    strides.sort_by_key(|s| (s.0 == Side::Right, s.1));
    assert_eq!(ranges(&after), strides);
    for q in &after.cycle_quality {
        let key = (q.side, q.first_frame, q.last_frame);
        if key == right_134 {
            assert_eq!(q.reasons, vec![Reason::Excluded], "{q:?}");
            assert!(!q.accepted);
        } else if key.1 == 60 {
            assert!(q.accepted, "{q:?}");
        } else {
            let old = before
                .cycle_quality
                .iter()
                .find(|o| (o.side, o.first_frame, o.last_frame) == key)
                .unwrap();
            assert_eq!((q.accepted, &q.reasons), (old.accepted, &old.reasons));
        }
    }
    assert_eq!(
        after.cycles_rejected.right,
        before.cycles_rejected.right + 1
    );

    let s = after.corrections.as_ref().unwrap();
    let sha: String = Sha256::digest(std::fs::read(&path).unwrap())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    assert_eq!(s.sha256, sha);
    assert_eq!(
        (
            s.events_added,
            s.events_removed,
            s.excludes,
            s.excluded_frames
        ),
        (2, 1, 2, 53)
    );
    assert_eq!((s.swaps, s.keypoints), (0, 0));
    assert_eq!(
        after.warnings[0],
        format!(
            "corrections applied from {}: 2 events added, 1 removed, 2 excludes (53 frames)",
            path.display()
        )
    );
    assert!(before.corrections.is_none());
}

/// Angle samples equal, NaN included.
fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// A swap and a keypoint, without smoothing (`filter = "none"`) so that every cleaned sample at
/// a frame the pose model saw fully is its own (or the person's) and the effects are exact.
#[test]
fn a_swap_exchanges_the_legs_and_a_keypoint_is_set_exactly() {
    let seq = sequence();
    let post = PostprocessConfig {
        filter: FilterKind::None,
        ..Default::default()
    };
    let before = analyse(&seq, &post, &kin(None)).unwrap();
    let c = Corrections {
        swap: vec![FrameRange {
            first: 120,
            last: 131,
        }],
        keypoint: vec![KeypointEdit {
            frame: 140,
            name: "right_ankle".into(),
            x: 590.0,
            y: 904.0,
        }],
        ..Default::default()
    };
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), &c);
    c.validate(&seq).unwrap();
    let after = analyse(&seq, &post, &kin(Some(&path))).unwrap();

    // The frames whose leg keypoints the model all gave (likelihood >= 0.5, legs not drawn on
    // one), and the frames the automatic swap correction exchanged, as the analysis finds them.
    let mut t = Tracks::from_sequence(&seq);
    LikelihoodThreshold(post.likelihood_threshold).apply(&mut t);
    let collapsed = CollapseRule::default().find(&t);
    gait_kin::collapse::drop_frames(&mut t, &collapsed);
    let auto = ContinuitySwap::default().detect(&t);
    let f0 = t.first_frame;
    let legs: Vec<usize> = ["left", "right"]
        .iter()
        .flat_map(|s| gait_kin::tracks::LEG.map(|p| t.index(&format!("{s}_{p}")).unwrap()))
        .collect();
    let seen: Vec<usize> = (120..=131)
        .filter(|&f| legs.iter().all(|&j| t.at(j, f - f0).is_some()))
        .collect();
    assert!(seen.len() >= 10, "{seen:?}");

    // Directions stay; the angles at the swapped frames are the other leg's.
    assert_eq!(after.direction, before.direction);
    let (a, b) = (&after.angles, &before.angles);
    for f in seen {
        let i = f - after.first_frame;
        for (x, y) in [
            (&a.left.hip, &b.right.hip),
            (&a.left.knee, &b.right.knee),
            (&a.left.ankle, &b.right.ankle),
            (&a.right.hip, &b.left.hip),
            (&a.right.knee, &b.left.knee),
            (&a.right.ankle, &b.left.ankle),
        ] {
            assert!(
                same(x[i], y[i]) && x[i].is_finite(),
                "frame {f}: {} vs {}",
                x[i],
                y[i]
            );
        }
    }

    // The person's keypoint, with likelihood 1.
    let k = seq.index_of("right_ankle").unwrap();
    let at = |r: &KinResult| r.filtered.poses[140 - r.filtered.frames[0]].keypoints[k];
    assert_eq!(at(&after), Keypoint::new(590.0, 904.0, 1.0));
    assert_ne!(at(&before), at(&after));

    // A person's swap is a confirmed fix: only the automatic correction's frames count for the
    // cycle quality (12 swapped frames would reject any stride over them).
    assert_eq!(after.swapped_frames, before.swapped_frames);
    let over: Vec<_> = after
        .cycle_quality
        .iter()
        .filter(|q| q.first_frame <= 131 && 120 <= q.last_frame)
        .collect();
    assert!(!over.is_empty());
    for q in &after.cycle_quality {
        let expect = (q.first_frame..=q.last_frame)
            .filter(|&f| auto[f - f0] && !(120..=131).contains(&f))
            .count();
        assert_eq!(q.swapped_frames, expect, "{q:?}");
        assert!(!q.reasons.contains(&Reason::Swap), "{q:?}");
    }
    let s = after.corrections.unwrap();
    assert_eq!((s.swaps, s.swapped_frames, s.keypoints), (1, 12, 1));
}

/// The file is checked against the keypoints before anything runs.
#[test]
fn a_file_that_does_not_fit_the_keypoints_is_refused() {
    let seq = sequence();
    let dir = tempfile::tempdir().unwrap();
    let c = Corrections {
        keypoint: vec![KeypointEdit {
            frame: 140,
            name: "right_big_toe".into(),
            x: 1.0,
            y: 2.0,
        }],
        ..Default::default()
    };
    let path = write(dir.path(), &c);
    let e = analyse(&seq, &PostprocessConfig::default(), &kin(Some(&path)))
        .unwrap_err()
        .to_string();
    let want = format!(
        "{}: [[keypoint]] #1 (right_big_toe at frame 140): the input has no keypoint `right_big_toe`",
        path.display()
    );
    assert!(e.starts_with(&want), "{e}");
    let c = Corrections {
        event: vec![event(
            Side::Left,
            EventKind::HeelStrike,
            100,
            EventAction::Remove,
        )],
        ..Default::default()
    };
    let path = write(dir.path(), &c);
    let e = analyse(&seq, &PostprocessConfig::default(), &kin(Some(&path)))
        .unwrap_err()
        .to_string();
    assert!(
        e.ends_with(
            "[[event]] #1 (remove left heel_strike at frame 100): no left heel_strike within 3 frames to remove (the nearest is at frame 117)"
        ),
        "{e}"
    );
}

/// A review tool recomputes from corrections in memory before saving them: the result must be
/// the one `analyse` gives on the saved file, summary (path, sha256) included, and a bad set is
/// refused with the same message.
#[test]
fn corrections_in_memory_give_what_the_saved_file_gives() {
    let seq = sequence();
    let dir = tempfile::tempdir().unwrap();
    let c = Corrections {
        swap: vec![FrameRange {
            first: 155,
            last: 163,
        }],
        event: vec![event(
            Side::Right,
            EventKind::HeelStrike,
            60,
            EventAction::Add,
        )],
        exclude: vec![FrameRange {
            first: 186,
            last: 192,
        }],
        keypoint: vec![KeypointEdit {
            frame: 140,
            name: "right_ankle".into(),
            x: 812.5,
            y: 901.0,
        }],
    };
    let path = write(dir.path(), &c);
    let post = PostprocessConfig::default();
    let from_file = analyse(&seq, &post, &kin(Some(&path))).unwrap();
    let sha = gait_kin::corrections::sha256_hex(c.to_toml().as_bytes());
    let in_memory = gait_kin::analyse_corrected(&seq, &post, &kin(None), &c, &path, sha).unwrap();
    assert_eq!(
        serde_json::to_value(&in_memory).unwrap(),
        serde_json::to_value(&from_file).unwrap()
    );
    // Debug text compares the NaNs of undefined samples too.
    assert_eq!(
        format!("{:?}", in_memory.angles),
        format!("{:?}", from_file.angles)
    );
    assert_eq!(
        format!("{:?}", in_memory.filtered),
        format!("{:?}", from_file.filtered)
    );

    let mut bad = c.clone();
    bad.swap.push(FrameRange {
        first: 160,
        last: 170,
    });
    let path = write(dir.path(), &bad);
    let from_file = analyse(&seq, &post, &kin(Some(&path))).unwrap_err();
    let in_memory =
        gait_kin::analyse_corrected(&seq, &post, &kin(None), &bad, &path, String::new())
            .unwrap_err();
    assert_eq!(in_memory.to_string(), from_file.to_string());
    assert!(in_memory.to_string().contains("overlaps"), "{in_memory}");
}
