//! Front and back views on real motion capture projected through a pinhole camera (issue 38):
//! tests/data/frontal/<trial>_<view>, made by tools/frontal/derive_frontal.py from the Fukuchi
//! 2018 healthy trial and the gaitkit Parkinson's trial. The script also computes the frontal
//! angles in 3-D (markers projected orthographically onto the lab's frontal plane), the step
//! width at each annotated heel strike and the circumduction of each stride; gait-kin sees only
//! the perspective image and must come close:
//! - trunk lean and pelvic obliquity within 1.5 deg MAE, hip adduction within 3 deg;
//! - step width within 2 cm of the heels' 3-D distance, circumduction within 2 cm of the
//!   ankle's 3-D excursion (3 cm under the measured jitter);
//! - heel strikes within 5 frames (150 Hz: one frame of a 30 fps video) of the annotated ones,
//!   where the annotation marks the contact (see below), and of the side view's heel strikes
//!   on the same trial (tests/data/fukuchi2018, tests/data/gaitkit_pd), none missed;
//! - the view decided from the keypoints, and the sides right in both views.
//!
//! Figures are printed (`cargo test -p gait-kin --test frontal_mocap -- --nocapture`).

mod jitter;
mod rng;
use jitter::Jitter;

use std::path::PathBuf;

use gait_core::PoseSequence;
use gait_kin::{
    EventKind, KinResult, KinematicsConfig, PostprocessConfig, Side, View, analyse,
    spatiotemporal::LEG_PER_HEIGHT,
};

const TRIALS: [&str; 2] = ["fukuchi2018", "gaitkit_pd"];
const VIEWS: [&str; 2] = ["anterior", "posterior"];
const FPS: f64 = 150.0;
/// Heel strikes within this many 150 Hz frames of the annotation (33 ms).
const HS_FRAMES: i64 = 5;

/// Annotated heel strikes that do not mark the heel's contact, with the window (detected -
/// annotated, frames) they are held to instead. Fukuchi's left 177 and 340 lie 14-16 frames
/// after the heel's kinematic contact (tests/data/fukuchi2018/README.md); the Parkinson's
/// walker's left heel reaches the floor still moving forward, so a rule that waits for it to
/// stop finds it up to 0.11 s late, as the side view's does (tests/data/gaitkit_pd/README.md,
/// crates/gait-kin/tests/independent_mocap.rs).
const NOT_AT_CONTACT: [(&str, &str, usize, [i64; 2]); 5] = [
    ("fukuchi2018", "left", 177, [-16, HS_FRAMES]),
    ("fukuchi2018", "left", 340, [-16, HS_FRAMES]),
    ("gaitkit_pd", "left", 200, [0, 16]),
    ("gaitkit_pd", "left", 395, [0, 16]),
    ("gaitkit_pd", "left", 581, [0, 16]),
];
/// Annotations this close to either end of the trial are not required: a heel strike needs the
/// swing before it in view (Fukuchi's left 13 is 0.09 s from the start).
const EDGE_FRAMES: usize = 15;

struct Case {
    dir: PathBuf,
}

impl Case {
    fn new(trial: &str, view: &str) -> Self {
        Self::at(
            PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("../../tests/data/frontal")
                .join(format!("{trial}_{view}")),
        )
    }

    fn at(dir: PathBuf) -> Self {
        Self { dir }
    }

    fn name(&self) -> String {
        self.dir.file_name().unwrap().to_string_lossy().into_owned()
    }

    fn sequence(&self) -> PoseSequence {
        let f = std::fs::File::open(self.dir.join("keypoints.csv")).expect("keypoints.csv");
        gait_core::dlc::read(f, None, FPS).expect("DeepLabCut CSV")
    }

    fn rows(&self, name: &str) -> (Vec<String>, Vec<Vec<String>>) {
        let text = std::fs::read_to_string(self.dir.join(name)).expect("csv");
        let mut lines = text.lines();
        let header = lines
            .next()
            .expect("header")
            .split(',')
            .map(String::from)
            .collect();
        let rows = lines
            .map(|l| l.split(',').map(String::from).collect())
            .collect();
        (header, rows)
    }

