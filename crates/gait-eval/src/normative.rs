//! Normative (healthy adult) gait curves and spatiotemporal ranges: the grey
//! band of the gait graphs and the reference of the gait scores.
//!
//! Built-in sets live in `data/normative/` (source, licence and how they were
//! made: its README); a lab can give its own CSV in the same layout.

use std::path::Path;

use crate::EvalError;

/// The header a normative curves file must have.
pub const CURVES_HEADER: &str = "joint,percent,mean,sd";
/// The header of a normative spatiotemporal file.
pub const PARAMS_HEADER: &str = "parameter,mean,sd,unit";
/// Joints a normative curves file must cover, 101 rows each (percent 0..100).
pub const JOINTS: [&str; 3] = ["hip", "knee", "ankle"];

/// A normative set: one mean and SD curve per sagittal joint, and
/// spatiotemporal means and SDs where the source has them.
#[derive(Debug, Clone, PartialEq)]
pub struct Normative {
    /// Built-in name or file path, as configured.
    pub name: String,
    /// Where the numbers come from (citation), shown under the graphs.
    pub source: String,
    pub curves: Vec<NormCurve>,
    pub params: Vec<NormParam>,
}

/// Mean and SD of one joint angle over 0..100 % of the cycle (101 points).
#[derive(Debug, Clone, PartialEq)]
pub struct NormCurve {
    pub joint: String,
    pub mean: Vec<f64>,
    pub sd: Vec<f64>,
}

/// Healthy mean and SD of one spatiotemporal parameter, in SI-like units
/// (steps/min, s, %, m, m/s).
#[derive(Debug, Clone, PartialEq)]
pub struct NormParam {
    pub parameter: String,
    pub mean: f64,
    pub sd: f64,
    pub unit: String,
}

/// One built-in set (listed in `normative_data.rs`): name, curves CSV,
/// spatiotemporal CSV, citation.
pub(crate) struct Builtin {
    pub name: &'static str,
    pub curves: &'static str,
    pub params: &'static str,
    pub source: &'static str,
}

const BUILTINS: &[Builtin] = crate::normative_data::BUILTINS;

/// Names of the built-in sets, the first being the default.
pub fn builtin_names() -> Vec<&'static str> {
    BUILTINS.iter().map(|b| b.name).collect()
}

impl Normative {
    /// A built-in set by name, or a lab's CSV when `choice` names a file (ends
    /// in `.csv`); a lab file `X.csv` may have spatiotemporal norms beside it
    /// in `X_spatiotemporal.csv`.
    pub fn load(choice: &str) -> Result<Normative, EvalError> {
        if let Some(b) = BUILTINS.iter().find(|b| b.name == choice) {
            let origin = Path::new(b.name);
            return Ok(Normative {
                name: b.name.into(),
                source: b.source.into(),
                curves: parse_curves(origin, b.curves)?,
                params: parse_params(origin, b.params)?,
            });
        }
        if !choice.ends_with(".csv") {
            return Err(EvalError::Option {
                key: "normative",
                reason: format!(
                    "`{choice}` is neither a built-in set ({}) nor a .csv file",
                    builtin_names().join(", ")
                ),
            });
        }
        let path = Path::new(choice);
        let text = std::fs::read_to_string(path).map_err(|e| {
            EvalError::input(
                path,
                format!("cannot read the normative file ({e}); expected a CSV with the header `{CURVES_HEADER}`"),
            )
        })?;
        let side_file = path.with_file_name(format!(
            "{}_spatiotemporal.csv",
            path.file_stem().and_then(|s| s.to_str()).unwrap_or("")
        ));
        let params = match std::fs::read_to_string(&side_file) {
            Ok(t) => parse_params(&side_file, &t)?,
            Err(_) => vec![],
        };
        Ok(Normative {
            name: choice.into(),
            source: format!("lab file {choice}"),
            curves: parse_curves(path, &text)?,
            params,
        })
    }

    /// The curve of `joint`, if the set has it.
    pub fn curve(&self, joint: &str) -> Option<&NormCurve> {
        self.curves.iter().find(|c| c.joint == joint)
    }

    /// The GVS a healthy walker of the normative population is expected to
    /// get: the RMS over the cycle of the between-subject SD (a walker one SD
    /// off the mean everywhere). No healthy-adult sagittal GPS is published
    /// for 2-D video, so this is the reference the report draws.
    pub fn expected_gvs(&self, joint: &str) -> Option<f64> {
        let c = self.curve(joint)?;
        let ss: f64 = c.sd.iter().map(|s| s * s).sum();
        Some((ss / c.sd.len() as f64).sqrt())
    }

    /// The sagittal GPS of that expected healthy walker (RMS of the three
    /// expected GVS): about 6 degrees for Schwartz 2008 at free speed.
    pub fn expected_gps(&self) -> Option<f64> {
        let g: Option<Vec<f64>> = JOINTS.iter().map(|j| self.expected_gvs(j)).collect();
        let g = g?;
        Some((g.iter().map(|v| v * v).sum::<f64>() / g.len() as f64).sqrt())
    }

    /// The norm of a spatiotemporal parameter, if the set has it.
    pub fn param(&self, parameter: &str) -> Option<&NormParam> {
        self.params.iter().find(|p| p.parameter == parameter)
    }
}

