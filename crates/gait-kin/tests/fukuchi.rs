//! Real motion capture: Fukuchi et al. 2018 (CC-BY 4.0), one overground trial at 150 Hz, projected
//! onto the sagittal plane by tools/kin/derive_fukuchi.py (see tests/data/fukuchi2018/README.md).

mod rng;
use rng::Rng;

use std::path::PathBuf;

use gait_core::PoseSequence;
use gait_kin::events::EventKind;
use gait_kin::swap::{ContinuitySwap, swap_frame};
use gait_kin::{
    Direction, EventDetector, KinematicsConfig, PostprocessConfig, Side, Tracks, ZeniRefined,
    analyse,
};

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data/fukuchi2018")
        .join(name)
}

fn sequence() -> PoseSequence {
    let f = std::fs::File::open(data("keypoints.csv")).expect("keypoints.csv");
    gait_core::dlc::read(f, None, 150.0).expect("DeepLabCut CSV")
}

/// Rows of a CSV with a header, as strings.
fn csv_rows(name: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(data(name)).expect("csv");
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    (
        header,
        lines
            .map(|l| l.split(',').map(String::from).collect())
            .collect(),
    )
}

fn reference(column: &str) -> Vec<f64> {
    let (h, rows) = csv_rows("reference.csv");
    let c = h.iter().position(|x| x == column).unwrap();
    rows.iter().map(|r| r[c].parse().unwrap()).collect()
}

/// Annotated events of the file: (side, kind, frame).
fn annotated() -> Vec<(Side, EventKind, usize)> {
    let (_, rows) = csv_rows("events.csv");
    rows.iter()
        .map(|r| {
            let side = if r[0] == "left" {
                Side::Left
            } else {
                Side::Right
            };
            let kind = if r[1] == "heel_strike" {
                EventKind::HeelStrike
            } else {
                EventKind::ToeOff
            };
            (side, kind, r[2].parse().unwrap())
        })
        .collect()
}

const TOLERANCE: usize = 10;

/// Each annotated event against the nearest detected one of the same side and kind.
/// Returns (matched absolute errors, unmatched annotated frames).
fn match_events(detected: &[gait_kin::Event], kind: EventKind) -> (Vec<usize>, Vec<(Side, usize)>) {
    let mut errors = Vec::new();
    let mut missed = Vec::new();
    for (side, k, frame) in annotated() {
        if k != kind {
            continue;
        }
        let best = detected
            .iter()
            .filter(|e| e.side == side && e.event == kind)
            .map(|e| e.frame.abs_diff(frame))
            .min();
        match best {
            Some(d) if d <= TOLERANCE => errors.push(d),
            _ => missed.push((side, frame)),
        }
    }
    (errors, missed)
}

fn mean(v: &[usize]) -> f64 {
    v.iter().sum::<usize>() as f64 / v.len() as f64
}

#[test]
fn events_match_the_annotations() {
    let seq = sequence();
    let r = analyse(
        &seq,
        &PostprocessConfig::default(),
        &KinematicsConfig::default(),
    )
    .unwrap();
    let (hs, hs_missed) = match_events(&r.events, EventKind::HeelStrike);
    let (to, to_missed) = match_events(&r.events, EventKind::ToeOff);
    println!(
        "detected: {:?}",
        r.events
            .iter()
            .map(|e| (e.side.name(), e.event.name(), e.frame))
            .collect::<Vec<_>>()
    );
    println!(
        "heel strike |error| frames {hs:?} mean {:.2}; unmatched annotations {hs_missed:?}",
        mean(&hs)
    );
    println!(
        "toe-off |error| frames {to:?} mean {:.2}; unmatched annotations {to_missed:?}",
        mean(&to)
    );
    // Plain Zeni for comparison.
    let mut t = Tracks::from_sequence(&seq);
    let dirs = vec![Direction::Right; t.len()];
    t.fps = 150.0;
    let zeni = ZeniRefined {
        speed_fraction: 1.0,
        ..Default::default()
    }
    .detect(&t, &dirs);
    let (zhs, _) = match_events(&zeni, EventKind::HeelStrike);
    let (zto, _) = match_events(&zeni, EventKind::ToeOff);
    println!(
        "plain Zeni: heel strike {zhs:?} mean {:.2}; toe-off {zto:?} mean {:.2}",
        mean(&zhs),
        mean(&zto)
    );

    // The annotations that lie at a kinematic contact are all found (see the README for the rest).
    assert!(hs.len() >= 3, "{hs:?}");
    assert!(!to.is_empty(), "{to:?}");
    assert!(mean(&hs) <= 2.0, "heel strike mean error {}", mean(&hs));
    assert!(mean(&to) <= 3.0, "toe-off mean error {}", mean(&to));
    // Every detected heel strike of a foot is one stride (163 frames here) from the next.
    for side in Side::BOTH {
        let f: Vec<usize> = r
            .events
            .iter()
            .filter(|e| e.side == side && e.event == EventKind::HeelStrike)
            .map(|e| e.frame)
            .collect();
        assert_eq!(f.len(), 2, "{side:?} {f:?}");
        assert!((f[1] - f[0]).abs_diff(163) <= 3, "{f:?}");
    }
}

