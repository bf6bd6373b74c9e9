//! Progress across a subject's visits: each checklist item's measure visit by visit, and a
//! change called only where it exceeds what the spread between the cycles of the two visits
//! (and, for timing, the minimal detectable change of re-encoding and pose noise) could make.
//!
//! Rule: between consecutive visits a and b with means m, SDs s and counts n, the difference
//! m_b - m_a is a change when it exceeds 1.96 x sqrt(s_a^2 / n_a + s_b^2 / n_b) (a two-sided
//! 95 % test of the two means; a visit with a single cycle, whose SD is unknown, gives no
//! call) and the measure's floor ([`floor`]): the minimal detectable change of re-encoding
//! and keypoint noise where the robustness matrix measured it, else the error of the measure
//! under pose-model jitter.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::VisitError;

/// Who and when a visit was (visit.json).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct VisitLabel {
    pub subject: String,
    pub session: String,
    /// ISO 8601, or empty.
    pub date: String,
    /// "left" or "right" when set (written by the visit, for the progress figure).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prosthetic: Option<String>,
}

/// One checklist row of a visit: (item, side) -> (value, SD, n, unit, verdict).
#[derive(Debug, Clone)]
struct Row {
    item: String,
    side: String,
    value: f64,
    sd: f64,
    n: usize,
    unit: String,
    verdict: String,
}

/// A visit folder's label and checklist.
#[derive(Debug, Clone)]
pub struct VisitRecord {
    pub dir: PathBuf,
    pub label: VisitLabel,
    rows: Vec<Row>,
}

fn io(path: &Path, e: impl std::fmt::Display) -> VisitError {
    VisitError::Pass {
        dir: path.to_path_buf(),
        message: e.to_string(),
    }
}

impl VisitRecord {
    /// Reads a visit folder (visit.json and visit_checklist.csv).
    pub fn read(dir: &Path) -> Result<Self, VisitError> {
        let label: VisitLabel = std::fs::read_to_string(dir.join("visit.json"))
            .map_err(|e| io(dir, format!("not a visit folder (visit.json: {e})")))
            .and_then(|t| serde_json::from_str(&t).map_err(|e| io(dir, e)))?;
        let path = dir.join("visit_checklist.csv");
        let mut r = csv::Reader::from_path(&path).map_err(|e| io(&path, e))?;
        let h: Vec<String> = r
            .headers()
            .map_err(|e| io(&path, e))?
            .iter()
            .map(String::from)
            .collect();
        let c = |name: &str| {
            h.iter()
                .position(|x| x == name)
                .ok_or_else(|| io(&path, format!("no `{name}` column")))
        };
        let (item, side, value, sd, n, unit, verdict) = (
            c("item")?,
            c("side")?,
            c("value")?,
            c("spread")?,
            c("n")?,
            c("unit")?,
            c("verdict")?,
        );
        let num = |s: &str| s.parse().unwrap_or(f64::NAN);
        let rows = r
            .records()
            .map(|rec| {
                rec.map(|x| Row {
                    item: x[item].into(),
                    side: x[side].into(),
                    value: num(&x[value]),
                    sd: num(&x[sd]),
                    n: x[n].parse().unwrap_or(0),
                    unit: x[unit].into(),
                    verdict: x[verdict].into(),
                })
                .map_err(|e| io(&path, e))
            })
            .collect::<Result<_, _>>()?;
        Ok(Self {
            dir: dir.to_path_buf(),
            label,
            rows,
        })
    }

    pub(crate) fn name(&self) -> String {
        match self.label.date.as_str() {
            "" => format!("session {}", self.label.session),
            d => format!("{d} (session {})", self.label.session),
        }
    }
}

/// A change between two consecutive visits.
#[derive(Debug, Clone, Serialize)]
pub struct Change {
    pub item: String,
    pub side: String,
    pub from: String,
    pub to: String,
    pub difference: f64,
    /// The smallest difference called a change here.
    pub limit: f64,
    pub unit: String,
    /// `change` or `no change`, or `not judged: REASON`.
    pub call: String,
}

