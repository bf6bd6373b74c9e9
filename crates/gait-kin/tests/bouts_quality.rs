//! Walking bouts and per-stride quality control on the real trials: the three motion-capture
//! trials (whole recordings of steady walking) and BlazePose on the bundled sample video,
//! where the walker leaves the image and the tracker then follows another person.

use std::path::PathBuf;

use gait_core::PoseSequence;
use gait_kin::{Direction, KinResult, KinematicsConfig, PostprocessConfig, Side, analyse};

fn sequence(dir: &str, fps: f64) -> PoseSequence {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data")
        .join(dir)
        .join("keypoints.csv");
    gait_core::dlc::read(std::fs::File::open(p).expect("keypoints.csv"), None, fps).expect("CSV")
}

const MOCAP: [(&str, f64); 3] = [
    ("fukuchi2018", 150.0),
    ("gaitkit_pd", 150.0),
    ("gaitalytics_treadmill", 100.0),
];

fn report(name: &str, r: &KinResult) {
    println!("{name}: {} frames, bouts {:?}", r.n_frames, r.bouts);
    println!(
        "{name}: strides accepted {:?}, rejected {:?}",
        r.cycles_accepted, r.cycles_rejected
    );
    for q in &r.cycle_quality {
        println!(
            "{name}:   {} {}-{} accepted {} {:?} stride {:.3} s dev {:.3} gap {:.3} s lik {:.3} \
             thigh {:.3} shank {:.3} swapped {} bout {:?}",
            q.side.name(),
            q.first_frame,
            q.last_frame,
            q.accepted,
            q.reasons.iter().map(|r| r.name()).collect::<Vec<_>>(),
            q.stride_s,
            q.stride_deviation,
            q.max_filled_s,
            q.mean_likelihood,
            q.thigh_ratio,
            q.shank_ratio,
            q.swapped_frames,
            q.bout
        );
    }
    for w in &r.warnings {
        println!("{name}: warning: {w}");
    }
}

/// Every rejected stride says why, every accepted one has no reason, and the counts add up.
fn consistent(name: &str, r: &KinResult) {
    assert_eq!(r.cycle_quality.len(), r.strides.len(), "{name}");
    for q in &r.cycle_quality {
        assert_eq!(q.accepted, q.reasons.is_empty(), "{name}: {q:?}");
    }
    let total = r.cycles_accepted.left
        + r.cycles_accepted.right
        + r.cycles_rejected.left
        + r.cycles_rejected.right;
    assert_eq!(total, r.strides.len(), "{name}");
    for c in &r.cycles {
        let accepted = match c.side {
            Side::Left => r.cycles_accepted.left,
            Side::Right => r.cycles_accepted.right,
        };
        assert!(c.n_cycles <= accepted, "{name}: {c:?}");
    }
}

#[test]
fn motion_capture_trials_are_one_bout_and_keep_their_strides() {
    for (dir, fps) in MOCAP {
        let r = analyse(
            &sequence(dir, fps),
            &PostprocessConfig::default(),
            &KinematicsConfig::default(),
        )
        .unwrap();
        report(dir, &r);
        consistent(dir, &r);
        // Each recording is one steady walk to the image right (the treadmill's ground moves).
        assert_eq!(r.bouts.len(), 1, "{dir}: {:?}", r.bouts);
        let b = r.bouts[0];
        assert_eq!(b.direction, Direction::Right, "{dir}");
        let edge = (0.1 * fps) as usize;
        assert!(
            b.first <= edge && b.last + 1 + edge >= r.n_frames,
            "{dir}: {b:?}"
        );
        assert!(b.mean_speed > 0.5 && b.mean_speed < 2.5, "{dir}: {b:?}");
        // Clean marker data: no stride is rejected, and each side keeps its cycles.
        let rejected = r.cycle_quality.iter().filter(|q| !q.accepted).count();
        assert_eq!(rejected, 0, "{dir}");
        for side in Side::BOTH {
            let n = r.strides.iter().filter(|s| s.side == side).count();
            assert!(n >= 1, "{dir} {side:?}: no stride");
        }
    }
}

