//! Butterworth design, filtfilt and not-a-knot spline against scipy 1.14.1 outputs
//! (fixtures from tools/kin/make_scipy_fixtures.py).

use gait_kin::GapFiller;
use gait_kin::butterworth::{design_lowpass, filtfilt};
use gait_kin::spline::CubicSplineFill;
use serde_json::Value;

fn load(name: &str) -> Value {
    let path = format!("{}/tests/fixtures/{name}", env!("CARGO_MANIFEST_DIR"));
    serde_json::from_str(&std::fs::read_to_string(&path).expect("fixture")).expect("json")
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().unwrap_or(f64::NAN))
        .collect()
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn butterworth_matches_scipy() {
    let f = load("butterworth.json");
    let mut worst: f64 = 0.0;
    for c in f["cases"].as_array().unwrap() {
        let order = c["order"].as_u64().unwrap() as usize;
        let (fc, fs) = (c["cutoff_hz"].as_f64().unwrap(), c["fs"].as_f64().unwrap());
        let (b, a) = design_lowpass(order, fc, fs);
        let db = max_abs_diff(&b, &floats(&c["b"]));
        let da = max_abs_diff(&a, &floats(&c["a"]));
        assert!(
            db < 1e-12 && da < 1e-12,
            "order {order} fc {fc} fs {fs}: b {db:e} a {da:e}"
        );
        let y = filtfilt(&b, &a, &floats(&c["x"]));
        let dy = max_abs_diff(&y, &floats(&c["y"]));
        assert!(dy < 1e-9, "filtfilt order {order} fc {fc} fs {fs}: {dy:e}");
        worst = worst.max(dy);
    }
    println!("filtfilt max |rust - scipy| = {worst:e}");
}

#[test]
fn spline_gap_fill_matches_scipy() {
    let f = load("spline.json");
    let mut worst: f64 = 0.0;
    for c in f["cases"].as_array().unwrap() {
        let mut y = floats(&c["y"]);
        let missing: Vec<usize> = c["missing"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap() as usize)
            .collect();
        let want = floats(&c["filled"]);
        let left = CubicSplineFill.fill(&mut y, usize::MAX);
        assert!(left.is_empty());
        let got: Vec<f64> = missing.iter().map(|&i| y[i]).collect();
        let d = max_abs_diff(&got, &want);
        assert!(d < 1e-9, "n {}: {d:e}", y.len());
        worst = worst.max(d);
    }
    println!("spline max |rust - scipy| = {worst:e}");
}