/// The smallest difference ever called a change for `item` in `unit`, and where it comes from:
/// the larger of the item's video MDC95 and its unit's floor. The MDC95 is the robustness
/// matrix's on the bundled sample (gait-eval's reliability table: re-encodings, resampling,
/// rescaling, mirroring and keypoint noise of one walk), measured for the side-view items. The
/// unit's floor: 2 deg for angles, the frontal angles' error under BlazePose-level jitter on
/// projected motion capture (1-2.6 deg, BENCHMARKS.md) and the sample's hip peak MDC95 (2.0-3.2
/// deg); 2 cm for lengths, the step width's accuracy target (0.025 leg lengths without a scale;
/// 2.5 % of the leg for heights and shifts in % of the leg: vaulting, whips).
pub fn floor(item: &str, unit: &str) -> (f64, &'static str) {
    let own = match unit {
        "deg" => (2.0, "2 deg: the angles' error under pose-model jitter"),
        "cm" => (2.0, "2 cm: the step width's accuracy"),
        "leg" => (0.025, "0.025 leg lengths: the step width's accuracy"),
        "% leg" => (2.5, "2.5 % of the leg: the step width's accuracy"),
        _ => (0.0, ""),
    };
    match gait_eval::reliability::checklist_mdc(item, unit) {
        Some(m) if m > own.0 => (m, "MDC95 of re-encoding and keypoint noise"),
        _ => own,
    }
}

/// Why two visits' values of an item cannot be compared, if they cannot: lengths in image
/// pixels change with the camera's distance and the video's size, and values in different
/// units (one visit with a known height, one without) are different measures.
fn incomparable(a: &Row, b: &Row) -> Option<String> {
    if a.unit.starts_with("px") {
        return Some(
            "not judged: image pixels change with the camera's distance and the video's size (set kinematics.subject_height_m for centimetres)".into(),
        );
    }
    (a.unit != b.unit).then(|| format!("not judged: {} against {}", a.unit, b.unit))
}

/// The changes between consecutive visits (in the order given) for every item and side both
/// measured.
pub fn changes(visits: &[VisitRecord]) -> Vec<Change> {
    let mut out = Vec::new();
    for w in visits.windows(2) {
        for a in w[0].rows.iter().filter(|r| r.value.is_finite()) {
            let Some(b) = w[1]
                .rows
                .iter()
                .find(|r| r.item == a.item && r.side == a.side && r.value.is_finite())
            else {
                continue;
            };
            let d = b.value - a.value;
            let se = (a.sd.powi(2) / a.n as f64 + b.sd.powi(2) / b.n as f64).sqrt();
            let limit = (1.96 * se).max(floor(&a.item, &a.unit).0);
            let call = if let Some(why) = incomparable(a, b) {
                why
            } else if !limit.is_finite() || a.n < 2 || b.n < 2 {
                "not judged: a visit with fewer than 2 cycles has no spread".to_string()
            } else if d.abs() > limit {
                "change".into()
            } else {
                "no change".into()
            };
            out.push(Change {
                item: a.item.clone(),
                side: a.side.clone(),
                from: w[0].name(),
                to: w[1].name(),
                difference: d,
                limit,
                unit: a.unit.clone(),
                call,
            });
        }
    }
    out
}

/// Orders visits by date (ISO 8601 sorts as text), then session.
pub fn order(visits: &mut [VisitRecord]) {
    visits.sort_by(|a, b| {
        (a.label.date.as_str(), a.label.session.as_str())
            .cmp(&(b.label.date.as_str(), b.label.session.as_str()))
    });
}

fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.2}")
    } else {
        String::new()
    }
}