    fn column(&self, file: &str, column: &str) -> Vec<f64> {
        let (h, rows) = self.rows(file);
        let c = h.iter().position(|x| x == column).expect("column");
        rows.iter()
            .map(|r| r[c].parse().unwrap_or(f64::NAN))
            .collect()
    }

    fn leg_length_cm(&self) -> f64 {
        let text = std::fs::read_to_string(self.dir.join("subject.json")).expect("subject.json");
        let v: serde_json::Value = serde_json::from_str(&text).expect("json");
        v["leg_length_cm"].as_f64().expect("leg_length_cm")
    }

    /// The analysis with the view left to `auto` and the scale from the subject's leg length.
    fn analyse(&self) -> KinResult {
        let kin = KinematicsConfig {
            subject_height_m: Some(self.leg_length_cm() / 100.0 / LEG_PER_HEIGHT),
            ..KinematicsConfig::default()
        };
        analyse(&self.sequence(), &PostprocessConfig::default(), &kin).expect("analysis")
    }
}

/// Mean absolute difference between gait-kin's frontal angle and the 3-D reference over the
/// frames of the accepted cycles of that side.
fn angle_mae(case: &Case, r: &KinResult, measure: usize, column: &str, side: Side) -> f64 {
    let f = r.frontal.as_ref().expect("frontal result");
    let ours = &f.angles.side(side)[measure];
    let frames = case.column("reference.csv", "frame");
    let reference = case.column("reference.csv", &format!("{column}_{}", side.name()));
    let mut errs = Vec::new();
    for q in r
        .cycle_quality
        .iter()
        .filter(|q| q.accepted && q.side == side)
    {
        for (fr, refv) in frames.iter().zip(&reference) {
            let fr = *fr as usize;
            if fr < q.first_frame || fr > q.last_frame {
                continue;
            }
            let v = ours[fr - r.first_frame];
            if v.is_finite() && refv.is_finite() {
                errs.push((v - refv).abs());
            }
        }
    }
    assert!(
        !errs.is_empty(),
        "{}: no frames compared for {column}",
        case.name()
    );
    errs.iter().sum::<f64>() / errs.len() as f64
}

/// Per annotated heel strike away from the trial's ends: (side, frame, detected - annotated of
/// the nearest detection of that side) and whether it lies in the allowed window.
fn heel_strike_errors(trial: &str, case: &Case, r: &KinResult) -> Vec<(Side, usize, i64, bool)> {
    let (_, rows) = case.rows("events.csv");
    let mut out = Vec::new();
    for row in rows.iter().filter(|r| r[1] == "heel_strike") {
        let side = if row[0] == "left" {
            Side::Left
        } else {
            Side::Right
        };
        let frame: usize = row[2].parse().expect("frame");
        if frame < r.first_frame + EDGE_FRAMES || frame + EDGE_FRAMES > r.first_frame + r.n_frames {
            continue;
        }
        let window = NOT_AT_CONTACT
            .iter()
            .find(|n| n.0 == trial && n.1 == row[0] && n.2 == frame)
            .map_or([-HS_FRAMES, HS_FRAMES], |n| n.3);
        let d = nearest(r, side, frame).unwrap_or(i64::MAX);
        out.push((side, frame, d, (window[0]..=window[1]).contains(&d)));
    }
    out
}

/// Detected - `frame` for the nearest heel strike of `side`.
fn nearest(r: &KinResult, side: Side, frame: usize) -> Option<i64> {
    nearest_of(r, side, EventKind::HeelStrike, frame)
}

/// Detected - `frame` for the nearest `kind` of `side`.
fn nearest_of(r: &KinResult, side: Side, kind: EventKind, frame: usize) -> Option<i64> {
    r.events
        .iter()
        .filter(|e| e.side == side && e.event == kind)
        .map(|e| e.frame as i64 - frame as i64)
        .min_by_key(|d| d.abs())
}

