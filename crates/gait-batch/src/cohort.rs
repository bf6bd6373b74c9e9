//! `cohort.csv`: one row per video and side (a failed video, or one with no result: one row with
//! the error or the reason), from the files each run folder holds.

use std::path::Path;

use gait_eval::plot::{CycleCurve, read_cycles_csv};
use gait_report::spatiotemporal::read_spatiotemporal;
use serde_json::Value;

use crate::plan::{Plan, PlannedRow, run_dir};
use crate::state;

/// Spatiotemporal parameters copied per side (cadence is for both sides together).
const PARAMS: [&str; 6] = [
    "cadence",
    "stride_time",
    "step_time",
    "stance",
    "stride_length",
    "speed",
];
const JOINTS: [&str; 3] = ["hip", "knee", "ankle"];

/// One row of the cohort table.
#[derive(Debug, Clone)]
pub struct CohortRow {
    pub row: PlannedRow,
    pub side: String,
    pub status: String,
    pub error: String,
    pub accepted: Option<u64>,
    pub rejected: Option<u64>,
    /// Peak and range (max - min) of the mean curve, per joint.
    pub angles: [(f64, f64); 3],
    pub params: [f64; PARAMS.len()],
    pub gps: f64,
    pub warnings: Option<usize>,
    /// The side's mean curves (for cohort.html).
    pub curves: Vec<CycleCurve>,
}

pub fn header() -> String {
    let mut h: Vec<String> = [
        "subject",
        "session",
        "view",
        "video",
        "run",
        "side",
        "prosthetic",
        "status",
        "error",
        "accepted_cycles",
        "rejected_cycles",
    ]
    .map(String::from)
    .to_vec();
    for j in JOINTS {
        h.push(format!("{j}_peak_deg"));
        h.push(format!("{j}_range_deg"));
    }
    h.extend(PARAMS.iter().map(|p| p.to_string()));
    h.push("gps_deg".into());
    h.push("warnings".into());
    h.join(",")
}

fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.4}")
    } else {
        String::new()
    }
}

/// A CSV field: quoted when it holds a comma, quote or line break.
fn field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

impl CohortRow {
    pub fn csv(&self) -> String {
        let r = &self.row;
        let prosthetic = match r.prosthetic_side.as_str() {
            "" => "",
            s if s == self.side => "yes",
            _ => "no",
        };
        let opt = |v: Option<u64>| v.map_or(String::new(), |v| v.to_string());
        let mut cells = vec![
            field(&r.subject),
            field(&r.session),
            field(&r.view),
            field(&r.video.display().to_string()),
            field(&r.name),
            self.side.clone(),
            prosthetic.into(),
            self.status.clone(),
            field(&self.error),
            opt(self.accepted),
            opt(self.rejected),
        ];
        for (peak, range) in self.angles {
            cells.push(num(peak));
            cells.push(num(range));
        }
        cells.extend(self.params.iter().map(|&v| num(v)));
        cells.push(num(self.gps));
        cells.push(self.warnings.map_or(String::new(), |w| w.to_string()));
        cells.join(",")
    }
}

fn read_json(path: &Path) -> Option<Value> {
    serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()
}

/// The (sagittal) GPS of `side` from scores.csv (`score,side,joint,value,unit`).
fn gps(dir: &Path, side: &str) -> f64 {
    let Ok(text) = std::fs::read_to_string(dir.join("scores.csv")) else {
        return f64::NAN;
    };
    text.lines()
        .map(|l| l.split(',').collect::<Vec<_>>())
        .find(|c| c.len() >= 4 && c[0].starts_with("gps") && c[1] == side)
        .and_then(|c| c[3].parse().ok())
        .unwrap_or(f64::NAN)
}

fn peak_and_range(curves: &[CycleCurve], joint: &str) -> (f64, f64) {
    let Some(c) = curves.iter().find(|c| c.joint == joint) else {
        return (f64::NAN, f64::NAN);
    };
    let v = c.mean.iter().copied().filter(|v| v.is_finite());
    let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    if hi >= lo {
        (hi, hi - lo)
    } else {
        (f64::NAN, f64::NAN)
    }
}

