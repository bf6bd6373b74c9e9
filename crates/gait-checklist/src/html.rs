//! The checklist as a section of report.html.

use crate::{Checklist, Status};

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.2}")
    } else {
        String::new()
    }
}

impl Checklist {
    /// The report section: one row per item and side, present items first.
    pub fn html(&self) -> String {
        self.html_with(None)
    }

    /// As [`Checklist::html`], with a column naming where each verdict comes from (a visit's
    /// passes), in the order of `verdicts`.
    pub fn html_with(&self, sources: Option<&[String]>) -> String {
        let level = match self.amputation.as_deref() {
            Some(a) => format!("Amputation level: {a}; items listed for the other level only are marked"),
            None => "Amputation level not set (kinematics.amputation): the items of both levels are shown".into(),
        };
        let side_name = |s: crate::Side| match self.prosthetic {
            Some(p) if p == s => format!("{} (prosthetic)", s.name()),
            Some(_) => format!("{} (intact)", s.name()),
            None => s.name().to_string(),
        };
        let mut rows: Vec<(usize, &crate::Verdict)> = self.verdicts.iter().enumerate().collect();
        let rank = |s: Status| match s {
            Status::Present => 0,
            Status::Absent => 1,
            Status::NotAssessable => 2,
        };
        rows.sort_by_key(|(_, v)| rank(v.status));
        let from_head = if sources.is_some() {
            "<th>From</th>"
        } else {
            ""
        };
        let mut out = format!(
            "<h2 id=\"checklist\">Amputee gait-deviation checklist</h2><p>Each item of the observational checklists (Berger 1992; Northwestern University Prosthetic-Orthotic Center) judged by a measure against a threshold with its source, per side. {}. This is a measurement, not a diagnosis. Also in checklist.csv.</p><table><thead><tr><th>Item</th><th>Side</th><th>Verdict</th><th>Value ± SD</th><th>Threshold</th><th>Measure and source</th><th>Cycles (first frames)</th>{from_head}</tr></thead><tbody>",
            escape(&level)
        );
        // Items that cannot be judged here are listed by reason under the table, not as rows.
        let mut unjudged: Vec<(String, Vec<String>)> = Vec::new();
        for (i, v) in rows {
            if v.status == Status::NotAssessable {
                let name = format!("{} ({})", v.item.name, v.side.name());
                match unjudged.iter_mut().find(|(r, _)| *r == v.reason) {
                    Some((_, names)) => names.push(name),
                    None => unjudged.push((v.reason.clone(), vec![name])),
                }
                continue;
            }
            let other_level = self
                .amputation
                .as_deref()
                .is_some_and(|a| v.item.amputation != "both" && v.item.amputation != a);
            let verdict = match v.status {
                Status::Present => "<b>present</b>".to_string(),
                Status::Absent => "absent".into(),
                Status::NotAssessable => format!("not assessable: {}", escape(&v.reason)),
            };
            let value = match (num(v.value), num(v.spread)) {
                (m, _) if m.is_empty() => String::new(),
                (m, s) if s.is_empty() => format!("{m} {}", v.unit),
                (m, s) => format!("{m} ± {s} {}", v.unit),
            };
            let threshold = if v.threshold.is_finite() {
                format!("{} {} {}", v.beyond, num(v.threshold), v.threshold_unit)
            } else {
                String::new()
            };
            let mut cycles = v
                .cycles
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ");
            if let (Status::Present, Some(f)) = (v.status, v.frames.first()) {
                // The page of `gait review` opens where the deviation shows most in the first
                // cycle that has it.
                cycles.push_str(&format!(
                    "<br><code>gait review {} --frame {f}</code>",
                    escape(&v.run)
                ));
            }
            let from = sources
                .and_then(|s| s.get(i))
                .map_or(String::new(), |s| format!("<td>{}</td>", escape(s)));
            out.push_str(&format!(
                "<tr><td>{}{}</td><td>{}</td><td>{verdict}</td><td>{value}</td><td>{threshold}</td><td>{}{}</td><td>{}</td>{from}</tr>",
                escape(v.item.name),
                if other_level { format!(" ({} only)", v.item.amputation) } else { String::new() },
                side_name(v.side),
                escape(v.item.measure),
                if v.source.is_empty() { String::new() } else { format!("; threshold: {}", escape(&v.source)) },
                cycles
            ));
        }
        out.push_str("</tbody></table>");
        if !unjudged.is_empty() {
            out.push_str("<p>Not assessable here:</p><ul>");
            for (reason, names) in unjudged {
                out.push_str(&format!(
                    "<li>{}: {}</li>",
                    escape(&reason),
                    escape(&names.join(", "))
                ));
            }
            out.push_str("</ul>");
        }
        out
    }
}
