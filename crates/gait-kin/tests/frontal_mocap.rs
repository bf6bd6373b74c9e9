//! Front and back views on real motion capture projected through a pinhole camera (issue 38):
//! tests/data/frontal/<trial>_<view>, made by tools/frontal/derive_frontal.py from the Fukuchi
//! 2018 healthy trial and the gaitkit Parkinson's trial. The script also computes the frontal
//! angles in 3-D (markers projected orthographically onto the lab's frontal plane), the step
//! width at each annotated heel strike and the circumduction of each stride; gait-kin sees only
//! the perspective image and must come close:
//! - trunk lean and pelvic obliquity within 1.5 deg MAE, hip adduction within 3 deg;
//! - step width within 2 cm of the heels' 3-D distance;
//! - every annotated heel strike found within 5 frames (150 Hz: one frame of a 30 fps video);
//! - the view decided from the keypoints, and the sides right in both views.
//!
//! Figures are printed (`cargo test -p gait-kin --test frontal_mocap -- --nocapture`).

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
        let header = lines.next().expect("header").split(',').map(String::from).collect();
        let rows = lines.map(|l| l.split(',').map(String::from).collect()).collect();
        (header, rows)
    }

    fn column(&self, file: &str, column: &str) -> Vec<f64> {
        let (h, rows) = self.rows(file);
        let c = h.iter().position(|x| x == column).expect("column");
        rows.iter().map(|r| r[c].parse().unwrap_or(f64::NAN)).collect()
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
    for q in r.cycle_quality.iter().filter(|q| q.accepted && q.side == side) {
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
    assert!(!errs.is_empty(), "{}: no frames compared for {column}", case.name());
    errs.iter().sum::<f64>() / errs.len() as f64
}

fn heel_strike_errors(case: &Case, r: &KinResult) -> (Vec<i64>, Vec<(Side, usize)>) {
    let (_, rows) = case.rows("events.csv");
    let mut errors = Vec::new();
    let mut missed = Vec::new();
    for row in rows.iter().filter(|r| r[1] == "heel_strike") {
        let side = if row[0] == "left" { Side::Left } else { Side::Right };
        let frame: usize = row[2].parse().expect("frame");
        let best = r
            .events
            .iter()
            .filter(|e| e.side == side && e.event == EventKind::HeelStrike)
            .map(|e| e.frame as i64 - frame as i64)
            .min_by_key(|d| d.abs());
        match best {
            Some(d) if d.abs() <= HS_FRAMES => errors.push(d),
            _ => missed.push((side, frame)),
        }
    }
    (errors, missed)
}

/// Step width at each detected heel strike against the 3-D width at the nearest annotated
/// heel strike of the same side (within 5 frames).
fn step_width_errors(case: &Case, r: &KinResult) -> Vec<f64> {
    let (_, rows) = case.rows("steps.csv");
    let f = r.frontal.as_ref().expect("frontal");
    let mut errs = Vec::new();
    for w in f.feet.iter().filter(|l| l.measure == "step_width") {
        let near = rows
            .iter()
            .filter(|row| row[0] == w.side.name())
            .map(|row| (row[1].parse::<i64>().unwrap(), row[2].parse::<f64>().unwrap()))
            .filter(|(fr, _)| (fr - w.first_frame as i64).abs() <= HS_FRAMES)
            .min_by_key(|(fr, _)| (fr - w.first_frame as i64).abs());
        if let Some((_, cm)) = near {
            assert_eq!(w.unit, "cm");
            errs.push(w.value - cm);
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
            let expected = if view == "anterior" { View::Anterior } else { View::Posterior };
            assert_eq!(r.view.view, expected, "{name}: {}", r.view.how);
            let (hs, missed) = heel_strike_errors(&case, &r);
            let widths = step_width_errors(&case, &r);
            let mut maes = Vec::new();
            for side in Side::BOTH {
                for (k, column, limit) in [
                    (0, "trunk_lean", 1.5),
                    (1, "pelvic_obliquity", 1.5),
                    (2, "hip_adduction", 3.0),
                ] {
                    let mae = angle_mae(&case, &r, k, column, side);
                    maes.push((side.name(), column, mae, limit));
                }
            }
            println!(
                "{name}: view {:?} ({}); cycles accepted {:?}; heel strikes signed errors {hs:?}, missed {missed:?}; step width errors (cm) {:?}; MAE {:?}",
                r.view.view,
                r.view.how,
                r.cycles_accepted,
                widths.iter().map(|e| (e * 10.0).round() / 10.0).collect::<Vec<_>>(),
                maes.iter().map(|m| (m.0, m.1, (m.2 * 100.0).round() / 100.0)).collect::<Vec<_>>()
            );
            assert!(missed.is_empty(), "{name}: heel strikes missed {missed:?}");
            assert!(!widths.is_empty(), "{name}: no step width compared");
            assert!(widths.iter().all(|e| e.abs() <= 2.0), "{name}: step widths {widths:?}");
            for (side, column, mae, limit) in maes {
                assert!(mae <= limit, "{name} {side} {column}: MAE {mae:.2} > {limit}");
            }
        }
    }
}
