//! Metrics against the independent numpy implementation in
//! `tools/eval/make_fixtures.py` (fixtures in `tests/fixtures/metrics`).

use std::path::PathBuf;

use gait_eval::{EvalOptions, Side, Stat, evaluate_with_angles, read_angles_csv, read_poses};
use serde_json::Value;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/metrics")
        .join(name)
}

fn close(stat: &Stat, want: &Value, what: &str) {
    assert_eq!(stat.n as u64, want["n"].as_u64().unwrap(), "{what}: n");
    for (got, key) in [(stat.mean, "mean"), (stat.sd, "sd")] {
        match (got, want[key].as_f64()) {
            (Some(g), Some(w)) => assert!(
                (g - w).abs() <= 1e-9 * w.abs().max(1.0),
                "{what} {key}: {g} vs numpy {w}"
            ),
            (None, None) => {}
            (g, w) => panic!("{what} {key}: {g:?} vs numpy {w:?}"),
        }
    }
}

#[test]
fn metrics_match_numpy() {
    let expected: Value =
        serde_json::from_str(&std::fs::read_to_string(fixture("expected.json")).unwrap()).unwrap();
    let truth = read_poses(&fixture("truth.csv"), 30.0, None).unwrap();
    let pred = read_poses(&fixture("pred_openpose"), 30.0, None).unwrap();
    assert_eq!((truth.len(), pred.len()), (60, 70));
    let (ta, pa) = (
        read_angles_csv(&fixture("truth_angles.csv")).unwrap(),
        read_angles_csv(&fixture("pred_angles.csv")).unwrap(),
    );
    let opts = EvalOptions {
        min_likelihood: 0.5,
        prosthetic_side: Side::Right,
        ..Default::default()
    };
    let e = evaluate_with_angles(&truth, &pred, Some((&ta, &pa)), &opts).unwrap();

    assert_eq!(
        e.frames_compared as u64,
        expected["frames_compared"].as_u64().unwrap()
    );
    let kps = expected["keypoints"].as_object().unwrap();
    assert_eq!(
        e.keypoints.len(),
        kps.len(),
        "compared keypoints: {:?}",
        e.keypoints.iter().map(|k| &k.name).collect::<Vec<_>>()
    );
    for k in &e.keypoints {
        close(&k.px, &kps[&k.name], &k.name);
    }
    for l in &e.legs {
        close(
            &l.stat,
            &expected["legs"][l.side.as_str()],
            &format!("{:?} leg", l.side),
        );
    }
    let kin = e.kinematics.as_ref().unwrap();
    for j in &kin.joints {
        close(&j.deg, &expected["joints"][&j.joint], &j.joint);
    }
    for l in &kin.legs {
        close(
            &l.stat,
            &expected["kinematics_legs"][l.side.as_str()],
            &format!("{:?} leg angles", l.side),
        );
    }

    let f = &e.failures;
    let xf = &expected["failures"];
    assert_eq!(f.frames as u64, xf["frames"].as_u64().unwrap());
    assert!((f.reference_length_px - xf["reference_length_px"].as_f64().unwrap()).abs() < 1e-9);
    for (name, c) in [
        ("not_identified", &f.not_identified),
        ("swapped", &f.swapped),
        ("misidentified", &f.misidentified),
        ("any", &f.any),
    ] {
        assert_eq!(
            c.frames as u64,
            xf[name]["frames"].as_u64().unwrap(),
            "{name}"
        );
        assert!(
            (c.percent - xf[name]["percent"].as_f64().unwrap()).abs() < 1e-9,
            "{name}"
        );
    }
    let frames = |v: &Value| -> Vec<usize> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_u64().unwrap() as usize)
            .collect()
    };
    assert_eq!(f.swapped_frames, frames(&xf["swapped_frames"]));
    assert_eq!(
        f.not_identified_frames,
        frames(&xf["not_identified_frames"])
    );
    assert_eq!(f.misidentified_frames, frames(&xf["misidentified_frames"]));
    for s in &f.by_side {
        let xs = &xf["by_side"][s.side.as_str()];
        assert_eq!(
            s.not_identified.frames as u64,
            xs["not_identified"]["frames"].as_u64().unwrap(),
            "{:?}",
            s.side
        );
        assert_eq!(
            s.misidentified.frames as u64,
            xs["misidentified"]["frames"].as_u64().unwrap(),
            "{:?}",
            s.side
        );
    }
    // The injected failures are what the fixture's numbers say they are.
    assert_eq!(f.swapped_frames, vec![20, 21, 22]);
    assert!(
        e.warnings
            .iter()
            .any(|w| w.contains("swapped in frames 20, 21, 22")),
        "{:?}",
        e.warnings
    );
    assert!(
        e.warnings
            .iter()
            .any(|w| w.contains("10 predicted frames have no ground truth")),
        "{:?}",
        e.warnings
    );
}

