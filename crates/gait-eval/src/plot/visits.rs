//! A subject's visits side by side (`gait progress`): each side's mean
//! sagittal curves of every visit over the normative band.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::cycles::{JOINTS, Series, panel, title};
use super::{Draw, Figure, render};
use crate::EvalError;
use crate::names::Side;
use crate::normative::Normative;
use crate::plot::CycleCurve;

/// The normative band's colour.
const NORM: RGBColor = RGBColor(150, 150, 150);

/// Visit colours, in order: none of them the red and blue that mean left and
/// right everywhere else in the reports.
const VISITS: [RGBColor; 5] = [
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(23, 190, 207),
    RGBColor(140, 86, 75),
];

struct Visits<'a> {
    visits: &'a [(String, Vec<CycleCurve>)],
    norms: Vec<Option<CycleCurve>>,
    rows: [(Side, String); 2],
}

/// Rows: the two sides (prosthetic first when set), columns: hip, knee, ankle;
/// one colour per visit, in order, over the normative mean ± 1 SD in grey.
pub fn visits_plot(
    visits: &[(String, Vec<CycleCurve>)],
    normative: Option<&Normative>,
    prosthetic: Option<Side>,
) -> Result<Figure, EvalError> {
    let rows = match prosthetic {
        Some(p) => [
            (p, format!("{} (prosthetic)", p.as_str())),
            (p.other(), format!("{} (intact)", p.other().as_str())),
        ],
        None => [(Side::Left, "left".into()), (Side::Right, "right".into())],
    };
    let norms = JOINTS
        .iter()
        .map(|j| {
            normative
                .and_then(|n| n.curve(j))
                .map(|c| band(j, &c.mean, &c.sd))
        })
        .collect();
    render(
        &Visits {
            visits,
            norms,
            rows,
        },
        "visits",
        1200,
        720,
        None,
    )
}

/// A normative curve as a cycle curve over 0-100 % (its points evenly spread).
fn band(joint: &str, mean: &[f64], sd: &[f64]) -> CycleCurve {
    let last = mean.len().saturating_sub(1).max(1) as f64;
    CycleCurve {
        side: Side::Left,
        joint: joint.into(),
        percent: (0..mean.len()).map(|i| 100.0 * i as f64 / last).collect(),
        mean: mean.to_vec(),
        sd: sd.to_vec(),
        n_cycles: 0,
    }
}

impl Draw for Visits<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        _bitmap: bool,
    ) -> Result<(), String> {
        for (i, area) in root.split_evenly((2, 3)).iter().enumerate() {
            let ((side, name), k) = (&self.rows[i / 3], i % 3);
            let mut series = Vec::new();
            if let Some(n) = &self.norms[k] {
                series.push(Series {
                    curve: n,
                    color: NORM,
                    label: "normative ± 1 SD".into(),
                    band: true,
                });
            }
            for (v, (label, curves)) in self.visits.iter().enumerate() {
                let found = curves
                    .iter()
                    .find(|c| c.side == *side && c.joint == JOINTS[k]);
                if let Some(c) = found {
                    series.push(Series {
                        curve: c,
                        color: VISITS[v % VISITS.len()],
                        label: label.clone(),
                        band: false,
                    });
                }
            }
            panel(area, &format!("{} – {name}", title(JOINTS[k])), &series)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_visit_and_the_band_are_drawn() {
        let curve = |side, joint: &str, offset: f64| CycleCurve {
            side,
            joint: joint.into(),
            percent: (0..=100).map(f64::from).collect(),
            mean: (0..=100)
                .map(|i| offset + (i as f64 / 16.0).sin() * 20.0)
                .collect(),
            sd: vec![3.0; 101],
            n_cycles: 4,
        };
        let visit = |o| {
            let mut v = Vec::new();
            for s in [Side::Left, Side::Right] {
                for j in JOINTS {
                    v.push(curve(s, j, o));
                }
            }
            v
        };
        let visits = vec![
            ("first visit".to_string(), visit(0.0)),
            ("second visit".to_string(), visit(5.0)),
        ];
        let norm = Normative::load("schwartz2008_free").unwrap();
        let fig = visits_plot(&visits, Some(&norm), Some(Side::Right)).unwrap();
        for text in [
            "first visit",
            "second visit",
            "normative",
            "right (prosthetic)",
            "left (intact)",
        ] {
            assert!(fig.svg.contains(text), "{text} missing");
        }
        assert!(!fig.png.is_empty());
    }
}