/// The frontal run's heel strikes against the side view's of the same trial (the sagittal
/// fixture, analysed with the defaults): per side-view heel strike, the nearest frontal one.
fn against_side_view(trial: &str, r: &KinResult) -> Vec<(Side, usize, i64)> {
    side_view_events(trial, EventKind::HeelStrike)
        .into_iter()
        .map(|(side, frame)| (side, frame, nearest(r, side, frame).unwrap_or(i64::MAX)))
        .collect()
}

/// The side view's events of `kind` on the same trial (the sagittal fixture, analysed with the
/// defaults), at 150 Hz.
fn side_view_events(trial: &str, kind: EventKind) -> Vec<(Side, usize)> {
    let side_view = Case::at(
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../tests/data")
            .join(trial),
    );
    let s = analyse(
        &side_view.sequence(),
        &PostprocessConfig::default(),
        &KinematicsConfig::default(),
    )
    .expect("side view");
    (s.events.iter())
        .filter(|e| e.event == kind)
        .map(|e| (e.side, e.frame))
        .collect()
}

/// Per side-view toe-off, the nearest frontal toe-off of the same side (`per_frame` trial
/// frames a run frame), in run frames; side-view toe-offs within `edge` run frames of the run's
/// ends without a frontal one nearer than `edge` are left out (no swing in view after them).
fn toe_offs_against_side_view(trial: &str, r: &KinResult, per_frame: f64, edge: i64) -> Vec<i64> {
    let (first, last) = (
        r.first_frame as i64,
        (r.first_frame + r.n_frames) as i64 - 1,
    );
    side_view_events(trial, EventKind::ToeOff)
        .into_iter()
        .filter_map(|(side, f)| {
            let at = (f as f64 / per_frame).round() as i64;
            let d = nearest_of(r, side, EventKind::ToeOff, at.max(0) as usize);
            let near_end = at < first + edge || at > last - edge;
            match d {
                Some(d) if d.abs() < edge => Some(d),
                _ if near_end => None,
                _ => Some(i64::MAX),
            }
        })
        .collect()
}

/// Step width at each detected heel strike against the 3-D width at the nearest annotated
/// heel strike of the same side (within 5 frames).
fn step_width_errors(case: &Case, r: &KinResult) -> Vec<f64> {
    errors_against(case, r, ("steps.csv", 2), "step_width", 1.0, HS_FRAMES)
}

/// Circumduction of each accepted stride against the 3-D excursion of the annotated stride of
/// the same foot that starts nearest (within 15 trial frames); a run frame is `per_frame`
/// trial frames.
fn circumduction_errors(case: &Case, r: &KinResult, per_frame: f64) -> Vec<f64> {
    errors_against(
        case,
        r,
        ("circumduction.csv", 3),
        "circumduction",
        per_frame,
        3 * HS_FRAMES,
    )
}

/// Each frontal foot length `measure` (in cm) minus the reference of the same side in
/// `file`'s `column` whose frame (column 1) lies nearest the length's first frame, within
/// `window` trial frames.
fn errors_against(
    case: &Case,
    r: &KinResult,
    (file, column): (&str, usize),
    measure: &str,
    per_frame: f64,
    window: i64,
) -> Vec<f64> {
    let (_, rows) = case.rows(file);
    let f = r.frontal.as_ref().expect("frontal");
    let mut errs = Vec::new();
    for l in f.feet.iter().filter(|l| l.measure == measure) {
        let at = l.first_frame as f64 * per_frame;
        let off = |fr: f64| (fr - at).abs();
        let near = (rows.iter())
            .filter(|row| row[0] == l.side.name())
            .map(|row| {
                let value: f64 = row[column].parse().unwrap();
                (row[1].parse::<f64>().unwrap(), value)
            })
            .filter(|(fr, _)| off(*fr) <= window as f64)
            .min_by(|a, b| off(a.0).total_cmp(&off(b.0)));
        if let Some((_, cm)) = near {
            assert_eq!(l.unit, "cm");
            errs.push(l.value - cm);
        }
    }
    errs
}

