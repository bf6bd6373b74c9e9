//! The clinical sections of the report: gait graphs, all cycles, scores and
//! the Movement Analysis Profile, spatiotemporal parameters.

use crate::html::{escape, table};
use crate::report::{Report, figure};
use gait_eval::plot::{GraphContext, consistency_plot, gait_graphs, map_bars};
use gait_eval::{EvalError, Side};

/// Why the gait graphs are empty, in words a clinician can act on.
fn no_cycles_reason(r: &Report) -> String {
    if let Some(f) = &r.frontal {
        return format!(
            "No sagittal angles: this is a {} view, whose measures are in the Frontal plane section; hip, knee and ankle flexion need a side view.",
            f.view
        );
    }
    let from_run = r
        .warnings
        .iter()
        .find(|w| {
            w.contains("no walking bout")
                || w.contains("no heel strike")
                || w.contains("fewer than")
        })
        .cloned();
    match from_run {
        Some(w) => format!("No accepted gait cycle to show: {w}."),
        None => "No accepted gait cycle to show: the run found no complete stride of either leg that passed the quality checks (see Warnings and Cycle quality).".into(),
    }
}

impl Report {
    fn graph_context(&self) -> GraphContext<'_> {
        GraphContext {
            prosthetic: self.prosthetic_side,
            normative: self.normative.as_ref(),
            toe_off: self.toe_off,
        }
    }

    /// Gait graphs and the all-cycles plot, or why there are none.
    pub(crate) fn gait_sections(&self) -> Result<String, EvalError> {
        let mut body = String::from("<h2 id=\"gait-graphs\">Kinematics over the gait cycle</h2>");
        if self.cycles.is_empty() {
            body.push_str(&format!(
                "<p class=\"no-cycles\">{}</p>",
                escape(&no_cycles_reason(self))
            ));
            return Ok(body);
        }
        let norm = match &self.normative {
            Some(n) => format!("Grey band: normative mean ± 1 SD ({}). ", n.source),
            None => "No normative band (report.normative is not set). ".into(),
        };
        let fig = gait_graphs(&self.cycles, self.graph_context())?;
        body.push_str(&figure(
            &fig,
            &format!("Mean (line) ± SD (band) over the accepted cycles, left red, right blue; dashed lines: each side's mean toe-off. {norm}"),
        ));
        if !self.traces.is_empty() {
            body.push_str("<h2 id=\"consistency\">Every accepted cycle</h2>");
            let fig = consistency_plot(&self.traces, self.graph_context())?;
            body.push_str(&figure(
                &fig,
                "Each line one accepted cycle (left red, right blue), to judge consistency between strides.",
            ));
        }
        Ok(body)
    }

    /// GVS and sagittal GPS table and the MAP bar chart.
    pub(crate) fn score_section(&self) -> Result<String, EvalError> {
        let Some(s) = &self.scores else {
            return Ok(String::new());
        };
        if s.gvs.is_empty() {
            return Ok(String::new());
        }
        let mut body = String::from("<h2 id=\"scores\">Gait scores (sagittal plane)</h2>");
        body.push_str(
            "<p>Gait Variable Score (GVS): the RMS difference over the cycle between the mean curve and the normative mean. \
             Sagittal Gait Profile Score (GPS): the RMS of a side's hip, knee and ankle GVS. The published GPS (Baker et al. 2009) \
             uses nine 3-D variables; a video in the sagittal plane has three, so these are the sagittal variant and not comparable \
             one to one with 3-D GPS values.</p>",
        );
        let cell = |v: Option<f64>| v.map_or("—".to_string(), |v| format!("{v:.1}"));
        let mut rows = Vec::new();
        for joint in gait_eval::normative::JOINTS {
            rows.push(vec![
                format!("GVS {joint}"),
                cell(s.gvs_of(Side::Left, joint)),
                cell(s.gvs_of(Side::Right, joint)),
            ]);
        }
        rows.push(vec![
            "GPS (sagittal)".into(),
            cell(s.gps_of(Some(Side::Left))),
            cell(s.gps_of(Some(Side::Right))),
        ]);
        rows.push(vec![
            "GPS (sagittal), both sides".into(),
            cell(s.gps_of(None)),
            String::new(),
        ]);
        let side = |x: Side| match self.prosthetic_side {
            Some(p) if p == x => format!("{} (prosthetic), °", x.as_str()),
            Some(_) => format!("{} (intact), °", x.as_str()),
            None => format!("{}, °", x.as_str()),
        };
        let header = ["Score".to_string(), side(Side::Left), side(Side::Right)];
        body.push_str(&table(&header, &rows));
        let reference = self
            .normative
            .as_ref()
            .and_then(|n| n.expected_gps())
            .map(|g| {
                (
                    g,
                    format!("healthy walker one SD off the norm: GPS {g:.1}°"),
                )
            });
        let fig = map_bars(s, reference)?;
        body.push_str(&figure(
            &fig,
            &format!(
                "Movement Analysis Profile: GVS per joint and the sagittal GPS, against {}.",
                s.normative
            ),
        ));
        Ok(body)
    }

    /// The spatiotemporal table with norms and symmetry.
    pub(crate) fn spatiotemporal_section(&self) -> String {
        if self.spatiotemporal.is_empty() {
            return String::new();
        }
        let t = crate::spatiotemporal::table(
            &self.spatiotemporal,
            self.normative.as_ref(),
            self.prosthetic_side,
        );
        format!(
            "<h2 id=\"spatiotemporal\">{}</h2>{}",
            escape(&t.title),
            table(&t.header, &t.rows)
        )
    }
}
