//! The checklist as a section of report.html.

use crate::{Checklist, Side, Status, Verdict};

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

/// How many cycles or steps a judged verdict rests on. A finding from one is flagged: the pose
/// model's foot jitter alone put a healthy stride past the whip threshold in 4 of 20
/// (BENCHMARKS.md, "Knees and feet"), and one value shows no consistency.
fn count(v: &Verdict) -> String {
    match (v.status, v.n) {
        (Status::NotAssessable, _) | (_, 0) => String::new(),
        (Status::Present, 1) => {
            "<br><small>n = 1: one value, confirm on a longer walk</small>".into()
        }
        (_, n) => format!("<br><small>n = {n}</small>"),
    }
}

impl Checklist {
    /// The report section: one row per item with both sides, present items first.
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
        let side_name = |s: Side| match self.prosthetic {
            Some(p) if p == s => format!("{} (prosthetic)", s.name()),
            Some(_) => format!("{} (intact)", s.name()),
            None => s.name().to_string(),
        };
        let from_head = if sources.is_some() {
            "<th>From</th>"
        } else {
            ""
        };
        let mut out = format!(
            "<h2 id=\"checklist\">Amputee gait-deviation checklist</h2><p>Each item of the observational checklists (Berger 1992; Northwestern University Prosthetic-Orthotic Center) judged by a measure against a threshold with its source, per side. {}. This is a measurement, not a diagnosis. Also in checklist.csv. A frame link opens that frame in <code>gait review</code> of its run folder while the review runs (<code>gait review RUN --open</code>; each run folder has its own address).</p><table><thead><tr><th>Item</th><th>{}</th><th>{}</th><th>Threshold</th><th>Measure and source</th><th>Cycles (first frames)</th>{from_head}</tr></thead><tbody>",
            escape(&level),
            escape(&side_name(Side::Left)),
            escape(&side_name(Side::Right)),
        );
        // Items that cannot be judged on either side are listed by reason under the table.
        let mut unjudged: Vec<(String, Vec<String>)> = Vec::new();
        let mut rows: Vec<(bool, String)> = Vec::new();
        for id in self.item_ids() {
            let of = |side| {
                self.verdicts
                    .iter()
                    .enumerate()
                    .find(|(_, v)| v.item.id == id && v.side == side)
            };
            let pair: Vec<(usize, &Verdict)> = Side::BOTH.iter().filter_map(|&s| of(s)).collect();
            if pair.iter().all(|(_, v)| v.status == Status::NotAssessable) {
                for (_, v) in &pair {
                    let name = format!("{} ({})", v.item.name, v.side.name());
                    match unjudged.iter_mut().find(|(r, _)| *r == v.reason) {
                        Some((_, names)) => names.push(name),
                        None => unjudged.push((v.reason.clone(), vec![name])),
                    }
                }
                continue;
            }
            let present = pair.iter().any(|(_, v)| v.status == Status::Present);
            rows.push((present, self.row(&pair, sources)));
        }
        // Present items first, each group in the checklist's order.
        rows.sort_by_key(|(present, _)| !present);
        for (_, row) in rows {
            out.push_str(&row);
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

    /// The items' ids in the order they first appear.
    fn item_ids(&self) -> Vec<&'static str> {
        let mut ids: Vec<&'static str> = Vec::new();
        for v in &self.verdicts {
            if !ids.contains(&v.item.id) {
                ids.push(v.item.id);
            }
        }
        ids
    }

