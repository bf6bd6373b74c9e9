//! Failure-mode bars per camera view (the paper's Fig. 2).

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{Draw, FONT, Figure, PALETTE, err, legend, render};
use crate::EvalError;
use crate::failure::Failures;

/// The failure modes of one method on one camera view.
#[derive(Debug, Clone)]
pub struct FailureEntry {
    pub view: String,
    pub method: String,
    pub failures: Failures,
}

struct Bars<'a> {
    entries: &'a [FailureEntry],
}

fn distinct(items: impl Iterator<Item = String>) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for i in items {
        if !out.contains(&i) {
            out.push(i);
        }
    }
    out
}

impl Draw for Bars<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        _bitmap: bool,
    ) -> Result<(), String> {
        let views = distinct(self.entries.iter().map(|e| e.view.clone()));
        let methods = distinct(self.entries.iter().map(|e| e.method.clone()));
        type Pick = fn(&Failures) -> f64;
        let modes: [(&str, Pick); 3] = [
            ("Not identified", |f| f.not_identified.percent),
            ("Misidentified", |f| f.misidentified.percent),
            ("Left/right swapped", |f| f.swapped.percent),
        ];
        let top = self
            .entries
            .iter()
            .flat_map(|e| modes.iter().map(|(_, p)| p(&e.failures)))
            .fold(10.0f64, f64::max)
            * 1.1;
        let nv = views.len().max(1);
        let width = 0.8 / methods.len().max(1) as f64;
        for (area, (caption, pick)) in root.split_evenly((1, 3)).iter().zip(modes) {
            let mut chart = ChartBuilder::on(area)
                .caption(format!("{caption} (% of frames)"), (FONT, 16))
                .margin(8)
                .x_label_area_size(32)
                .y_label_area_size(40)
                .build_cartesian_2d(-0.5f64..(nv as f64 - 0.5), 0f64..top)
                .map_err(err)?;
            let views_ref = &views;
            chart
                .configure_mesh()
                .disable_x_mesh()
                .x_labels(nv)
                .x_label_formatter(&|x: &f64| {
                    let i = x.round();
                    if (x - i).abs() < 1e-6 && i >= 0.0 {
                        views_ref.get(i as usize).cloned().unwrap_or_default()
                    } else {
                        String::new()
                    }
                })
                .label_style((FONT, 12))
                .draw()
                .map_err(err)?;
            for (m, method) in methods.iter().enumerate() {
                let color = PALETTE[m % PALETTE.len()];
                let bars: Vec<Rectangle<(f64, f64)>> = self
                    .entries
                    .iter()
                    .filter(|e| &e.method == method)
                    .filter_map(|e| {
                        let v = views.iter().position(|x| *x == e.view)? as f64;
                        let x0 = v - 0.4 + m as f64 * width;
                        Some(Rectangle::new(
                            [(x0, 0.0), (x0 + width * 0.9, pick(&e.failures))],
                            color.filled(),
                        ))
                    })
                    .collect();
                chart
                    .draw_series(bars)
                    .map_err(err)?
                    .label(method.clone())
                    .legend(move |(x, y)| {
                        Rectangle::new([(x, y - 5), (x + 12, y + 5)], color.filled())
                    });
            }
            legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        }
        Ok(())
    }
}

/// Bars of the three failure modes per camera view, one colour per method.
pub fn failure_bars(entries: &[FailureEntry]) -> Result<Figure, EvalError> {
    if entries.is_empty() {
        return Err(EvalError::plot("failure_modes", "no evaluation to plot"));
    }
    render(&Bars { entries }, "failure_modes", 1200, 400, None)
}
