//! The report's frontal section for a front or back view: which view and how it was decided,
//! a drawing of the sign conventions, gait graphs of the four frontal measures, their per-side
//! scalars with the sides' difference, and step width and circumduction.

use std::path::Path;

use serde_json::Value;

use crate::html::{escape, table};
use crate::report::figure;
use gait_eval::normative::Normative;
use gait_eval::plot::{CycleCurve, GraphContext, frontal_graphs, read_curves_csv};
use gait_eval::{EvalError, Side};

/// The frontal normative bands that go with a sagittal set (its speed stratum).
pub fn norms(sagittal: Option<&str>) -> Option<Normative> {
    gait_eval::normative_frontal::for_sagittal(sagittal)
}

/// What the frontal section shows, read from a run folder's frontal_*.csv files.
#[derive(Debug, Clone, Default)]
pub struct FrontalReport {
    /// `anterior` or `posterior`.
    pub view: String,
    /// How the view was decided (run.json `kinematics.view.how`).
    pub how: String,
    pub curves: Vec<CycleCurve>,
    /// frontal_scalars.csv rows: measure, statistic, side, mean, sd, n, unit.
    pub scalars: Vec<Vec<String>>,
    /// frontal_feet.csv rows: side, measure, first_frame, last_frame, value, unit.
    pub feet: Vec<Vec<String>>,
    /// Frontal normative curves (measure names as `joint`), when a source has them.
    pub normative: Option<Normative>,
}

impl FrontalReport {
    /// The frontal files of `dir`, or `None` for a side view (no frontal_cycles.csv).
    /// `sagittal` names the report's sagittal normative set, whose speed stratum is taken.
    pub fn read(
        dir: &Path,
        manifest: Option<&Value>,
        sagittal: Option<&str>,
    ) -> Result<Option<Self>, EvalError> {
        let cycles = dir.join("frontal_cycles.csv");
        if !cycles.exists() {
            return Ok(None);
        }
        let view = manifest.and_then(|m| m.pointer("/kinematics/view"));
        let from_run = |key: &str| {
            view.and_then(|v| v.get(key))
                .and_then(Value::as_str)
                .map(str::to_string)
        };
        // `gait kin` writes no run.json: frontal_view.csv says the same.
        let file = rows(&dir.join("frontal_view.csv"))?;
        let from_file = |col: usize| file.first().and_then(|r| r.get(col)).cloned();
        Ok(Some(Self {
            view: from_run("view")
                .or_else(|| from_file(0))
                .unwrap_or_default(),
            how: from_run("how").or_else(|| from_file(2)).unwrap_or_default(),
            curves: read_curves_csv(&cycles, "measure")?,
            scalars: rows(&dir.join("frontal_scalars.csv"))?,
            feet: rows(&dir.join("frontal_feet.csv"))?,
            normative: gait_eval::normative_frontal::for_sagittal(sagittal),
        }))
    }

    /// The section's HTML.
    pub fn html(&self, prosthetic: Option<Side>) -> Result<String, EvalError> {
        let mut body = format!(
            "<h2 id=\"frontal\">Frontal plane ({} view)</h2><p>View: {}.</p>",
            escape(&self.view),
            escape(&self.how)
        );
        body.push_str(CONVENTIONS);
        if self.curves.is_empty() {
            body.push_str("<p class=\"no-cycles\">No frontal mean curves: fewer accepted cycles per side than kinematics.min_cycles (see Warnings and Cycle quality).</p>");
        } else {
            let ctx = GraphContext {
                prosthetic,
                normative: self.normative.as_ref(),
                toe_off: [None, None],
            };
            let norm = match &self.normative {
                Some(n) => format!(
                    "Grey band: normative mean ± 1 SD where the source has the measure ({}); trunk lean has none. ",
                    n.source
                ),
                None => "No normative band: no redistributable frontal norm is bundled. ".into(),
            };
            let fig = frontal_graphs(&self.curves, ctx)?;
            body.push_str(&figure(
                &fig,
                &format!("Mean (line) ± SD (band) over the accepted cycles, left red, right blue, from each side's heel strike. {norm}"),
            ));
        }
        body.push_str(&self.scalar_table(prosthetic));
        body.push_str(&self.feet_table());
        Ok(body)
    }

