//! The Movement Analysis Profile (Baker et al. 2009): a bar per joint and
//! side (its Gait Variable Score) and the sagittal GPS per side.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{Draw, FONT, Figure, LEFT, RIGHT, err, legend, render};
use crate::EvalError;
use crate::names::Side;
use crate::scores::Scores;

const GROUPS: [&str; 4] = ["hip", "knee", "ankle", "GPS"];

struct Map<'a> {
    scores: &'a Scores,
    /// A horizontal reference line (e.g. the healthy GPS), with its label.
    reference: Option<(f64, String)>,
}

impl Map<'_> {
    fn value(&self, group: &str, side: Side) -> Option<f64> {
        match group {
            "GPS" => self.scores.gps_of(Some(side)),
            joint => self.scores.gvs_of(side, joint),
        }
    }
}

impl Draw for Map<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        _: bool,
    ) -> Result<(), String> {
        let top = GROUPS
            .iter()
            .flat_map(|g| Side::BOTH.map(|s| self.value(g, s)))
            .flatten()
            .chain(self.reference.as_ref().map(|r| r.0))
            .fold(1.0f64, f64::max)
            // Room above the tallest bar for the legend (three lines in the upper left).
            / 0.65;
        let mut chart = ChartBuilder::on(root)
            .caption("Movement Analysis Profile (sagittal)", (FONT, 16))
            .margin(10)
            .x_label_area_size(32)
            .y_label_area_size(48)
            // Four groups: segments 0..=3 (an integer range includes its end).
            .build_cartesian_2d((0u32..3u32).into_segmented(), 0f64..top)
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(4)
            .x_label_formatter(&|x| match x {
                SegmentValue::CenterOf(i) => GROUPS
                    .get(*i as usize)
                    .map(|g| g.to_string())
                    .unwrap_or_default(),
                _ => String::new(),
            })
            .y_desc("RMS difference from the norm (°)")
            .label_style((FONT, 12))
            .axis_desc_style((FONT, 12))
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(err)?;
        for (k, side) in Side::BOTH.into_iter().enumerate() {
            let col = match side {
                Side::Left => LEFT,
                Side::Right => RIGHT,
            };
            // Two bars per group: the left half of a segment for the left side.
            let bars = GROUPS.iter().enumerate().filter_map(|(i, g)| {
                let v = self.value(g, side)?;
                let mut rect = Rectangle::new(
                    [
                        (SegmentValue::Exact(i as u32), 0.0),
                        (SegmentValue::Exact(i as u32 + 1), v),
                    ],
                    col.filled(),
                );
                rect.set_margin(
                    0,
                    0,
                    if k == 0 { 12 } else { 78 },
                    if k == 0 { 78 } else { 12 },
                );
                Some(rect)
            });
            chart
                .draw_series(bars)
                .map_err(err)?
                .label(side.as_str())
                .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], col.filled()));
        }
        if let Some((v, label)) = &self.reference {
            chart
                .draw_series(DashedLineSeries::new(
                    [(SegmentValue::Exact(0), *v), (SegmentValue::Exact(4), *v)],
                    6,
                    4,
                    BLACK.mix(0.6).stroke_width(1),
                ))
                .map_err(err)?
                .label(label.clone())
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.mix(0.6)));
        }
        legend(&mut chart, SeriesLabelPosition::UpperLeft)
    }
}

/// The MAP bar chart; `reference` draws a dashed line, e.g. the healthy GPS.
pub fn map_bars(scores: &Scores, reference: Option<(f64, String)>) -> Result<Figure, EvalError> {
    render(&Map { scores, reference }, "map", 700, 380, None)
}