#[test]
fn knee_agrees_with_the_reference_and_signs_are_clinical() {
    let seq = sequence();
    let r = analyse(
        &seq,
        &PostprocessConfig::default(),
        &KinematicsConfig::default(),
    )
    .unwrap();
    assert_eq!(r.direction_counts, [374, 0, 0]);
    assert_eq!(r.near_side, Some(Side::Right));
    let mut mae = Vec::new();
    for (ours, theirs) in [
        (&r.angles.left.knee, "left_knee"),
        (&r.angles.right.knee, "right_knee"),
    ] {
        let re = reference(theirs);
        let e: f64 = ours
            .iter()
            .zip(&re)
            .map(|(a, b)| (a - b).abs())
            .sum::<f64>()
            / re.len() as f64;
        mae.push(e);
    }
    println!(
        "knee MAE vs reference: left {:.2} deg, right {:.2} deg",
        mae[0], mae[1]
    );
    // The reference is the 3-D hip-knee-ankle angle; ours is its sagittal projection after a
    // 6 Hz filter. Projection of a leg that stays close to the sagittal plane changes the angle
    // by a few degrees at most.
    assert!(mae.iter().all(|&e| e < 3.0), "{mae:?}");
    // Ankle: the file's reference is angle(knee, ankle, toe) - 90, i.e. plantarflexion positive;
    // ours is dorsiflexion positive, so the two must be strongly anti-correlated.
    for (ours, theirs) in [
        (&r.angles.left.ankle, "left_ankle"),
        (&r.angles.right.ankle, "right_ankle"),
    ] {
        let c = correlation(ours, &reference(theirs));
        println!("{theirs}: correlation with the reference {c:.3}");
        assert!(c < -0.8, "{theirs}: {c}");
    }
    // Hip (the file's hip reference is against the mediolateral axis, unusable): flexed at heel
    // strike, extended before toe-off, as in every healthy gait.
    for e in &r.events {
        let leg = r.angles.leg(e.side);
        let v = leg.hip[e.frame - r.first_frame];
        match e.event {
            EventKind::HeelStrike => assert!(v > 10.0, "{e:?}: hip {v}"),
            EventKind::ToeOff => assert!(v < 0.0, "{e:?}: hip {v}"),
        }
    }
}

fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
    cov / (va * vb).sqrt()
}

#[test]
fn mirrored_walk_gives_the_same_angles_and_events() {
    let seq = sequence();
    let mut mirrored = seq.clone();
    for p in &mut mirrored.poses {
        for k in &mut p.keypoints {
            k.x = 2000.0 - k.x;
        }
    }
    let (post, kin) = (PostprocessConfig::default(), KinematicsConfig::default());
    let a = analyse(&seq, &post, &kin).unwrap();
    let b = analyse(&mirrored, &post, &kin).unwrap();
    assert_eq!(b.direction_counts, [0, 374, 0]);
    let keys = |r: &gait_kin::KinResult| r.events.iter().map(|e| e.key()).collect::<Vec<_>>();
    assert_eq!(keys(&a), keys(&b));
    // The sub-frame times too, up to the rounding of the mirrored coordinates.
    for (e, f) in a.events.iter().zip(&b.events) {
        assert!((e.time() - f.time()).abs() < 1e-6, "{e:?} {f:?}");
    }
    for side in Side::BOTH {
        let (x, y) = (a.angles.leg(side), b.angles.leg(side));
        for (u, v) in [(&x.hip, &y.hip), (&x.knee, &y.knee), (&x.ankle, &y.ankle)] {
            let d = u
                .iter()
                .zip(v)
                .map(|(p, q)| (p - q).abs())
                .fold(0.0, f64::max);
            assert!(d < 1e-6, "{side:?}: {d}");
        }
    }
}