#[test]
fn frontal_views_of_real_mocap_match_the_3d_measures() {
    for trial in TRIALS {
        for view in VIEWS {
            let case = Case::new(trial, view);
            let r = case.analyse();
            let name = case.name();
            let expected = if view == "anterior" {
                View::Anterior
            } else {
                View::Posterior
            };
            assert_eq!(r.view.view, expected, "{name}: {}", r.view.how);
            let hs = heel_strike_errors(trial, &case, &r);
            let side_view = against_side_view(trial, &r);
            let toe_offs = toe_offs_against_side_view(trial, &r, 1.0, 30);
            let widths = step_width_errors(&case, &r);
            let circ = circumduction_errors(&case, &r, 1.0);
            let mut maes = Vec::new();
            for side in Side::BOTH {
                for (k, column, limit) in [
                    (0, "trunk_lean", 1.5),
                    (1, "pelvic_obliquity", 1.5),
                    (2, "hip_adduction", 3.0),
                ] {
                    // The Fukuchi trial has no shoulder markers (tests/data/frontal/README.md).
                    if !case
                        .rows("reference.csv")
                        .0
                        .iter()
                        .any(|h| h.starts_with(column))
                    {
                        continue;
                    }
                    let mae = angle_mae(&case, &r, k, column, side);
                    maes.push((side.name(), column, mae, limit));
                }
            }
            println!(
                "{name}: view {:?} ({}); cycles accepted {:?}; heel strikes against the annotations (side, frame, error, ok) {hs:?}; against the side view {side_view:?}; toe-offs against the side view's {toe_offs:?}; step width errors (cm) {:?}; circumduction errors (cm) {:?}; MAE {:?}",
                r.view.view,
                r.view.how,
                r.cycles_accepted,
                widths
                    .iter()
                    .map(|e| (e * 10.0).round() / 10.0)
                    .collect::<Vec<_>>(),
                circ.iter()
                    .map(|e| (e * 10.0).round() / 10.0)
                    .collect::<Vec<_>>(),
                maes.iter()
                    .map(|m| (m.0, m.1, (m.2 * 100.0).round() / 100.0))
                    .collect::<Vec<_>>()
            );
            assert!(hs.iter().all(|h| h.3), "{name}: heel strikes {hs:?}");
            assert!(
                side_view.iter().all(|h| h.2.abs() <= HS_FRAMES),
                "{name}: against the side view {side_view:?}"
            );
            assert!(
                !toe_offs.is_empty() && toe_offs.iter().all(|d| d.abs() <= HS_FRAMES),
                "{name}: toe-offs against the side view {toe_offs:?}"
            );
            assert!(!widths.is_empty(), "{name}: no step width compared");
            assert!(
                !circ.is_empty() && circ.iter().all(|e| e.abs() <= 2.0),
                "{name}: circumduction errors {circ:?}"
            );
            assert!(
                widths.iter().all(|e| e.abs() <= 2.0),
                "{name}: step widths {widths:?}"
            );
            for (side, column, mae, limit) in maes {
                assert!(
                    mae <= limit,
                    "{name} {side} {column}: MAE {mae:.2} > {limit}"
                );
            }
        }
    }
}