/// progress.csv and progress.html of `visits` (ordered) into `out`.
pub fn write(out: &Path, visits: &[VisitRecord]) -> Result<Vec<Change>, VisitError> {
    let changes = changes(visits);
    std::fs::create_dir_all(out).map_err(|source| VisitError::Io {
        path: out.to_path_buf(),
        source,
    })?;
    let mut csv = String::from("item,side,from,to,difference,limit,unit,call\n");
    for c in &changes {
        csv.push_str(&format!(
            "{},{},{},{},{},{},{},{}\n",
            c.item,
            c.side,
            c.from,
            c.to,
            num(c.difference),
            num(c.limit),
            c.unit,
            c.call
        ));
    }
    std::fs::write(out.join("progress.csv"), csv).map_err(|source| VisitError::Io {
        path: out.join("progress.csv"),
        source,
    })?;
    let subject = visits.first().map_or("", |v| v.label.subject.as_str());
    let mut html = format!(
        "<!doctype html><html><head><meta charset=\"utf-8\"><title>Progress: {subject}</title><style>body{{font-family:sans-serif;max-width:1100px;margin:24px auto}}table{{border-collapse:collapse}}td,th{{border:1px solid #ccc;padding:3px 6px;font-size:13px}}td.change{{font-weight:bold}}</style></head><body><h1>Progress across visits: {subject}</h1><p>Each checklist measure visit by visit (mean ± SD over its cycles, n cycles). A difference between two visits is called a change when it exceeds 1.96 × √(SD₁²/n₁ + SD₂²/n₂), the spread the cycles of the two visits alone could make, and the measure's floor: the larger of its minimal detectable change under re-encoding and keypoint noise (measured for the side-view items) and 2 deg for angles (their error under pose-model jitter), 2 cm for lengths, 2.5 % of the leg for heights in % of the leg; visits with one cycle are not judged, nor are lengths in image pixels (they change with the camera's distance and the video's size) or values in different units.</p><table><tr><th>Item</th><th>Side</th>"
    );
    for v in visits {
        html.push_str(&format!("<th>{}</th>", v.name()));
    }
    html.push_str("<th>Changes</th></tr>");
    let mut keys: Vec<(String, String)> = visits
        .iter()
        .flat_map(|v| v.rows.iter().map(|r| (r.item.clone(), r.side.clone())))
        .collect();
    keys.dedup();
    let mut seen = Vec::new();
    for key in keys {
        if seen.contains(&key)
            || !visits.iter().any(|v| {
                v.rows
                    .iter()
                    .any(|r| (r.item.clone(), r.side.clone()) == key && r.value.is_finite())
            })
        {
            continue;
        }
        seen.push(key.clone());
        html.push_str(&format!(
            "<tr><td>{}</td><td>{}</td>",
            key.0.replace('_', " "),
            key.1
        ));
        for v in visits {
            let cell = v
                .rows
                .iter()
                .find(|r| r.item == key.0 && r.side == key.1)
                .map_or(String::new(), |r| {
                    if r.value.is_finite() {
                        format!(
                            "{} ± {} {} (n={}; {})",
                            num(r.value),
                            num(r.sd),
                            r.unit,
                            r.n,
                            r.verdict
                        )
                    } else {
                        r.verdict.clone()
                    }
                });
            html.push_str(&format!("<td>{cell}</td>"));
        }
        let calls: Vec<String> = changes
            .iter()
            .filter(|c| c.item == key.0 && c.side == key.1)
            .map(|c| {
                format!(
                    "{} → {}: {:+.2} (limit {}) {}",
                    c.from,
                    c.to,
                    c.difference,
                    num(c.limit),
                    c.call
                )
            })
            .collect();
        let class = if calls
            .iter()
            .any(|c| c.ends_with(" change") && !c.ends_with(" no change"))
        {
            " class=\"change\""
        } else {
            ""
        };
        html.push_str(&format!("<td{class}>{}</td></tr>", calls.join("<br>")));
    }
    html.push_str("</table>");
    let norm = gait_eval::report_config::ReportConfig::default()
        .load_normative()
        .ok()
        .flatten();
    let prosthetic = visits
        .iter()
        .find_map(|v| v.label.prosthetic.as_deref())
        .and_then(|s| match s {
            "left" => Some(gait_eval::Side::Left),
            "right" => Some(gait_eval::Side::Right),
            _ => None,
        });
    html.push_str(&crate::outcomes::html(visits, norm.as_ref(), prosthetic)?);
    html.push_str("</body></html>");
    std::fs::write(out.join("progress.html"), html).map_err(|source| VisitError::Io {
        path: out.join("progress.html"),
        source,
    })?;
    Ok(changes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn visit(session: &str, value: f64, sd: f64, n: usize) -> VisitRecord {
        VisitRecord {
            dir: PathBuf::new(),
            label: VisitLabel {
                subject: "S".into(),
                session: session.into(),
                date: String::new(),
                prosthetic: None,
            },
            rows: vec![Row {
                item: "hip_hiking".into(),
                side: "right".into(),
                value,
                sd,
                n,
                unit: "deg".into(),
                verdict: "absent".into(),
            }],
        }
    }

    /// 2.5 deg apart with SDs of 1 deg over 4 cycles each: 1.96 x sqrt(1/4 + 1/4) = 1.39 deg,
    /// under the 2 deg floor, so the floor decides: a change; with SDs of 2 deg over 2 cycles
    /// the limit is 3.92 deg: none; a difference under the floor is none however small the SDs.
    #[test]
    fn a_change_must_exceed_the_spread_of_the_cycles_and_the_floor() {
        let calls = |a: VisitRecord, b: VisitRecord| changes(&[a, b])[0].call.clone();
        assert_eq!(
            calls(visit("1", 3.0, 1.0, 4), visit("2", 5.5, 1.0, 4)),
            "change"
        );
        assert_eq!(
            calls(visit("1", 3.0, 2.0, 2), visit("2", 5.5, 2.0, 2)),
            "no change"
        );
        assert_eq!(
            calls(visit("1", 3.0, 0.01, 4), visit("2", 4.5, 0.01, 4)),
            "no change"
        );
        assert!(
            calls(visit("1", 3.0, f64::NAN, 1), visit("2", 9.0, 1.0, 4)).starts_with("not judged")
        );
    }

    /// Vaulting in % of the leg on clean motion capture (SDs of a few hundredths): 0.09 % of
    /// the leg, under a millimetre, was called a change before the unit had a floor.
    #[test]
    fn a_height_in_percent_of_the_leg_has_a_floor() {
        let vaulting = |session, value| {
            let mut v = visit(session, value, 0.02, 4);
            v.rows[0].item = "vaulting".into();
            v.rows[0].unit = "% leg".into();
            v
        };
        let c = changes(&[vaulting("1", -0.50), vaulting("2", -0.41)]);
        assert_eq!(c[0].call, "no change");
        let c = changes(&[vaulting("1", -0.50), vaulting("2", -3.5)]);
        let floor = floor("vaulting", "% leg").0;
        let expected = if 3.0 > floor { "change" } else { "no change" };
        assert_eq!(c[0].call, expected, "floor {floor}");
    }

    /// Step lengths in pixels of two visits (the same walk filmed at 1080p and at 720p, or from
    /// another distance) differ by the camera, not the patient: not judged, nor are values in
    /// different units.
    #[test]
    fn pixels_and_different_units_are_not_judged() {
        let of = |session, value, unit: &str| {
            let mut v = visit(session, value, 1.0, 4);
            v.rows[0].item = "uneven_step_length".into();
            v.rows[0].unit = unit.into();
            v
        };
        let c = changes(&[of("1", 175.0, "px"), of("2", 126.0, "px")]);
        assert!(
            c[0].call.starts_with("not judged: image pixels"),
            "{}",
            c[0].call
        );
        let c = changes(&[of("1", 70.0, "cm"), of("2", 0.8, "leg")]);
        assert_eq!(c[0].call, "not judged: cm against leg");
    }
}