/// Injects single frames and runs of 2..=30 frames of swapped leg labels at random places, then
/// scores detection frame by frame. `noise_px` adds Gaussian jitter (pose-estimator-like);
/// `step` keeps every step-th frame (5: the 150 Hz capture seen as 30 fps video).
fn swap_scores(noise_px: f64, trials: u64, step: usize) -> (f64, f64) {
    let mut seq = sequence();
    seq.poses = seq.poses.into_iter().step_by(step).collect();
    seq.frames = (0..seq.poses.len()).collect();
    seq.fps /= step as f64;
    let (mut tp, mut fp, mut fn_) = (0usize, 0usize, 0usize);
    for seed in 1..=trials {
        let mut rng = Rng::seeded(seed);
        let mut t = Tracks::from_sequence(&seq);
        if noise_px > 0.0 {
            for j in 0..t.names.len() {
                for i in 0..t.len() {
                    t.x[j][i] += noise_px * rng.normal();
                    t.y[j][i] += noise_px * rng.normal();
                }
            }
        }
        let n = t.len();
        let mut truth = vec![false; n];
        for _ in 0..6 {
            let len = if rng.below(3) == 0 {
                1
            } else {
                2 + rng.below(29.min(n / 4))
            };
            let start = rng.below(n - len);
            for s in &mut truth[start..start + len] {
                *s = !*s;
            }
        }
        for (i, &s) in truth.iter().enumerate() {
            if s {
                swap_frame(&mut t, i);
            }
        }
        let found = ContinuitySwap::default().detect(&t);
        for (f, w) in found.iter().zip(&truth) {
            match (f, w) {
                (true, true) => tp += 1,
                (true, false) => fp += 1,
                (false, true) => fn_ += 1,
                _ => {}
            }
        }
    }
    (
        tp as f64 / (tp + fp).max(1) as f64,
        tp as f64 / (tp + fn_).max(1) as f64,
    )
}

#[test]
fn swap_detection_precision_and_recall() {
    // The target holds on the capture rate. Seen as 30 fps video the legs move
    // 5x further between frames and a run that starts or ends while the legs cross is
    // ambiguous by a frame or two; that lower level (measured 0.83 / 0.75, with 2 px noise
    // 0.87 / 0.80) is guarded, not claimed to meet the target.
    for (noise, step, bar) in [(0.0, 1, 0.95), (2.0, 1, 0.95), (0.0, 5, 0.7), (2.0, 5, 0.7)] {
        let (p, r) = swap_scores(noise, 40, step);
        let hz = 150 / step;
        println!("mocap at {hz} Hz + {noise} px noise: precision {p:.4} recall {r:.4}");
        assert!(p >= bar && r >= bar, "{hz} Hz: precision {p} recall {r}");
    }
}

#[test]
fn swapped_input_is_corrected_before_the_angles() {
    let seq = sequence();
    let (post, kin) = (PostprocessConfig::default(), KinematicsConfig::default());
    let clean = analyse(&seq, &post, &kin).unwrap();
    let mut t = Tracks::from_sequence(&seq);
    for i in 120..140 {
        swap_frame(&mut t, i);
    }
    let bad = t.to_sequence();
    let fixed = analyse(&bad, &post, &kin).unwrap();
    assert_eq!(fixed.swapped_frames, 20);
    assert!(fixed.warnings.iter().any(|w| w.contains("20 frames")));
    assert_eq!(fixed.events, clean.events);
    let d = fixed
        .angles
        .left
        .knee
        .iter()
        .zip(&clean.angles.left.knee)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(d < 1e-9, "{d}");
}

