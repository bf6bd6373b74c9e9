//! The spatiotemporal table of the report: each parameter per side, the
//! normative range beside it, and the symmetry index.

use std::path::Path;

use crate::report::Table;
use gait_eval::EvalError;
use gait_eval::Side;
use gait_eval::normative::{NormParam, Normative};

/// One row of gait-kin's `spatiotemporal.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct StParam {
    pub parameter: String,
    /// `left`, `right`, `both`, or `prosthetic_vs_intact` / `left_vs_right`.
    pub side: String,
    pub mean: f64,
    pub sd: f64,
    pub n: usize,
    pub unit: String,
}

/// Reads `spatiotemporal.csv` (`parameter,side,mean,sd,n,unit`).
pub fn read_spatiotemporal(path: &Path) -> Result<Vec<StParam>, EvalError> {
    let mut r = csv::Reader::from_path(path).map_err(|e| EvalError::input(path, e))?;
    let mut out = Vec::new();
    for (i, rec) in r.records().enumerate() {
        let rec = rec.map_err(|e| EvalError::input(path, e))?;
        let cell = |k: usize| rec.get(k).unwrap_or("").trim();
        let num = |k: usize| cell(k).parse::<f64>().unwrap_or(f64::NAN);
        if rec.len() != 6 {
            return Err(EvalError::input(
                path,
                format!("line {}: expected parameter,side,mean,sd,n,unit", i + 2),
            ));
        }
        out.push(StParam {
            parameter: cell(0).into(),
            side: cell(1).into(),
            mean: num(2),
            sd: num(3),
            n: cell(4).parse().unwrap_or(0),
            unit: cell(5).into(),
        });
    }
    Ok(out)
}

/// Parameters in the order a clinician reads them.
const ORDER: [&str; 8] = [
    "cadence",
    "speed",
    "stride_time",
    "step_time",
    "stance",
    "stride_length",
    "step_length",
    "leg_length",
];

fn label(parameter: &str) -> String {
    parameter.replace('_', " ")
}

/// Gravity for Hof's dimensionless parameters (m/s^2).
const G: f64 = 9.81;

/// The norm's mean and SD in our unit `ours`, when they can be compared: the
/// same unit, cm against m, or one of Hof's dimensionless forms scaled by the
/// subject's leg length `leg` (value, unit; speed and cadence need it in cm).
fn norm_in(ours: &str, n: &NormParam, leg: Option<(f64, &str)>) -> Option<(f64, f64)> {
    let factor = match (ours, n.unit.as_str(), leg) {
        (a, b, _) if a == b => 1.0,
        ("cm", "m", _) | ("cm/s", "m/s", _) => 100.0,
        (a, "s/L", Some((l, u))) if a == u => l,
        ("cm/s", "v/sqrt(gL)", Some((l, "cm"))) => (G * l / 100.0).sqrt() * 100.0,
        ("steps/min", "f*sqrt(L/g)", Some((l, "cm"))) => 60.0 * (G / (l / 100.0)).sqrt(),
        _ => return None,
    };
    Some((n.mean * factor, n.sd * factor))
}

/// A normative unit as a reader takes it: Hof's dimensionless forms spelt out ("s/L" reads
/// like seconds per litre).
fn unit_label(unit: &str) -> String {
    match unit {
        "s/L" => "leg lengths (step length / leg length)".into(),
        "v/sqrt(gL)" => "speed / √(g × leg length)".into(),
        "f*sqrt(L/g)" => "steps/s × √(leg length / g)".into(),
        other => other.into(),
    }
}

fn mean_sd(p: &StParam) -> String {
    // No cycle behind the value: blank as in spatiotemporal.csv, not "NaN (n=0)".
    if p.n == 0 || !p.mean.is_finite() {
        "—".into()
    } else if p.sd.is_finite() {
        format!("{:.2} ± {:.2} (n={})", p.mean, p.sd, p.n)
    } else {
        format!("{:.2} (n={})", p.mean, p.n)
    }
}