fn rows<'a>(
    path: &Path,
    text: &'a str,
    header: &str,
) -> Result<impl Iterator<Item = (usize, Vec<&'a str>)>, EvalError> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let first = lines.next().map(|(_, l)| l.trim()).unwrap_or("");
    if first != header {
        return Err(EvalError::input(
            path,
            format!("the header is `{first}`; expected `{header}`"),
        ));
    }
    Ok(lines.map(|(i, l)| (i + 1, l.split(',').map(str::trim).collect())))
}

fn number(path: &Path, line: usize, what: &str, s: &str) -> Result<f64, EvalError> {
    s.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| EvalError::input(path, format!("line {line}: {what} `{s}` is not a number")))
}

fn parse_curves(path: &Path, text: &str) -> Result<Vec<NormCurve>, EvalError> {
    let mut curves: Vec<NormCurve> = JOINTS
        .iter()
        .map(|j| NormCurve {
            joint: j.to_string(),
            mean: vec![],
            sd: vec![],
        })
        .collect();
    for (line, cells) in rows(path, text, CURVES_HEADER)? {
        let [joint, percent, mean, sd] = cells[..] else {
            return Err(EvalError::input(
                path,
                format!(
                    "line {line}: {} cells; expected 4 ({CURVES_HEADER})",
                    cells.len()
                ),
            ));
        };
        let Some(c) = curves.iter_mut().find(|c| c.joint == joint) else {
            return Err(EvalError::input(
                path,
                format!(
                    "line {line}: unknown joint `{joint}`; expected one of {}",
                    JOINTS.join(", ")
                ),
            ));
        };
        if percent != c.mean.len().to_string() {
            return Err(EvalError::input(
                path,
                format!(
                    "line {line}: percent `{percent}` for the {joint}; expected {} (rows 0..100 in order)",
                    c.mean.len()
                ),
            ));
        }
        c.mean.push(number(path, line, "mean", mean)?);
        c.sd.push(number(path, line, "sd", sd)?);
    }
    if let Some(c) = curves.iter().find(|c| c.mean.len() != 101) {
        return Err(EvalError::input(
            path,
            format!(
                "the {} has {} rows; expected 101 (percent 0..100) for each of {} under `{CURVES_HEADER}`",
                c.joint,
                c.mean.len(),
                JOINTS.join(", ")
            ),
        ));
    }
    Ok(curves)
}

fn parse_params(path: &Path, text: &str) -> Result<Vec<NormParam>, EvalError> {
    let mut out = Vec::new();
    for (line, cells) in rows(path, text, PARAMS_HEADER)? {
        let [parameter, mean, sd, unit] = cells[..] else {
            return Err(EvalError::input(
                path,
                format!(
                    "line {line}: {} cells; expected 4 ({PARAMS_HEADER})",
                    cells.len()
                ),
            ));
        };
        out.push(NormParam {
            parameter: parameter.into(),
            mean: number(path, line, "mean", mean)?,
            sd: number(path, line, "sd", sd)?,
            unit: unit.into(),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lab_csv(rows_per_joint: usize) -> String {
        let mut s = format!("{CURVES_HEADER}\n");
        for j in JOINTS {
            for p in 0..rows_per_joint {
                s.push_str(&format!("{j},{p},{}.5,2\n", p % 7));
            }
        }
        s
    }

    #[test]
    fn every_builtin_loads() {
        for name in builtin_names() {
            let n = Normative::load(name).unwrap();
            assert_eq!(n.curves.len(), 3, "{name}");
            assert!(
                n.curves
                    .iter()
                    .all(|c| c.mean.len() == 101 && c.sd.len() == 101)
            );
            assert!(!n.source.is_empty());
        }
    }

    #[test]
    fn a_lab_file_and_its_errors() {
        let dir = tempfile::tempdir().unwrap();
        let good = dir.path().join("lab.csv");
        std::fs::write(&good, lab_csv(101)).unwrap();
        std::fs::write(
            dir.path().join("lab_spatiotemporal.csv"),
            format!("{PARAMS_HEADER}\ncadence,110,8,steps/min\n"),
        )
        .unwrap();
        let n = Normative::load(good.to_str().unwrap()).unwrap();
        assert_eq!(n.curve("knee").unwrap().mean[8], 1.5);
        assert_eq!(n.param("cadence").unwrap().mean, 110.0);

        let short = dir.path().join("short.csv");
        std::fs::write(&short, lab_csv(100)).unwrap();
        let e = Normative::load(short.to_str().unwrap())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("short.csv") && e.contains("expected 101") && e.contains(CURVES_HEADER),
            "{e}"
        );

        let wrong = dir.path().join("wrong.csv");
        std::fs::write(&wrong, "joint,pct,mean,sd\nhip,0,1,1\n").unwrap();
        let e = Normative::load(wrong.to_str().unwrap())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("wrong.csv") && e.contains("expected `joint,percent,mean,sd`"),
            "{e}"
        );

        let e = Normative::load(dir.path().join("missing.csv").to_str().unwrap())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("missing.csv") && e.contains(CURVES_HEADER),
            "{e}"
        );
        let e = Normative::load("nosuchset").unwrap_err().to_string();
        assert!(e.contains("normative") && e.contains("built-in"), "{e}");
        assert!(!e.contains('\n'));
    }
}