#[test]
fn writes_metrics_files_in_the_table_layout() {
    let truth = read_poses(&fixture("truth.csv"), 30.0, None).unwrap();
    let pred = read_poses(&fixture("pred_openpose"), 30.0, None).unwrap();
    let (ta, pa) = (
        read_angles_csv(&fixture("truth_angles.csv")).unwrap(),
        read_angles_csv(&fixture("pred_angles.csv")).unwrap(),
    );
    let mk = |method: &str| EvalOptions {
        method: method.into(),
        group: Some("Transtibial".into()),
        ..Default::default()
    };
    let a = evaluate_with_angles(&truth, &pred, Some((&ta, &pa)), &mk("OpenPose")).unwrap();
    let b = evaluate_with_angles(&truth, &truth, Some((&ta, &ta)), &mk("Zero-shot")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    gait_eval::write_eval(&[a.clone(), b], dir.path()).unwrap();
    let table = std::fs::read_to_string(dir.path().join("table.md")).unwrap();
    assert!(
        table.starts_with(
            "| Metrics (Units) | Amputation Type | Leg | OpenPose (MAE) | Zero-shot (MAE) |"
        ),
        "{table}"
    );
    let prosthetic = table
        .lines()
        .find(|l| l.starts_with("| Joint Coordinates (pixels) | Transtibial | Prosthetic |"))
        .unwrap();
    assert!(
        prosthetic.ends_with(&format!(" {} | **0.00 (0.00)** |", a.legs[1].stat.cell())),
        "{prosthetic}"
    );
    assert!(
        table.contains("| Joint Kinematics (°) | Transtibial | Intact |"),
        "{table}"
    );
    let csv = std::fs::read_to_string(dir.path().join("metrics.csv")).unwrap();
    assert!(csv.starts_with("method,group,view,metric,name,side,role,unit,n,mean,sd\n"));
    assert!(
        csv.contains("OpenPose,Transtibial,,failure,swapped,,,percent_of_frames,3,5,"),
        "{csv}"
    );
    let json: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("metrics.json")).unwrap())
            .unwrap();
    assert_eq!(json.as_array().unwrap().len(), 2);
    // One evaluation: a single object.
    gait_eval::write_eval(&[a], dir.path()).unwrap();
    let json: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("metrics.json")).unwrap())
            .unwrap();
    assert_eq!(json["failures"]["swapped"]["frames"], 3);
}

#[test]
fn kinematics_through_gait_kin() {
    let truth = read_poses(&fixture("truth.csv"), 30.0, None).unwrap();
    let pred = read_poses(&fixture("pred_openpose"), 30.0, None).unwrap();
    let (post, kin) = (
        gait_kin::PostprocessConfig::default(),
        gait_kin::KinematicsConfig::default(),
    );
    let opts = EvalOptions::default();
    let same = gait_eval::evaluate(&truth, &truth, &post, &kin, &opts).unwrap();
    let k = same.kinematics.as_ref().unwrap();
    for j in &k.joints {
        assert!(
            j.deg.n > 40,
            "{}: angles defined in most frames ({} of 60)",
            j.joint,
            j.deg.n
        );
        assert_eq!(j.deg.mean, Some(0.0), "{}: truth against itself", j.joint);
    }
    let e = gait_eval::evaluate(&truth, &pred, &post, &kin, &opts).unwrap();
    let k = e.kinematics.as_ref().unwrap();
    // 4 px keypoint noise on ~100 px segments plus the injected failures
    // (right ankle misplaced in two frames), after gait-kin's filtering.
    for j in &k.joints {
        let m = j.deg.mean.unwrap();
        eprintln!(
            "{} angle MAE through gait-kin: {m:.2} deg (n={})",
            j.joint, j.deg.n
        );
        assert!(m > 0.0 && m < 20.0, "{} angle MAE {m}", j.joint);
    }
}
