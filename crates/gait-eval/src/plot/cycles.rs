//! Joint angles over the normalised gait cycle (mean and SD band).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{
    Draw, Figure, PALETTE, TRUTH, cycle_axes, err, legend, line_key, padded_range, render,
};
use crate::EvalError;
use crate::names::Side;

/// Mean and SD of one joint angle of one side over 0..100 % of the gait cycle
/// (one row group of gait-kin's `cycles.csv`).
#[derive(Debug, Clone, PartialEq)]
pub struct CycleCurve {
    pub side: Side,
    /// "hip", "knee" or "ankle".
    pub joint: String,
    /// Percent of the cycle of each point (usually 0, 1, ..., 100).
    pub percent: Vec<f64>,
    pub mean: Vec<f64>,
    pub sd: Vec<f64>,
    pub n_cycles: usize,
}

/// Reads a `cycles.csv` (`side,joint,percent,mean,sd,n_cycles`).
pub fn read_cycles_csv(path: &Path) -> Result<Vec<CycleCurve>, EvalError> {
    read_curves_csv(path, "joint")
}

/// As [`read_cycles_csv`], with the curve's name in column `key` (frontal_cycles.csv: `measure`).
pub fn read_curves_csv(path: &Path, key: &str) -> Result<Vec<CycleCurve>, EvalError> {
    let mut r = csv::Reader::from_path(path).map_err(|e| EvalError::input(path, e))?;
    let header: Vec<String> = r
        .headers()
        .map_err(|e| EvalError::input(path, e))?
        .iter()
        .map(str::to_string)
        .collect();
    let want = ["side", key, "percent", "mean", "sd", "n_cycles"];
    let cols: Vec<usize> = want
        .iter()
        .map(|w| {
            header.iter().position(|h| h == w).ok_or_else(|| {
                EvalError::input(
                    path,
                    format!("no `{w}` column; expected {}", want.join(",")),
                )
            })
        })
        .collect::<Result<_, _>>()?;
    let mut curves: Vec<CycleCurve> = Vec::new();
    for (i, rec) in r.records().enumerate() {
        let rec = rec.map_err(|e| EvalError::input(path, e))?;
        let line = i + 2;
        let text = |c: usize| rec.get(cols[c]).unwrap_or("").trim();
        let num = |c: usize| -> Result<f64, EvalError> {
            let s = text(c);
            if s.is_empty() {
                return Ok(f64::NAN);
            }
            s.parse()
                .map_err(|_| EvalError::input(path, format!("line {line}: `{s}` is not a number")))
        };
        let side: Side = text(0)
            .parse()
            .map_err(|e| EvalError::input(path, format!("line {line}: {e}")))?;
        let joint = text(1).to_string();
        let n_cycles = text(5).parse().map_err(|_| {
            EvalError::input(path, format!("line {line}: n_cycles is not a whole number"))
        })?;
        let curve = match curves
            .iter_mut()
            .find(|c| c.side == side && c.joint == joint)
        {
            Some(c) => c,
            None => {
                curves.push(CycleCurve {
                    side,
                    joint,
                    percent: vec![],
                    mean: vec![],
                    sd: vec![],
                    n_cycles,
                });
                curves
                    .last_mut()
                    .ok_or_else(|| EvalError::input(path, "internal"))?
            }
        };
        curve.percent.push(num(2)?);
        curve.mean.push(num(3)?);
        curve.sd.push(num(4)?);
    }
    Ok(curves)
}

pub(super) const JOINTS: [&str; 3] = ["hip", "knee", "ankle"];

pub(super) fn title(joint: &str) -> String {
    let unit = if joint == "ankle" {
        "dorsiflexion +"
    } else {
        "flexion +"
    };
    format!(
        "{} angle (°, {unit})",
        joint[..1].to_uppercase() + &joint[1..]
    )
}