    /// One row per measure and statistic: each side's mean ± SD over its cycles and the
    /// difference between the sides (frontal_scalars.csv laid out side by side).
    fn scalar_table(&self, prosthetic: Option<Side>) -> String {
        if self.scalars.is_empty() {
            return String::new();
        }
        let name = |s: Side| match prosthetic {
            Some(p) if p == s => format!("{} (prosthetic)", s.as_str()),
            Some(_) => format!("{} (intact)", s.as_str()),
            None => s.as_str().to_string(),
        };
        let diff_label = if prosthetic.is_some() {
            "Prosthetic − intact"
        } else {
            "Left − right"
        };
        let cell = |measure: &str, stat: &str, side: &str| {
            self.scalars
                .iter()
                .find(|r| r[0] == measure && r[1] == stat && r[2] == side)
                .map(|r| {
                    let f = fmt_row(r, &[3, 4]);
                    match (f[3].as_str(), f[4].as_str()) {
                        ("", _) => String::new(),
                        (m, "") => m.to_string(),
                        (m, sd) => format!("{m} ± {sd} (n={})", r[5]),
                    }
                })
                .unwrap_or_default()
        };
        let mut rows = Vec::new();
        let mut seen: Vec<(&str, &str)> = Vec::new();
        for r in &self.scalars {
            let key = (r[0].as_str(), r[1].as_str());
            if seen.contains(&key) {
                continue;
            }
            seen.push(key);
            let diff = self
                .scalars
                .iter()
                .find(|x| x[0] == key.0 && x[1] == key.1 && x[2].contains("minus"))
                .map(|x| fmt_row(x, &[3])[3].clone())
                .unwrap_or_default();
            rows.push(vec![
                key.0.replace('_', " "),
                key.1.into(),
                cell(key.0, key.1, "left"),
                cell(key.0, key.1, "right"),
                diff,
            ]);
        }
        let header = [
            "Measure (deg)".to_string(),
            "Per cycle".into(),
            name(Side::Left),
            name(Side::Right),
            diff_label.into(),
        ];
        format!(
            "<h3>Frontal measures per cycle</h3><p>Each cycle's maximum, minimum and range, as mean ± SD over the accepted cycles of each side, and the difference between the sides' means.</p>{}",
            table(&header, &rows)
        )
    }

    /// Step width and circumduction per side: mean ± SD, count, range.
    fn feet_table(&self) -> String {
        if self.feet.is_empty() {
            return "<p>No step width or circumduction: no heel strike inside a walking bout with both heels seen.</p>".into();
        }
        let mut rows = Vec::new();
        for measure in ["step_width", "circumduction"] {
            for side in ["left", "right"] {
                let of: Vec<&Vec<String>> = self
                    .feet
                    .iter()
                    .filter(|r| r[0] == side && r[1] == measure)
                    .collect();
                let v: Vec<f64> = of.iter().filter_map(|r| r[4].parse().ok()).collect();
                if v.is_empty() {
                    continue;
                }
                let st = gait_eval::Stat::of(&v);
                let (mean, sd) = (st.mean.unwrap_or(f64::NAN), st.sd.unwrap_or(f64::NAN));
                let unit = of[0][5].as_str();
                let unit = if unit == "leg" { "leg lengths" } else { unit };
                rows.push(vec![
                    measure.replace('_', " "),
                    side.into(),
                    format!("{mean:.3}"),
                    if sd.is_finite() {
                        format!("{sd:.3}")
                    } else {
                        String::new()
                    },
                    v.len().to_string(),
                    unit.into(),
                ]);
            }
        }
        let header = ["Measure", "Side", "Mean", "SD", "n", "Unit"];
        format!(
            "<h3>Step width and circumduction</h3><p>Step width: the heels' lateral distance at each heel strike of the side; circumduction: the swing ankle's largest lateral excursion from the line joining where the foot stood before and after the swing. Normal walking base 5-10 cm (Northwestern University Prosthetic-Orthotic Center); a wider base is the abducted gait of the amputee checklists. {} Lengths in cm when kinematics.subject_height_m is set, else in leg lengths.</p>{}",
            escape(&gait_eval::normative_frontal::step_width_note()),
            table(&header.map(String::from), &rows)
        )
    }
}

