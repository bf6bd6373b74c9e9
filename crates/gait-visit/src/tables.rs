//! The visit's files: visit_checklist.csv (checklist.csv with the pass each verdict comes
//! from), visit_cycles.csv (the combined mean curves) and visit_spatiotemporal.csv, and the
//! checklist section of its report.

use std::path::Path;

use gait_checklist::{Checklist, Verdict};
use gait_eval::plot::CycleCurve;
use gait_report::spatiotemporal::StParam;

use crate::{VisitError, VisitOptions};

fn write(path: &Path, text: &str) -> Result<(), VisitError> {
    let tmp = path.with_extension("partial");
    std::fs::write(&tmp, text)
        .and_then(|()| std::fs::rename(&tmp, path))
        .map_err(|source| VisitError::Io {
            path: path.to_path_buf(),
            source,
        })
}

fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.6}")
    } else {
        String::new()
    }
}

/// Writes the three CSV files into `out`.
pub fn write_all(
    out: &Path,
    checklist: &[(Verdict, String)],
    sagittal: &[CycleCurve],
    frontal: &[CycleCurve],
    spatiotemporal: &[StParam],
) -> Result<(), VisitError> {
    std::fs::create_dir_all(out).map_err(|source| VisitError::Io {
        path: out.to_path_buf(),
        source,
    })?;
    let verdicts: Vec<Verdict> = checklist.iter().map(|(v, _)| v.clone()).collect();
    let list = Checklist {
        view: "visit".into(),
        prosthetic: None,
        amputation: None,
        verdicts,
    };
    let mut text = String::new();
    for (k, line) in list.csv().lines().enumerate() {
        let from = if k == 0 {
            "pass".to_string()
        } else {
            format!("\"{}\"", checklist[k - 1].1)
        };
        text.push_str(&format!("{line},{from}\n"));
    }
    write(&out.join("visit_checklist.csv"), &text)?;
    let mut text = String::from("plane,side,curve,percent,mean,sd,n_cycles\n");
    for (plane, curves) in [("sagittal", sagittal), ("frontal", frontal)] {
        for c in curves {
            for (i, (m, s)) in c.mean.iter().zip(&c.sd).enumerate() {
                let pct = c.percent.get(i).copied().unwrap_or(i as f64);
                text.push_str(&format!(
                    "{plane},{},{},{pct},{},{},{}\n",
                    c.side.as_str(),
                    c.joint,
                    num(*m),
                    num(*s),
                    c.n_cycles
                ));
            }
        }
    }
    write(&out.join("visit_cycles.csv"), &text)?;
    let mut text = String::from("parameter,side,mean,sd,n,unit\n");
    for p in spatiotemporal {
        text.push_str(&format!(
            "{},{},{},{},{},{}\n",
            p.parameter,
            p.side,
            num(p.mean),
            num(p.sd),
            p.n,
            p.unit
        ));
    }
    write(&out.join("visit_spatiotemporal.csv"), &text)
}

/// The combined checklist as a report section, with the pass of each verdict.
pub fn checklist_html(checklist: &[(Verdict, String)], o: &VisitOptions) -> String {
    let list = Checklist {
        view: "visit".into(),
        prosthetic: o.prosthetic,
        amputation: o.amputation.map(String::from),
        verdicts: checklist.iter().map(|(v, _)| v.clone()).collect(),
    };
    let from: Vec<String> = checklist.iter().map(|(_, p)| p.clone()).collect();
    list.html_with(Some(&from))
}
