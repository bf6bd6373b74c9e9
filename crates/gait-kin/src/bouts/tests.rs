use super::*;
use crate::testing::walker;

fn bouts_of(t: &Tracks, kin: &KinematicsConfig) -> Vec<(usize, usize, Direction)> {
    let dirs = crate::direction::detect(t).per_frame;
    let f = Frames {
        clean: t,
        gated: t,
        dirs: &dirs,
        max_gap: 10,
    };
    find(&f, kin)
        .iter()
        .map(|b| (b.first, b.last, b.direction))
        .collect()
}

fn default_bouts(t: &Tracks) -> Vec<(usize, usize, Direction)> {
    bouts_of(t, &KinematicsConfig::default())
}

/// Pelvis x at 30 fps walking at 400 px/s (1.3 leg lengths/s) from x = 100.
fn steady(i: usize) -> f64 {
    100.0 + 400.0 * i as f64 / 30.0
}

#[test]
fn steady_walk_is_one_bout_and_standing_none() {
    let b = default_bouts(&walker(30.0, 120, steady));
    assert_eq!(b, vec![(0, 119, Direction::Right)]);
    assert!(default_bouts(&walker(30.0, 120, |_| 500.0)).is_empty());
    // Shuffling on the spot at 0.1 leg lengths/s is not walking either.
    assert!(default_bouts(&walker(30.0, 120, |i| 500.0 + i as f64)).is_empty());
}

#[test]
fn a_turn_splits_the_walk_into_two_bouts() {
    // 2 s right, slow down and turn over 1 s, 2 s back to the left.
    let pos = |i: usize| {
        let s = i as f64 / 30.0;
        if s < 2.0 {
            100.0 + 400.0 * s
        } else if s < 3.0 {
            900.0 + 400.0 * (s - 2.0) * (1.0 - (s - 2.0)) // up and back, speed through 0
        } else {
            900.0 - 400.0 * (s - 3.0)
        }
    };
    let b = default_bouts(&walker(30.0, 150, pos));
    assert_eq!(b.len(), 2, "{b:?}");
    assert_eq!((b[0].2, b[1].2), (Direction::Right, Direction::Left));
    assert!(
        b[0].0 == 0 && b[0].1 < 75 && b[1].0 > 75 && b[1].1 == 149,
        "{b:?}"
    );
}

#[test]
fn short_hidden_gaps_are_bridged_long_ones_split() {
    let mut t = walker(30.0, 120, steady);
    let k = t.index("left_knee").unwrap();
    for i in 50..58 {
        t.x[k][i] = f64::NAN;
    }
    assert_eq!(default_bouts(&t), vec![(0, 119, Direction::Right)]);
    for i in 50..62 {
        t.x[k][i] = f64::NAN;
    }
    assert_eq!(
        default_bouts(&t),
        vec![(0, 49, Direction::Right), (62, 119, Direction::Right)]
    );
    // A keypoint missing at the start is never filled: the person is not yet seen.
    let mut t = walker(30.0, 120, steady);
    let a = t.index("right_ankle").unwrap();
    t.x[a][..5].fill(f64::NAN);
    assert_eq!(default_bouts(&t), vec![(5, 119, Direction::Right)]);
}

#[test]
fn short_pauses_are_bridged_long_ones_end_the_bout() {
    let stop = |from: usize, len: usize| {
        move |i: usize| {
            let moving = i.min(from) + i.saturating_sub(from + len);
            100.0 + 400.0 * moving as f64 / 30.0
        }
    };
    let b = default_bouts(&walker(30.0, 150, stop(60, 3)));
    assert_eq!(b, vec![(0, 149, Direction::Right)]);
    let b = default_bouts(&walker(30.0, 150, stop(60, 30)));
    assert_eq!(b.len(), 2, "{b:?}");
    assert!(b[0].1 < 70 && b[1].0 > 80, "{b:?}");
}

#[test]
fn runs_shorter_than_the_minimum_are_dropped() {
    let t = walker(30.0, 120, steady);
    let kin = KinematicsConfig {
        bout_min_s: 5.0,
        ..Default::default()
    };
    assert!(bouts_of(&t, &kin).is_empty());
}

