//! `metrics.csv`, `metrics.json` and `table.md` (the layout of the paper's Table 1).

use std::path::{Path, PathBuf};

use crate::fsutil::{ensure_dir, write_atomic};
use crate::options::Role;
use crate::stats::Stat;
use crate::{EvalError, Evaluation};

fn distinct<'a>(items: impl Iterator<Item = &'a str>) -> Vec<&'a str> {
    let mut out: Vec<&str> = Vec::new();
    for i in items {
        if !out.contains(&i) {
            out.push(i);
        }
    }
    out
}

fn group_of(e: &Evaluation) -> &str {
    e.options.group.as_deref().unwrap_or("–")
}

/// The paper's Table 1: rows metric x group x leg (prosthetic, intact),
/// one column per method with "MAE (SD)"; evaluations of one method and
/// group (e.g. several camera views) are pooled. The lowest MAE of a row is
/// bold when there are several methods.
pub fn table_markdown(evals: &[Evaluation]) -> String {
    let methods = distinct(evals.iter().map(|e| e.options.method.as_str()));
    let groups = distinct(evals.iter().map(group_of));
    let mut out = String::from("| Metrics (Units) | Amputation Type | Leg |");
    for m in &methods {
        out.push_str(&format!(" {m} (MAE) |"));
    }
    out.push_str("\n|---|---|---|");
    out.push_str(&"---|".repeat(methods.len()));
    out.push('\n');
    type Pick = fn(&Evaluation, Role) -> Option<Stat>;
    let coords: Pick = |e, r| e.legs.iter().find(|l| l.role == r).map(|l| l.stat);
    let kin: Pick = |e, r| {
        e.kinematics
            .as_ref()?
            .legs
            .iter()
            .find(|l| l.role == r)
            .map(|l| l.stat)
    };
    for (metric, pick) in [
        ("Joint Coordinates (pixels)", coords),
        ("Joint Kinematics (°)", kin),
    ] {
        for g in &groups {
            for role in [Role::Prosthetic, Role::Intact] {
                let cells: Vec<Stat> = methods
                    .iter()
                    .map(|m| {
                        let parts: Vec<Stat> = evals
                            .iter()
                            .filter(|e| e.options.method == *m && group_of(e) == *g)
                            .filter_map(|e| pick(e, role))
                            .collect();
                        Stat::pool(&parts)
                    })
                    .collect();
                let best = cells
                    .iter()
                    .filter_map(|s| s.mean)
                    .fold(f64::INFINITY, f64::min);
                let role_name = if role == Role::Prosthetic {
                    "Prosthetic"
                } else {
                    "Intact"
                };
                out.push_str(&format!("| {metric} | {g} | {role_name} |"));
                for c in &cells {
                    let text = c.cell();
                    if methods.len() > 1 && c.mean == Some(best) {
                        out.push_str(&format!(" **{text}** |"));
                    } else {
                        out.push_str(&format!(" {text} |"));
                    }
                }
                out.push('\n');
            }
        }
    }
    out
}

fn num(v: Option<f64>) -> String {
    v.map(|x| format!("{x}")).unwrap_or_default()
}

/// Long-format CSV: one row per keypoint, leg, joint and failure mode.
pub fn metrics_csv(evals: &[Evaluation]) -> Result<String, EvalError> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let wrap = |e: csv::Error| EvalError::io("formatting metrics.csv", e.into());
    w.write_record([
        "method", "group", "view", "metric", "name", "side", "role", "unit", "n", "mean", "sd",
    ])
    .map_err(wrap)?;
    for e in evals {
        let o = &e.options;
        let mut row = |metric: &str,
                       name: &str,
                       side: &str,
                       role: &str,
                       unit: &str,
                       n: usize,
                       mean: Option<f64>,
                       sd: Option<f64>| {
            w.write_record([
                o.method.as_str(),
                o.group.as_deref().unwrap_or(""),
                o.view.as_deref().unwrap_or(""),
                metric,
                name,
                side,
                role,
                unit,
                &n.to_string(),
                &num(mean),
                &num(sd),
            ])
        };
        for k in &e.keypoints {
            let (side, role) = (
                k.side.map(|s| s.as_str()).unwrap_or(""),
                k.role.map(Role::as_str).unwrap_or(""),
            );
            row(
                "keypoint", &k.name, side, role, "px", k.px.n, k.px.mean, k.px.sd,
            )
            .map_err(wrap)?;
        }
        for l in &e.legs {
            row(
                "leg_keypoints",
                "leg",
                l.side.as_str(),
                l.role.as_str(),
                "px",
                l.stat.n,
                l.stat.mean,
                l.stat.sd,
            )
            .map_err(wrap)?;
        }
        if let Some(k) = &e.kinematics {
            for j in &k.joints {
                row(
                    "joint_angle",
                    &j.joint,
                    j.side.as_str(),
                    j.role.as_str(),
                    "deg",
                    j.deg.n,
                    j.deg.mean,
                    j.deg.sd,
                )
                .map_err(wrap)?;
            }
            for l in &k.legs {
                row(
                    "leg_kinematics",
                    "leg",
                    l.side.as_str(),
                    l.role.as_str(),
                    "deg",
                    l.stat.n,
                    l.stat.mean,
                    l.stat.sd,
                )
                .map_err(wrap)?;
            }
        }
        let f = &e.failures;
        for (name, c) in [
            ("not_identified", &f.not_identified),
            ("swapped", &f.swapped),
            ("misidentified", &f.misidentified),
            ("any", &f.any),
        ] {
            row(
                "failure",
                name,
                "",
                "",
                "percent_of_frames",
                c.frames,
                Some(c.percent),
                None,
            )
            .map_err(wrap)?;
        }
        for s in &f.by_side {
            for (name, c) in [
                ("not_identified", &s.not_identified),
                ("misidentified", &s.misidentified),
            ] {
                row(
                    "failure",
                    name,
                    s.side.as_str(),
                    s.role.as_str(),
                    "percent_of_frames",
                    c.frames,
                    Some(c.percent),
                    None,
                )
                .map_err(wrap)?;
            }
        }
    }
    let bytes = w.into_inner().map_err(|e| {
        EvalError::io(
            "formatting metrics.csv",
            std::io::Error::other(e.to_string()),
        )
    })?;
    String::from_utf8(bytes)
        .map_err(|e| EvalError::io("formatting metrics.csv", std::io::Error::other(e)))
}

/// Writes `metrics.csv`, `metrics.json` (the evaluation, or an array of them
/// when there are several) and `table.md` into `out_dir`; returns their paths.
pub fn write_eval(evals: &[Evaluation], out_dir: &Path) -> Result<Vec<PathBuf>, EvalError> {
    ensure_dir(out_dir)?;
    let json = match evals {
        [one] => serde_json::to_string_pretty(one),
        many => serde_json::to_string_pretty(many),
    }
    .map_err(|e| EvalError::io("formatting metrics.json", e.into()))?;
    let files = [
        ("metrics.csv", metrics_csv(evals)?),
        ("metrics.json", json),
        ("table.md", table_markdown(evals)),
    ];
    let mut paths = Vec::new();
    for (name, text) in files {
        let p = out_dir.join(name);
        write_atomic(&p, text.as_bytes())?;
        paths.push(p);
    }
    Ok(paths)
}