/// The same figures on the trials as 30 fps videos with BlazePose's jitter, 10 seeds each,
/// with the jitter as measured (crates/gait-kin/tests/jitter) and, reported beside it, every
/// coordinate independent: heel strikes within one video frame (33 ms) of the side view's and
/// the frontal angles within the targets. Measured (printed as SUMMARY): the angles hold in 39
/// of 40 seeds (the independent model: 25, the Parkinson's walker's pelvic obliquity about 2
/// deg, his hip joint centres 14 cm apart); the healthy walk's figures in 10 of 10 seeds each
/// way, the Parkinson's walker's in 9 of 10 each way (before the heel strikes were placed from
/// the feet's vertical distance, calibrated on the walk: 3 of 10 each way, with heel strikes up
/// to 14 frames off; his shuffling feet's distance peaks flatly). Asserted: every seed's view
/// decided right, the angles in at least 9 of 10 seeds of every walk and view, the figures of
/// the healthy walk in at least 9 of 10 and of the Parkinson's in at least 8, both ways, and
/// under every jitter model cycles on both sides.
#[test]
fn frontal_figures_hold_under_pose_model_noise() {
    let mut summary = Vec::new();
    let mut worst_circumduction = 0.0f64;
    for trial in TRIALS {
        let side_view = Case::at(
            PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("../../tests/data")
                .join(trial),
        );
        let sagittal = analyse(
            &side_view.sequence(),
            &PostprocessConfig::default(),
            &KinematicsConfig::default(),
        )
        .expect("side view");
        for view in VIEWS {
            let case = Case::new(trial, view);
            let name = case.name();
            let kin = KinematicsConfig {
                subject_height_m: Some(case.leg_length_cm() / 100.0 / LEG_PER_HEIGHT),
                ..KinematicsConfig::default()
            };
            let seq = case.sequence();
            for kind in [Jitter::Measured, Jitter::MeasuredLimbs, Jitter::Independent] {
                let model = format!("{kind:?}").to_lowercase();
                let (mut held, mut angles_held, mut with_cycles_held, mut lost) = (0, 0, 0, 0);
                // Toe-offs within one video frame of the side view's, of those found; not found.
                let mut toe_offs = (0usize, 0usize, 0usize);
                for seed in 1..=10u64 {
                    let noisy = jitter::as_video(&seq, seed, kind);
                    let r = analyse(&noisy, &PostprocessConfig::default(), &kin).expect("analysis");
                    let mut problems = Vec::new();
                    for e in sagittal
                        .events
                        .iter()
                        .filter(|e| e.event == EventKind::HeelStrike)
                    {
                        // A side-view heel strike at 150 Hz frame f falls in video frame round(f / 5).
                        let want = (e.frame as f64 / 5.0).round();
                        let got = r
                            .events
                            .iter()
                            .filter(|g| g.side == e.side && g.event == EventKind::HeelStrike)
                            .map(|g| g.frame as f64 - want)
                            .min_by(|a, b| a.abs().total_cmp(&b.abs()));
                        if !got.is_some_and(|d| d.abs() <= 1.0) {
                            problems.push(format!(
                                "{} heel strike {} off by {got:?} frames",
                                e.side.name(),
                                e.frame
                            ));
                        }
                    }
                    for d in toe_offs_against_side_view(trial, &r, 5.0, 6) {
                        toe_offs.0 += usize::from(d.abs() <= 1);
                        toe_offs.1 += usize::from(d != i64::MAX);
                        toe_offs.2 += usize::from(d == i64::MAX);
                    }
                    let maes = noisy_maes(&case, &r);
                    let circ = circumduction_errors(&case, &r, 5.0);
                    if kind == Jitter::Measured {
                        worst_circumduction =
                            circ.iter().fold(worst_circumduction, |w, e| w.max(e.abs()));
                    }
                    angles_held += usize::from(maes.iter().all(|(_, mae, limit)| mae <= limit));
                    // A side without an accepted cycle has no angles to judge (its MAE is
                    // infinite): counted apart, as a failure of the events, not of the angles.
                    let judged = maes.iter().filter(|(_, mae, _)| mae.is_finite());
                    with_cycles_held += usize::from(judged.clone().all(|(_, m, l)| m <= l));
                    lost += usize::from(maes.iter().any(|(_, mae, _)| mae.is_infinite()));
                    for (what, mae, limit) in &maes {
                        if mae > limit {
                            problems.push(format!("{what} MAE {mae:.2}"));
                        }
                    }
                    println!(
                        "{name} ({model} jitter) seed {seed}: view {:?}, cycles {:?}, MAE {:?} {problems:?}",
                        r.view.view,
                        r.cycles_accepted,
                        maes.iter()
                            .map(|m| (m.0.clone(), (m.1 * 100.0).round() / 100.0))
                            .collect::<Vec<_>>()
                    );
                    let expected = if view == "anterior" {
                        View::Anterior
                    } else {
                        View::Posterior
                    };
                    assert_eq!(r.view.view, expected, "{name} seed {seed}: {}", r.view.how);
                    held += usize::from(problems.is_empty());
                }
                println!(
                    "SUMMARY {name} ({model} jitter): the figures held in {held} of 10 seeds, \
                     the angles in {angles_held} (on the sides with cycles: {with_cycles_held}; \
                     a side without cycles in {lost}); toe-offs within a video frame of the side \
                     view's: {} of {} found ({} not found)",
                    toe_offs.0, toe_offs.1, toe_offs.2
                );
                summary.push((name.clone(), kind, held, angles_held, with_cycles_held));
                // Before heel strikes that conflict with placed ones were dropped, the
                // Parkinson's walker's limbs' jitter left a side without cycles in 3 of 20 seeds.
                assert_eq!(lost, 0, "{name} ({model} jitter): a side without cycles");
                if kind == Jitter::Measured {
                    let share = toe_offs.0 as f64 / toe_offs.1.max(1) as f64;
                    assert!(share >= 0.8, "{name}: toe-offs within a frame {toe_offs:?}");
                    // Not found: 0-5 in 10 seeds (the Parkinson's walk toward the camera: 17
                    // before the toe-off's peak was searched up to 0.5 s after the still run).
                    assert!(toe_offs.2 <= 6, "{name}: toe-offs not found {toe_offs:?}");
                }
            }
        }
    }
    println!(
        "SUMMARY circumduction under the measured jitter: at most {worst_circumduction:.2} cm off the 3-D excursion"
    );
    assert!(
        worst_circumduction <= 3.0,
        "circumduction {worst_circumduction:.2} cm off"
    );
    for (walk, least) in [
        ("fukuchi2018_anterior", 9),
        ("fukuchi2018_posterior", 9),
        ("gaitkit_pd_anterior", 8),
        ("gaitkit_pd_posterior", 8),
    ] {
        assert!(
            summary.iter().any(|(name, kind, held, ..)| name == walk
                && *kind == Jitter::Measured
                && *held >= least),
            "{walk}: {summary:?}"
        );
    }
    // With the jitter as measured, the frontal angles of every walk and view; with the knees
    // and feet at their own, larger jitter, wherever a side keeps accepted cycles (its heel
    // strikes, not its angles, are what that jitter breaks: BENCHMARKS.md, "Knees and feet").
    for (name, kind, _, angles_held, with_cycles_held) in &summary {
        assert!(
            *kind != Jitter::Measured || *angles_held >= 9,
            "{name}: the angles held in {angles_held} of 10 seeds"
        );
        assert!(
            *kind != Jitter::MeasuredLimbs || *with_cycles_held >= 9,
            "{name}: with the limbs' jitter, the angles held in {with_cycles_held} of 10 seeds"
        );
    }
}