#[test]
fn parkinson_and_treadmill_keep_their_mean_curves() {
    for (dir, fps, min_per_side) in [
        ("gaitkit_pd", 150.0, 2),
        ("gaitalytics_treadmill", 100.0, 9),
    ] {
        let r = analyse(
            &sequence(dir, fps),
            &PostprocessConfig::default(),
            &KinematicsConfig::default(),
        )
        .unwrap();
        for side in Side::BOTH {
            let knee = r
                .cycles
                .iter()
                .find(|c| c.side == side && c.joint == "knee")
                .unwrap_or_else(|| panic!("{dir}: no {side:?} knee curve"));
            println!("{dir} {side:?}: {} knee cycles", knee.n_cycles);
            assert!(knee.n_cycles >= min_per_side, "{dir} {side:?}");
        }
    }
}

fn sample(kin: KinematicsConfig) -> KinResult {
    let seq = sequence("sample-blazepose", 30.0);
    analyse(&seq, &PostprocessConfig::default(), &kin).unwrap()
}

/// The walker leaves the image at about frame 194 and from about 200 the tracker follows a
/// second person (see tests/data/sample-blazepose/README.md): no bout and no accepted stride
/// may reach into those frames, and the accepted strides agree with each other.
#[test]
fn sample_video_bouts_stop_before_the_other_person() {
    for reject_swaps in [true, false] {
        let r = sample(KinematicsConfig {
            frame_size: Some([1768, 994]),
            cycle_max_swapped_share: if reject_swaps { 0.0 } else { 1.0 },
            ..Default::default()
        });
        let name = format!("sample-blazepose (reject swaps {reject_swaps})");
        report(&name, &r);
        consistent(&name, &r);
        assert!(!r.bouts.is_empty(), "{name}");
        assert!(
            r.bouts.iter().all(|b| b.last < 205),
            "{name}: {:?}",
            r.bouts
        );
        assert!(
            r.bouts.iter().all(|b| b.direction == Direction::Left),
            "{name}: the walker walks to the image left"
        );
        let accepted: Vec<_> = r.cycle_quality.iter().filter(|q| q.accepted).collect();
        assert!(accepted.iter().all(|q| q.last_frame < 200), "{name}");
        assert!(r.events.iter().all(|e| e.frame < 205), "{name}");
        let mut times: Vec<f64> = accepted.iter().map(|q| q.stride_s).collect();
        times.sort_by(f64::total_cmp);
        if let Some(&m) = times.get(times.len() / 2) {
            let med = if times.len().is_multiple_of(2) {
                (m + times[times.len() / 2 - 1]) / 2.0
            } else {
                m
            };
            for t in &times {
                assert!((t - med).abs() <= 0.2 * med, "{name}: {t} vs median {med}");
            }
        }
        if !reject_swaps {
            assert!(!accepted.is_empty(), "{name}: some stride is accepted");
        }
    }
}

/// Without the frame size the edge rule cannot apply, but the tracker's jump to the other
/// person and that person's short run still keep the bouts on the walker.
#[test]
fn sample_video_without_frame_size() {
    let r = sample(KinematicsConfig::default());
    report("sample-blazepose (no frame size)", &r);
    consistent("sample-blazepose (no frame size)", &r);
    assert!(r.bouts.iter().all(|b| b.last < 205), "{:?}", r.bouts);
}

#[test]
fn bouts_and_quality_are_written_and_serialised() {
    let r = sample(KinematicsConfig {
        frame_size: Some([1768, 994]),
        ..Default::default()
    });
    let dir = tempfile::tempdir().unwrap();
    gait_kin::write_outputs(&r, dir.path()).unwrap();
    let read = |n: &str| std::fs::read_to_string(dir.path().join(n)).unwrap();
    let bouts = read("bouts.csv");
    assert!(
        bouts.starts_with("bout,first,last,direction,mean_speed\n0,"),
        "{bouts}"
    );
    assert_eq!(bouts.lines().count(), 1 + r.bouts.len());
    let q = read("cycle_quality.csv");
    assert!(
        q.starts_with(
            "side,first_frame,last_frame,accepted,reasons,stride_s,stride_deviation,\
             max_filled_s,mean_likelihood,thigh_ratio,shank_ratio,leg_px,blur_px,swing_contrast,\
             swapped_frames,unsure_frames,bout\n"
        ),
        "{q}"
    );
    assert_eq!(q.lines().count(), 1 + r.cycle_quality.len());
    let json = serde_json::to_value(&r).unwrap();
    assert!(json["bouts"][0]["direction"] == "left", "{}", json["bouts"]);
    assert!(json["cycle_quality"].is_array() && json["cycles_accepted"]["left"].is_u64());
}