#[test]
fn outputs_are_written_in_the_documented_layout() {
    let seq = sequence();
    let kin = KinematicsConfig {
        min_cycles: 1,
        subject_height_m: Some(1.75),
        ..Default::default()
    };
    let r = analyse(&seq, &PostprocessConfig::default(), &kin).unwrap();
    let dir = tempfile::tempdir().unwrap();
    gait_kin::write_outputs(&r, dir.path()).unwrap();
    let read = |n: &str| std::fs::read_to_string(dir.path().join(n)).unwrap();
    let angles = read("angles.csv");
    assert!(angles.starts_with(
        "frame,time_s,left_hip,right_hip,left_knee,right_knee,left_ankle,right_ankle\n0,0.000000,"
    ));
    assert_eq!(angles.lines().count(), 375);
    let events = read("events.csv");
    assert!(events.starts_with("side,event,frame,time_s\n"));
    assert_eq!(events.lines().count(), 1 + r.events.len());
    let cycles = read("cycles.csv");
    assert!(cycles.starts_with("side,joint,percent,mean,sd,n_cycles\n"));
    assert_eq!(
        cycles.lines().count(),
        1 + 6 * 101,
        "one cycle per side with min_cycles = 1"
    );
    let st = read("spatiotemporal.csv");
    assert!(
        st.starts_with("parameter,side,mean,sd,n,unit\n") && st.contains("\ncadence,both,"),
        "{st}"
    );
    println!("{st}");
    let back =
        gait_core::dlc::read(read("keypoints_filtered.csv").as_bytes(), None, 150.0).unwrap();
    assert_eq!(back.len(), 374);
    assert!(std::fs::read_dir(dir.path()).unwrap().all(|e| {
        !e.unwrap()
            .file_name()
            .to_string_lossy()
            .ends_with(".partial")
    }));
}

#[test]
fn known_length_scaling_gives_the_mocap_walking_speed() {
    let seq = sequence();
    // The derivation maps 2 mm to 1 px: 1 m is 500 px.
    let kin = KinematicsConfig {
        known_length_m: Some(1.0),
        known_length_px: Some(500.0),
        ..Default::default()
    };
    let r = analyse(&seq, &PostprocessConfig::default(), &kin).unwrap();
    assert_eq!(r.px_per_cm, Some(5.0));
    // Independent reference: the pelvis (mean of the hip markers) displacement over the trial.
    let t = Tracks::from_sequence(&seq);
    let (a, b) = (t.pelvis(0).unwrap(), t.pelvis(t.len() - 1).unwrap());
    let pelvis_cm_s = (b.0 - a.0) / 5.0 / ((t.len() - 1) as f64 / 150.0);
    for side in ["left", "right"] {
        let speed = r
            .spatiotemporal
            .iter()
            .find(|p| p.parameter == "speed" && p.side == side)
            .unwrap();
        assert_eq!(speed.unit, "cm/s");
        let rel = (speed.mean - pelvis_cm_s).abs() / pelvis_cm_s;
        println!(
            "{side} stride speed {:.1} cm/s, pelvis {pelvis_cm_s:.1} cm/s",
            speed.mean
        );
        assert!(rel < 0.05, "{side}: {} vs {pelvis_cm_s}", speed.mean);
    }
}

#[test]
fn events_file_overrides_detection_and_long_gaps_are_reported() {
    let mut seq = sequence();
    let k = seq.index_of("right_knee").unwrap();
    for p in &mut seq.poses[100..160] {
        p.keypoints[k] = gait_core::Keypoint::missing();
    }
    for p in &mut seq.poses[200..205] {
        p.keypoints[k].likelihood = 0.1;
    }
    let dir = tempfile::tempdir().unwrap();
    let events = dir.path().join("events.csv");
    std::fs::write(
        &events,
        "side,event,frame\nleft,heel_strike,10\nleft,heel_strike,170\nleft,heel_strike,330\n",
    )
    .unwrap();
    let kin = KinematicsConfig {
        events_csv: Some(events),
        ..Default::default()
    };
    let r = analyse(&seq, &PostprocessConfig::default(), &kin).unwrap();
    assert!(r.events_from_file);
    assert_eq!(r.events.len(), 3);
    assert_eq!(r.strides.len(), 2);
    assert_eq!(r.cycles.iter().filter(|c| c.side == Side::Left).count(), 3);
    assert!(
        r.warnings
            .iter()
            .any(|w| w
                == "gap of 60 frames in right_knee (from frame 100) left empty (longer than 50)"),
        "{:?}",
        r.warnings
    );
    assert!(
        !r.warnings.iter().any(|w| w.contains("from frame 200")),
        "the 5-frame gap is filled"
    );
    assert!(r.angles.right.knee[130].is_nan() && r.angles.right.knee[202].is_finite());
}