#[test]
fn leaving_the_image_ends_the_bout() {
    // Walking right across a 1280 px frame: the toe reaches 1280 - 0.01 * 1280 first.
    let t = walker(30.0, 120, steady);
    let kin = KinematicsConfig {
        frame_size: Some([1280, 720]),
        ..Default::default()
    };
    let b = bouts_of(&t, &kin);
    assert_eq!(b.len(), 1, "{b:?}");
    let toe = t.index("right_toe").unwrap();
    let last = b[0].1;
    let margin = kin.bout_edge_margin * 1280.0;
    assert!(t.x[toe][last] <= 1280.0 - margin, "{}", t.x[toe][last]);
    assert!((last + 1..120).any(|i| t.x[toe][i] > 1280.0 - margin));
    assert!(last < 100, "{b:?}");
}

/// A toe that brushes the bottom border for a frame in mid-walk (a pose model's outlier) is
/// still in view; one that stays there is not.
#[test]
fn a_brief_touch_of_the_border_is_no_exit() {
    let mut t = walker(30.0, 120, |i| steady(i) + 300.0);
    let bottom = t.y.iter().flatten().copied().fold(f64::MIN, f64::max) + 50.0;
    let kin = KinematicsConfig {
        frame_size: Some([4000, bottom as u32]),
        ..Default::default()
    };
    assert_eq!(bouts_of(&t, &kin), vec![(0, 119, Direction::Right)]);
    let toe = t.index("right_toe").unwrap();
    t.y[toe][60] = bottom - 1.0;
    assert_eq!(bouts_of(&t, &kin), vec![(0, 119, Direction::Right)]);
    for i in 50..90 {
        t.y[toe][i] = bottom - 1.0;
    }
    let b = bouts_of(&t, &kin);
    assert!(b.iter().all(|b| b.1 < 50 || b.0 >= 90), "{b:?}");
}

#[test]
fn a_tracker_jump_is_a_break() {
    // After 2 s the tracker picks up someone 800 px further on, walking the same way.
    let t = walker(30.0, 120, |i| steady(i) + if i >= 60 { 800.0 } else { 0.0 });
    assert_eq!(
        default_bouts(&t),
        vec![(0, 59, Direction::Right), (61, 119, Direction::Right)]
    );
}

#[test]
fn a_treadmill_walker_is_walking() {
    // The pelvis stays put; the belt carries the stance foot backwards.
    let t = crate::testing::treadmill(100.0, 400, 300.0);
    let b = default_bouts(&t);
    assert_eq!(b.len(), 1, "{b:?}");
    assert!(b[0].0 <= 5 && b[0].1 >= 394, "{b:?}");
}

#[test]
fn bouts_given_by_hand_replace_detection() {
    let t = walker(30.0, 120, |_| 500.0);
    let kin = KinematicsConfig {
        bouts: Some(vec![[60, 500], [10, 40]]),
        ..Default::default()
    };
    let dirs = crate::direction::detect(&t).per_frame;
    let f = Frames {
        clean: &t,
        gated: &t,
        dirs: &dirs,
        max_gap: 10,
    };
    let b = find(&f, &kin);
    assert_eq!(
        b.iter().map(|b| (b.first, b.last)).collect::<Vec<_>>(),
        vec![(10, 40), (60, 119)]
    );
    assert!(b.iter().all(|b| b.mean_speed.abs() < 0.01), "{b:?}");
    assert_eq!(bout_of(&b, 70), Some(1));
    assert_eq!(bout_of(&b, 50), None);
}

#[test]
fn speed_is_reported_in_leg_lengths_per_second() {
    let t = walker(30.0, 120, steady);
    let b = default_bouts(&t);
    let dirs = crate::direction::detect(&t).per_frame;
    let f = Frames {
        clean: &t,
        gated: &t,
        dirs: &dirs,
        max_gap: 10,
    };
    let speed = detect(&f, &KinematicsConfig::default())[0].mean_speed;
    let expect = 400.0 / t.leg_length();
    assert!(
        (speed - expect).abs() < 0.02 * expect,
        "{speed} vs {expect}"
    );
    assert_eq!(b.len(), 1);
}