/// MAE per side and measure over the frames of the accepted cycles, for a 30 fps run whose
/// frame k is the trial's frame 5k.
fn noisy_maes(case: &Case, r: &KinResult) -> Vec<(String, f64, f64)> {
    let f = r.frontal.as_ref().expect("frontal");
    let frames = case.column("reference.csv", "frame");
    let mut out = Vec::new();
    for side in Side::BOTH {
        for (k, column, limit) in [
            (0, "trunk_lean", 1.5),
            (1, "pelvic_obliquity", 1.5),
            (2, "hip_adduction", 3.0),
        ] {
            let header = case.rows("reference.csv").0;
            let name = format!("{column}_{}", side.name());
            if !header.contains(&name) {
                continue;
            }
            let reference = case.column("reference.csv", &name);
            let mut errs = Vec::new();
            for q in r
                .cycle_quality
                .iter()
                .filter(|q| q.accepted && q.side == side)
            {
                for i in q.first_frame..=q.last_frame {
                    let Some(row) = frames.iter().position(|&fr| fr as usize == 5 * i) else {
                        continue;
                    };
                    let v = f.angles.side(side)[k][i - r.first_frame];
                    if v.is_finite() {
                        errs.push((v - reference[row]).abs());
                    }
                }
            }
            let mae = if errs.is_empty() {
                f64::INFINITY
            } else {
                errs.iter().sum::<f64>() / errs.len() as f64
            };
            out.push((name, mae, limit));
        }
    }
    out
}