/// The rows of one video: two sides when it ran with a result, one with the error or the reason
/// when not.
fn rows_of(out: &Path, row: &PlannedRow, done: bool) -> Vec<CohortRow> {
    let dir = run_dir(out, row);
    let blank = |side: &str, status: &str, error: String| CohortRow {
        row: row.clone(),
        side: side.into(),
        status: status.into(),
        error,
        accepted: None,
        rejected: None,
        angles: [(f64::NAN, f64::NAN); 3],
        params: [f64::NAN; PARAMS.len()],
        gps: f64::NAN,
        warnings: None,
        curves: Vec::new(),
    };
    if !done {
        let (status, error) = match state::failure(out, row) {
            Some(e) => ("failed", e),
            None => ("not run", "the run did not finish".to_string()),
        };
        return vec![blank("", status, error)];
    }
    if let Some(why) = state::no_result(out, row) {
        return vec![blank("", "no result", why)];
    }
    let manifest = read_json(&dir.join("run.json")).unwrap_or_default();
    let curves = read_cycles_csv(&dir.join("cycles.csv")).unwrap_or_default();
    let params = read_spatiotemporal(&dir.join("spatiotemporal.csv")).unwrap_or_default();
    let warnings = manifest
        .get("warnings")
        .and_then(Value::as_array)
        .map(Vec::len);
    ["left", "right"]
        .into_iter()
        .map(|side| {
            let mine: Vec<CycleCurve> = curves
                .iter()
                .filter(|c| c.side.as_str() == side)
                .cloned()
                .collect();
            let count = |k: &str| {
                manifest
                    .pointer(&format!("/extra/kinematics/{k}/{side}"))
                    .and_then(Value::as_u64)
            };
            let param = |p: &str| {
                params
                    .iter()
                    .find(|x| {
                        x.parameter == p && (x.side == side || (p == "cadence" && x.side == "both"))
                    })
                    .map_or(f64::NAN, |x| x.mean)
            };
            CohortRow {
                accepted: count("cycles_accepted"),
                rejected: count("cycles_rejected"),
                angles: JOINTS.map(|j| peak_and_range(&mine, j)),
                params: PARAMS.map(param),
                gps: gps(&dir, side),
                warnings,
                curves: mine,
                ..blank(side, "done", String::new())
            }
        })
        .collect()
}

/// Every row of the plan, in study order.
pub fn collect(out: &Path, plan: &Plan) -> Vec<CohortRow> {
    plan.rows
        .iter()
        .flat_map(|row| {
            let config = Plan::config(out, row).ok();
            let done = state::row_state(out, row, config.as_ref()).finished();
            rows_of(out, row, done)
        })
        .collect()
}

/// cohort.csv's text.
pub fn csv(rows: &[CohortRow]) -> String {
    let mut s = header();
    s.push('\n');
    for r in rows {
        s.push_str(&r.csv());
        s.push('\n');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use gait_eval::Side;

    #[test]
    fn peak_and_range_come_from_the_mean_curve() {
        let c = CycleCurve {
            side: Side::Left,
            joint: "knee".into(),
            percent: vec![0.0, 50.0, 100.0],
            mean: vec![5.0, 62.5, f64::NAN],
            sd: vec![1.0; 3],
            n_cycles: 2,
        };
        assert_eq!(
            peak_and_range(std::slice::from_ref(&c), "knee"),
            (62.5, 57.5)
        );
        assert!(peak_and_range(&[c], "hip").0.is_nan());
    }

    #[test]
    fn the_sagittal_gps_is_read_per_side() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("scores.csv"),
            "score,side,joint,value,unit\ngvs,left,hip,4.5,deg\ngps_sagittal,left,,6.7,deg\ngps_sagittal,right,,4.8,deg\n",
        )
        .unwrap();
        assert_eq!(gps(dir.path(), "left"), 6.7);
        assert_eq!(gps(dir.path(), "right"), 4.8);
        assert!(gps(&dir.path().join("none"), "left").is_nan());
    }

    #[test]
    fn fields_with_commas_are_quoted() {
        assert_eq!(field("a,b \"c\""), "\"a,b \"\"c\"\"\"");
        assert_eq!(field("plain"), "plain");
    }
}