/// The report's table; `norm` adds the normative column (and marks values
/// outside mean ± 2 SD).
pub fn table(rows: &[StParam], norm: Option<&Normative>, prosthetic: Option<Side>) -> Table {
    let name = |s: Side| match prosthetic {
        Some(p) if p == s => format!("{} (prosthetic)", s.as_str()),
        Some(_) => format!("{} (intact)", s.as_str()),
        None => s.as_str().to_string(),
    };
    let sym = if prosthetic.is_some() {
        "Symmetry index % (prosthetic vs intact)"
    } else {
        "Symmetry index % (left vs right)"
    };
    let header = vec![
        "Parameter".into(),
        "Unit".into(),
        name(Side::Left),
        name(Side::Right),
        "Both".into(),
        "Normative mean ± SD".into(),
        sym.into(),
        "Smallest real change (MDC95)".into(),
    ];
    let leg = rows
        .iter()
        .find(|r| r.parameter == "leg_length" && r.mean.is_finite())
        .map(|r| (r.mean, r.unit.as_str()));
    let mut out = Vec::new();
    for param in ORDER {
        let of = |side: &str| rows.iter().find(|r| r.parameter == param && r.side == side);
        let (l, r, b) = (of("left"), of("right"), of("both"));
        let Some(unit) = [l, r, b].iter().flatten().map(|p| p.unit.clone()).next() else {
            continue;
        };
        let sym_row = rows
            .iter()
            .find(|r| r.parameter == format!("symmetry_index_{param}"));
        let norm_cell = match norm.and_then(|n| n.param(param)) {
            None => "—".to_string(),
            Some(n) => match norm_in(&unit, n, leg) {
                None => format!(
                    "{:.2} ± {:.2} {} (needs a scale to compare: set kinematics.subject_height_m)",
                    n.mean,
                    n.sd,
                    unit_label(&n.unit)
                ),
                Some((m, sd)) => {
                    // Which column is outside, and on which side of the norm.
                    let outside: Vec<String> = [(name(Side::Left), l), (name(Side::Right), r)]
                        .into_iter()
                        .chain([("both".to_string(), b)])
                        .filter_map(|(who, p)| {
                            let v = p.filter(|p| p.n > 0)?.mean;
                            let dir = if v > m + 2.0 * sd {
                                "above"
                            } else if v < m - 2.0 * sd {
                                "below"
                            } else {
                                return None;
                            };
                            Some(format!("{who} {dir}"))
                        })
                        .collect();
                    let flag = if outside.is_empty() {
                        String::new()
                    } else {
                        format!(" — outside ±2 SD: {}", outside.join(", "))
                    };
                    let hof = if n.unit == unit {
                        String::new()
                    } else {
                        format!(" ({:.2} ± {:.2} {})", n.mean, n.sd, unit_label(&n.unit))
                    };
                    format!("{m:.2} ± {sd:.2}{hof}{flag}")
                }
            },
        };
        let cell = |p: Option<&StParam>| p.map_or("—".to_string(), mean_sd);
        let mdc = gait_eval::reliability::cell(param, &unit);
        out.push(vec![
            label(param),
            unit,
            cell(l),
            cell(r),
            cell(b),
            norm_cell,
            sym_row.map_or("—".into(), |s| format!("{:.1}", s.mean)),
            mdc,
        ]);
    }
    Table {
        title: "Spatiotemporal parameters (accepted cycles)".into(),
        header,
        rows: out,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(parameter: &str, side: &str, mean: f64, unit: &str) -> StParam {
        StParam {
            parameter: parameter.into(),
            side: side.into(),
            mean,
            sd: 0.1,
            n: 2,
            unit: unit.into(),
        }
    }

    #[test]
    fn norms_convert_units_and_flag_outliers() {
        let norm = Normative {
            name: "t".into(),
            source: String::new(),
            curves: vec![],
            params: vec![
                NormParam {
                    parameter: "speed".into(),
                    mean: 1.3,
                    sd: 0.1,
                    unit: "m/s".into(),
                },
                NormParam {
                    parameter: "cadence".into(),
                    mean: 110.0,
                    sd: 8.0,
                    unit: "steps/min".into(),
                },
                NormParam {
                    parameter: "stride_length".into(),
                    mean: 1.4,
                    sd: 0.1,
                    unit: "m".into(),
                },
                NormParam {
                    parameter: "step_length".into(),
                    mean: 0.76,
                    sd: 0.04,
                    unit: "s/L".into(),
                },
            ],
        };
        let rows = vec![
            p("cadence", "both", 80.0, "steps/min"),
            p("speed", "left", 128.0, "cm/s"),
            p("stride_length", "left", 300.0, "px"),
            p("symmetry_index_speed", "prosthetic_vs_intact", -2.5, "%"),
            p("step_length", "left", 190.0, "px"),
            p("leg_length", "both", 250.0, "px"),
        ];
        let t = table(&rows, Some(&norm), Some(Side::Right));
        assert_eq!(t.rows[0][0], "cadence");
        assert!(
            t.rows[0][5].ends_with("outside ±2 SD: both below"),
            "{:?}",
            t.rows[0]
        );
        assert!(
            !t.rows[1][5].contains("outside"),
            "128 cm/s is 1.28 m/s: {:?}",
            t.rows[1]
        );
        assert_eq!(t.rows[1][6], "-2.5");
        assert!(t.rows[2][5].contains("needs a scale"), "{:?}", t.rows[2]);
        // Hof: 0.76 leg lengths of 250 px = 190 px.
        assert!(
            t.rows[3][5]
                .starts_with("190.00 ± 10.00 (0.76 ± 0.04 leg lengths (step length / leg length))"),
            "{:?}",
            t.rows[3]
        );
        assert_eq!(
            norm_in(
                "steps/min",
                &NormParam {
                    parameter: "cadence".into(),
                    mean: 0.5648,
                    sd: 0.0374,
                    unit: "f*sqrt(L/g)".into()
                },
                Some((90.0, "cm"))
            )
            .map(|(m, _)| m.round()),
            Some(112.0)
        );
        assert!(t.header[2].contains("intact") && t.header[6].contains("prosthetic vs intact"));
    }

    #[test]
    fn no_cycle_is_an_empty_cell_and_the_outside_side_is_named() {
        let norm = Normative {
            name: "t".into(),
            source: String::new(),
            curves: vec![],
            params: vec![NormParam {
                parameter: "speed".into(),
                mean: 1.3,
                sd: 0.1,
                unit: "m/s".into(),
            }],
        };
        let mut none = p("speed", "right", f64::NAN, "cm/s");
        none.n = 0;
        none.sd = f64::NAN;
        let rows = vec![p("speed", "left", 160.0, "cm/s"), none];
        let t = table(&rows, Some(&norm), None);
        assert_eq!(t.rows[0][3], "—", "{:?}", t.rows[0]);
        assert!(
            !t.rows[0].iter().any(|c| c.contains("NaN")),
            "{:?}",
            t.rows[0]
        );
        assert!(
            t.rows[0][5].ends_with("outside ±2 SD: left above"),
            "{:?}",
            t.rows[0]
        );
    }
}