/// Numbers in the given columns to 2 decimals, empty for NaN.
fn fmt_row(r: &[String], numeric: &[usize]) -> Vec<String> {
    r.iter()
        .enumerate()
        .map(|(i, c)| match (numeric.contains(&i), c.parse::<f64>()) {
            (true, Ok(v)) if v.is_finite() => format!("{v:.2}"),
            (true, _) => String::new(),
            _ => c.clone(),
        })
        .collect()
}

/// A CSV's rows as text (no header); none when the file is absent.
fn rows(path: &Path) -> Result<Vec<Vec<String>>, EvalError> {
    if !path.exists() {
        return Ok(Vec::new());
    }
    let mut r = csv::Reader::from_path(path).map_err(|e| EvalError::input(path, e))?;
    r.records()
        .map(|rec| {
            rec.map(|rec| rec.iter().map(str::to_string).collect())
                .map_err(|e| EvalError::input(path, e))
        })
        .collect()
}

/// How the measures are signed, drawn: a walker seen from behind (posterior view), leaning
/// toward the left with the left hip up, the left knee medial.
const CONVENTIONS: &str = r##"<figure id="fig-frontal-conventions" class="plot"><svg xmlns="http://www.w3.org/2000/svg" width="640" height="250" viewBox="0 0 640 250" font-family="sans-serif" font-size="11">
<line x1="130" y1="30" x2="130" y2="120" stroke="#999" stroke-dasharray="4 3"/>
<line x1="130" y1="120" x2="112" y2="38" stroke="#333" stroke-width="3"/>
<circle cx="110" cy="28" r="9" fill="none" stroke="#333" stroke-width="2"/>
<line x1="100" y1="116" x2="160" y2="124" stroke="#333" stroke-width="3"/>
<line x1="100" y1="116" x2="112" y2="178" stroke="#c0392b" stroke-width="3"/>
<line x1="112" y1="178" x2="104" y2="236" stroke="#c0392b" stroke-width="3"/>
<line x1="160" y1="124" x2="158" y2="184" stroke="#2e6fba" stroke-width="3"/>
<line x1="158" y1="184" x2="160" y2="240" stroke="#2e6fba" stroke-width="3"/>
<line x1="60" y1="120" x2="200" y2="120" stroke="#999" stroke-dasharray="4 3"/>
<text x="20" y="20">seen from behind: the subject's left on the image left</text>
<text x="40" y="60">trunk lean +</text><text x="40" y="73">toward the left</text>
<text x="170" y="112">pelvic obliquity: left +</text><text x="170" y="125">(left hip up), right −</text>
<text x="20" y="170">left hip</text><text x="20" y="183">adduction +</text>
<text x="20" y="215">left knee</text><text x="20" y="228">valgus −</text>
<text x="260" y="160" fill="#555">Each side's curves run from that side's heel strike;</text>
<text x="260" y="175" fill="#555">seen from the front the picture is mirrored and the</text>
<text x="260" y="190" fill="#555">signs stay the subject's: + toward, up, medial, varus.</text>
</svg><figcaption>Sign conventions of the frontal measures (left leg red, right leg blue).</figcaption></figure>"##;
