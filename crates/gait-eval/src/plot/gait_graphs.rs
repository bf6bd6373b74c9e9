//! Gait graphs as clinical reports draw them (pyCGM2, Vicon, Visual3D): one
//! panel per sagittal joint, left and right on the same axes over a grey
//! normative band, a vertical line at each side's mean toe-off; and the
//! all-cycles ("consistency") plot with every accepted cycle.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{
    CycleChart, Draw, Figure, LEFT, RIGHT, cycle_axes, err, legend, line_key, padded_range, render,
};
use crate::EvalError;
use crate::cycle_traces::CycleTrace;
use crate::names::Side;
use crate::normative::Normative;
use crate::plot::CycleCurve;

const JOINTS: [&str; 3] = ["hip", "knee", "ankle"];
const NORM_FILL: RGBColor = RGBColor(200, 200, 200);

/// What both gait figures share: the sides' names, the norm, the toe-offs.
#[derive(Debug, Clone, Copy)]
pub struct GraphContext<'a> {
    /// The prosthetic leg, when set: legends say "left (prosthetic)".
    pub prosthetic: Option<Side>,
    pub normative: Option<&'a Normative>,
    /// Mean toe-off of each side in % of the cycle (left, right).
    pub toe_off: [Option<f64>; 2],
}

impl GraphContext<'_> {
    fn name(&self, side: Side) -> String {
        match self.prosthetic {
            Some(p) if p == side => format!("{} (prosthetic)", side.as_str()),
            Some(_) => format!("{} (intact)", side.as_str()),
            None => side.as_str().to_string(),
        }
    }
}

fn colour(side: Side) -> RGBColor {
    match side {
        Side::Left => LEFT,
        Side::Right => RIGHT,
    }
}

fn title(joint: &str) -> String {
    match joint {
        "hip" => "Hip flexion (°)".into(),
        "knee" => "Knee flexion (°)".into(),
        "ankle" => "Ankle dorsiflexion (°)".into(),
        "trunk_lean" => "Trunk lean, toward the side + (°)".into(),
        "pelvic_obliquity" => "Pelvic obliquity, side up + (°)".into(),
        "hip_adduction" => "Hip adduction + / abduction − (°)".into(),
        "knee_varus" => "Knee varus + / valgus − (°)".into(),
        other => other.to_string(),
    }
}

fn pct(i: usize, n: usize) -> f64 {
    if n < 2 {
        0.0
    } else {
        100.0 * i as f64 / (n - 1) as f64
    }
}

/// Axes of one joint panel, with the normative band and the toe-off lines drawn.
fn axes<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    joint: &str,
    ctx: &GraphContext,
    data: impl Iterator<Item = f64>,
) -> Result<CycleChart<'a, DB>, String> {
    let norm = ctx.normative.and_then(|n| n.curve(joint));
    let band = norm
        .into_iter()
        .flat_map(|c| c.mean.iter().zip(&c.sd).flat_map(|(m, s)| [m - s, m + s]));
    let (lo, hi) = padded_range(data.chain(band));
    // Head room for the legend, so it never hides the curves' peaks.
    let hi = hi + 0.3 * (hi - lo);
    let mut chart = cycle_axes(area, &title(joint), lo, hi)?;
    if let Some(c) = norm {
        let n = c.mean.len();
        let mut poly: Vec<(f64, f64)> = (0..n).map(|i| (pct(i, n), c.mean[i] + c.sd[i])).collect();
        poly.extend((0..n).rev().map(|i| (pct(i, n), c.mean[i] - c.sd[i])));
        chart
            .draw_series(std::iter::once(Polygon::new(
                poly,
                NORM_FILL.mix(0.6).filled(),
            )))
            .map_err(err)?
            .label("normative ±1 SD")
            .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 18, y + 5)], NORM_FILL.filled()));
    }
    for side in Side::BOTH {
        if let Some(t) = ctx.toe_off[side as usize] {
            let c = colour(side);
            chart
                .draw_series(DashedLineSeries::new(
                    [(t, lo), (t, hi)],
                    6,
                    4,
                    c.stroke_width(1),
                ))
                .map_err(err)?;
        }
    }
    Ok(chart)
}

struct MeanGraphs<'a> {
    curves: &'a [CycleCurve],
    ctx: GraphContext<'a>,
    /// One panel each, left to right.
    joints: &'a [&'a str],
}