/// One series of a panel: curve, colour, label, whether to draw the SD band.
pub(super) struct Series<'a> {
    pub(super) curve: &'a CycleCurve,
    pub(super) color: RGBColor,
    pub(super) label: String,
    pub(super) band: bool,
}

pub(super) fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    caption: &str,
    series: &[Series],
) -> Result<(), String> {
    let (lo, hi) = padded_range(series.iter().flat_map(|s| {
        let band = if s.band { 1.0 } else { 0.0 };
        s.curve
            .mean
            .iter()
            .zip(&s.curve.sd)
            .flat_map(move |(m, d)| {
                let d = if d.is_finite() { d * band } else { 0.0 };
                [m - d, m + d]
            })
    }));
    let mut chart = cycle_axes(area, caption, lo, hi)?;
    for s in series {
        let pts = |sign: f64| -> Vec<(f64, f64)> {
            s.curve
                .percent
                .iter()
                .zip(s.curve.mean.iter().zip(&s.curve.sd))
                .filter(|(p, (m, d))| p.is_finite() && m.is_finite() && d.is_finite())
                .map(|(p, (m, d))| (*p, m + sign * d))
                .collect()
        };
        if s.band {
            let mut poly = pts(1.0);
            poly.extend(pts(-1.0).into_iter().rev());
            if poly.len() > 2 {
                chart
                    .draw_series(std::iter::once(Polygon::new(
                        poly,
                        s.color.mix(0.2).filled(),
                    )))
                    .map_err(err)?;
            }
        }
        let line: Vec<(f64, f64)> = s
            .curve
            .percent
            .iter()
            .zip(&s.curve.mean)
            .filter(|(p, m)| p.is_finite() && m.is_finite())
            .map(|(p, m)| (*p, *m))
            .collect();
        let color = s.color;
        chart
            .draw_series(LineSeries::new(line, color.stroke_width(2)))
            .map_err(err)?
            .label(s.label.clone())
            .legend(line_key(color, 2));
    }
    legend(&mut chart, SeriesLabelPosition::UpperRight)
}

struct Comparison<'a> {
    truth: &'a [CycleCurve],
    methods: &'a [(String, Vec<CycleCurve>)],
    prosthetic: Side,
}

impl Draw for Comparison<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        _bitmap: bool,
    ) -> Result<(), String> {
        let rows = [self.prosthetic, self.prosthetic.other()];
        for (i, area) in root.split_evenly((2, 3)).iter().enumerate() {
            let (side, joint) = (rows[i / 3], JOINTS[i % 3]);
            let role = if side == self.prosthetic {
                "prosthetic"
            } else {
                "intact"
            };
            let mut series = Vec::new();
            if let Some(c) = self
                .truth
                .iter()
                .find(|c| c.side == side && c.joint == joint)
            {
                series.push(Series {
                    curve: c,
                    color: TRUTH,
                    label: "ground truth".into(),
                    band: true,
                });
            }
            for (k, (name, curves)) in self.methods.iter().enumerate() {
                if let Some(c) = curves.iter().find(|c| c.side == side && c.joint == joint) {
                    series.push(Series {
                        curve: c,
                        color: PALETTE[k % PALETTE.len()],
                        label: name.clone(),
                        band: false,
                    });
                }
            }
            panel(
                area,
                &format!("{} – {role} ({})", title(joint), side.as_str()),
                &series,
            )?;
        }
        Ok(())
    }
}

/// Methods against ground truth over the gait cycle: rows prosthetic and
/// intact side, columns hip, knee, ankle; truth green with its SD band.
pub fn comparison_plot(
    truth: &[CycleCurve],
    methods: &[(String, Vec<CycleCurve>)],
    prosthetic_side: Side,
) -> Result<Figure, EvalError> {
    render(
        &Comparison {
            truth,
            methods,
            prosthetic: prosthetic_side,
        },
        "comparison",
        1200,
        720,
        None,
    )
}