    /// One item's row from its verdicts of each side (with their index in `verdicts`).
    fn row(&self, pair: &[(usize, &Verdict)], sources: Option<&[String]>) -> String {
        let side_cell = |side: Side| {
            let Some((_, v)) = pair.iter().find(|(_, v)| v.side == side) else {
                return "<td></td>".to_string();
            };
            let verdict = match v.status {
                Status::Present => "<b>present</b>".to_string(),
                Status::Absent if v.reason.is_empty() => "absent".into(),
                Status::Absent => format!("absent ({})", escape(&v.reason)),
                Status::NotAssessable => format!("not assessable: {}", escape(&v.reason)),
            };
            let value = match (num(v.value), num(v.spread)) {
                (m, _) if m.is_empty() => String::new(),
                (m, s) if s.is_empty() => format!("<br>{m} {}", v.unit),
                (m, s) => format!("<br>{m} ± {s} {}", v.unit),
            };
            format!("<td>{verdict}{value}{}</td>", count(v))
        };
        // The threshold and its source from the present side, else the first judged one.
        let (_, lead) = pair
            .iter()
            .find(|(_, v)| v.status == Status::Present)
            .or_else(|| pair.iter().find(|(_, v)| v.status != Status::NotAssessable))
            .copied()
            .unwrap_or(pair[0]);
        let threshold = if lead.threshold.is_finite() {
            format!(
                "{} {} {}",
                lead.beyond,
                num(lead.threshold),
                lead.threshold_unit
            )
        } else {
            String::new()
        };
        let other_level = self
            .amputation
            .as_deref()
            .is_some_and(|a| lead.item.amputation != "both" && lead.item.amputation != a);
        let cycles: Vec<String> = pair
            .iter()
            .filter(|(_, v)| !v.cycles.is_empty())
            .map(|(_, v)| {
                let mut c = format!(
                    "{}: {}",
                    v.side.name(),
                    v.cycles
                        .iter()
                        .map(usize::to_string)
                        .collect::<Vec<_>>()
                        .join(", ")
                );
                if let (Status::Present, Some(f)) = (v.status, v.frames.first()) {
                    // The page of `gait review` opens where the deviation shows most in the
                    // first cycle that has it: a link while the review runs, the command to
                    // start it (and for the PDF).
                    c.push_str(&format!(
                        "<br><a class=\"review-link\" href=\"{}\">frame {f} in gait review</a> <code>gait review {} --frame {f}</code>",
                        escape(&crate::review_url(std::path::Path::new(&v.run), *f)),
                        escape(&v.run)
                    ));
                }
                c
            })
            .collect();
        let from = sources.map_or(String::new(), |s| {
            let of: Vec<(&str, &String)> = (pair.iter())
                .filter_map(|(i, v)| Some((v.side.name(), s.get(*i)?)))
                .collect();
            // A judgement of both sides (a paired item, the pooled timing) is named once.
            let names: Vec<String> = match of.as_slice() {
                [(_, a), (_, b)] if a == b => vec![a.to_string()],
                _ => of.iter().map(|(side, f)| format!("{side}: {f}")).collect(),
            };
            format!("<td>{}</td>", escape(&names.join("; ")))
        });
        format!(
            "<tr><td>{}{}</td>{}{}<td>{threshold}</td><td>{}{}</td><td>{}</td>{from}</tr>",
            escape(lead.item.name),
            if other_level {
                format!(" ({} only)", lead.item.amputation)
            } else {
                String::new()
            },
            side_cell(Side::Left),
            side_cell(Side::Right),
            escape(lead.item.measure),
            if lead.source.is_empty() {
                String::new()
            } else {
                format!("; threshold: {}", escape(&lead.source))
            },
            cycles.join("<br>"),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::judge::{Sample, Threshold, judge};
    use crate::whip::WHIP;

    fn verdict(side: Side, values: &[f64]) -> Verdict {
        let samples: Vec<Sample> = (values.iter().enumerate())
            .map(|(i, &value)| Sample {
                value,
                first: 40 * i,
                frame: 40 * i + 30,
            })
            .collect();
        let t = Threshold {
            value: 5.0,
            beyond: "above",
            source: "test".into(),
        };
        judge(WHIP, side, &samples, t, "% leg", "none")
    }

    #[test]
    fn each_cell_says_how_many_values_and_a_finding_from_one_says_so() {
        let c = Checklist {
            view: "posterior".into(),
            prosthetic: None,
            amputation: None,
            verdicts: vec![
                verdict(Side::Left, &[1.0, 2.0, 1.5]),
                verdict(Side::Right, &[6.0]),
            ],
        };
        assert_eq!(c.verdicts[1].status, Status::Present);
        let html = c.html();
        assert!(html.contains("<small>n = 3</small>"), "{html}");
        assert!(
            html.contains("n = 1: one value, confirm on a longer walk"),
            "{html}"
        );
        // Two values past the threshold: a count, no caution.
        let c = Checklist {
            verdicts: vec![verdict(Side::Right, &[6.0, 7.0])],
            ..c
        };
        let html = c.html();
        assert!(
            html.contains("<small>n = 2</small>") && !html.contains("one value"),
            "{html}"
        );
    }
}