impl Draw for MeanGraphs<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        _: bool,
    ) -> Result<(), String> {
        let panels = root.split_evenly((1, self.joints.len()));
        for (area, &joint) in panels.iter().zip(self.joints) {
            let curves: Vec<&CycleCurve> = Side::BOTH
                .iter()
                .filter_map(|&s| self.curves.iter().find(|c| c.side == s && c.joint == joint))
                .collect();
            let data = curves.iter().flat_map(|c| {
                c.mean.iter().zip(&c.sd).flat_map(|(m, s)| {
                    let s = if s.is_finite() { *s } else { 0.0 };
                    [m - s, m + s]
                })
            });
            let mut chart = axes(area, joint, &self.ctx, data)?;
            for c in curves {
                let col = colour(c.side);
                let pts = |k: f64| -> Vec<(f64, f64)> {
                    c.percent
                        .iter()
                        .zip(c.mean.iter().zip(&c.sd))
                        .filter(|(p, (m, _))| p.is_finite() && m.is_finite())
                        .map(|(p, (m, s))| (*p, m + k * if s.is_finite() { *s } else { 0.0 }))
                        .collect()
                };
                let mut band = pts(1.0);
                band.extend(pts(-1.0).into_iter().rev());
                if band.len() > 2 {
                    chart
                        .draw_series(std::iter::once(Polygon::new(band, col.mix(0.18).filled())))
                        .map_err(err)?;
                }
                chart
                    .draw_series(LineSeries::new(pts(0.0), col.stroke_width(2)))
                    .map_err(err)?
                    .label(format!("{}, n={}", self.ctx.name(c.side), c.n_cycles))
                    .legend(line_key(col, 2));
            }
            legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        }
        Ok(())
    }
}

/// Hip, knee and ankle: left (red) and right (blue) mean ± SD over the
/// normative band, toe-off lines, legend with cycle counts.
pub fn gait_graphs(curves: &[CycleCurve], ctx: GraphContext) -> Result<Figure, EvalError> {
    let joints = &JOINTS;
    render(
        &MeanGraphs {
            curves,
            ctx,
            joints,
        },
        "gait_graphs",
        1200,
        400,
        None,
    )
}

/// The frontal measures of a front or back view, as [`gait_graphs`] draws the sagittal joints.
pub fn frontal_graphs(curves: &[CycleCurve], ctx: GraphContext) -> Result<Figure, EvalError> {
    let joints = &FRONTAL;
    render(
        &MeanGraphs {
            curves,
            ctx,
            joints,
        },
        "frontal_graphs",
        1600,
        400,
        None,
    )
}

/// The panels of [`frontal_graphs`], named as gait-kin's frontal_cycles.csv names them.
pub const FRONTAL: [&str; 4] = [
    "trunk_lean",
    "pelvic_obliquity",
    "hip_adduction",
    "knee_varus",
];

struct AllCycles<'a> {
    traces: &'a [CycleTrace],
    ctx: GraphContext<'a>,
}

impl Draw for AllCycles<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        _: bool,
    ) -> Result<(), String> {
        for (area, joint) in root.split_evenly((1, 3)).iter().zip(JOINTS) {
            let mine: Vec<&CycleTrace> = self.traces.iter().filter(|t| t.joint == joint).collect();
            let data = mine.iter().flat_map(|t| t.values.iter().copied());
            let mut chart = axes(area, joint, &self.ctx, data)?;
            for side in Side::BOTH {
                let col = colour(side);
                let of_side: Vec<&&CycleTrace> = mine.iter().filter(|t| t.side == side).collect();
                for (k, t) in of_side.iter().enumerate() {
                    let n = t.values.len();
                    let line = t
                        .values
                        .iter()
                        .enumerate()
                        .filter(|(_, v)| v.is_finite())
                        .map(|(i, v)| (pct(i, n), *v));
                    let series = chart
                        .draw_series(LineSeries::new(line, col.mix(0.75).stroke_width(1)))
                        .map_err(err)?;
                    if k == 0 {
                        series
                            .label(format!("{}, {} cycles", self.ctx.name(side), of_side.len()))
                            .legend(line_key(col, 1));
                    }
                }
            }
            legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        }
        Ok(())
    }
}

/// Every accepted cycle of every joint, in side colours, over the normative band.
pub fn consistency_plot(traces: &[CycleTrace], ctx: GraphContext) -> Result<Figure, EvalError> {
    render(&AllCycles { traces, ctx }, "consistency", 1200, 400, None)
}
