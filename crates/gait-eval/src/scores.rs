//! Gait Variable Scores, the sagittal Gait Profile Score and the Movement
//! Analysis Profile (Baker et al. 2009), against a normative set.
//!
//! The published GPS is the RMS of nine 3-D kinematic variables; a 2-D video
//! has only the three sagittal ones (hip and knee flexion, ankle
//! dorsiflexion), so this is the *sagittal* GPS and is named so everywhere.

use serde::Serialize;

use crate::names::Side;
use crate::normative::Normative;
use crate::plot::CycleCurve;

/// The RMS difference between one mean curve and the normative mean (degrees).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Gvs {
    pub side: Side,
    pub joint: String,
    pub value: f64,
}

/// The sagittal GPS of one side (RMS of its GVS), or of both sides together.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Gps {
    /// None: both sides together (the overall score).
    pub side: Option<Side>,
    pub value: f64,
    /// The joints that went into it.
    pub joints: usize,
}

/// All scores of a run.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Scores {
    /// The normative set the scores are against.
    pub normative: String,
    pub gvs: Vec<Gvs>,
    /// Left, right, then overall, where the curves exist.
    pub gps: Vec<Gps>,
}

/// RMS over the cycle of `curve` minus `norm`; None when lengths differ or a
/// point is missing.
fn rms_difference(curve: &[f64], norm: &[f64]) -> Option<f64> {
    if curve.len() != norm.len() || curve.is_empty() {
        return None;
    }
    let mut ss = 0.0;
    for (a, b) in curve.iter().zip(norm) {
        let d = a - b;
        if !d.is_finite() {
            return None;
        }
        ss += d * d;
    }
    Some((ss / curve.len() as f64).sqrt())
}

fn rms(values: &[f64]) -> f64 {
    (values.iter().map(|v| v * v).sum::<f64>() / values.len() as f64).sqrt()
}

impl Scores {
    /// GVS per joint and side, and GPS per side and overall (a GPS needs all
    /// three joints of its sides).
    pub fn compute(curves: &[CycleCurve], norm: &Normative) -> Scores {
        let mut gvs = Vec::new();
        for side in [Side::Left, Side::Right] {
            for joint in crate::normative::JOINTS {
                let (Some(c), Some(n)) = (
                    curves.iter().find(|c| c.side == side && c.joint == joint),
                    norm.curve(joint),
                ) else {
                    continue;
                };
                if let Some(value) = rms_difference(&c.mean, &n.mean) {
                    gvs.push(Gvs {
                        side,
                        joint: joint.into(),
                        value,
                    });
                }
            }
        }
        let mut gps = Vec::new();
        for side in [Some(Side::Left), Some(Side::Right), None] {
            let values: Vec<f64> = gvs
                .iter()
                .filter(|g| side.is_none_or(|s| g.side == s))
                .map(|g| g.value)
                .collect();
            let needed = if side.is_some() { 3 } else { 6 };
            if values.len() == needed {
                gps.push(Gps {
                    side,
                    value: rms(&values),
                    joints: values.len(),
                });
            }
        }
        Scores {
            normative: norm.name.clone(),
            gvs,
            gps,
        }
    }

    /// The GVS of a joint and side.
    pub fn gvs_of(&self, side: Side, joint: &str) -> Option<f64> {
        self.gvs
            .iter()
            .find(|g| g.side == side && g.joint == joint)
            .map(|g| g.value)
    }

    /// The sagittal GPS of one side, or overall (`None`).
    pub fn gps_of(&self, side: Option<Side>) -> Option<f64> {
        self.gps.iter().find(|g| g.side == side).map(|g| g.value)
    }

    /// `scores.csv`: `score,side,joint,value,unit`.
    pub fn csv(&self) -> String {
        let mut s = String::from("score,side,joint,value,unit\n");
        for g in &self.gvs {
            s.push_str(&format!(
                "gvs,{},{},{:.6},deg\n",
                g.side.as_str(),
                g.joint,
                g.value
            ));
        }
        for g in &self.gps {
            let side = g.side.map_or("both", |s| s.as_str());
            s.push_str(&format!("gps_sagittal,{side},,{:.6},deg\n", g.value));
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::normative::NormCurve;

    fn curve(side: Side, joint: &str, offset: f64) -> CycleCurve {
        CycleCurve {
            side,
            joint: joint.into(),
            percent: (0..=100).map(f64::from).collect(),
            mean: (0..=100).map(|p| f64::from(p).sin() + offset).collect(),
            sd: vec![1.0; 101],
            n_cycles: 3,
        }
    }

    #[test]
    fn gvs_is_the_rms_difference_and_gps_their_rms() {
        let norm = Normative {
            name: "test".into(),
            source: String::new(),
            curves: crate::normative::JOINTS
                .iter()
                .map(|j| NormCurve {
                    joint: j.to_string(),
                    mean: curve(Side::Left, j, 0.0).mean,
                    sd: vec![5.0; 101],
                })
                .collect(),
            params: vec![],
        };
        // Constant offsets of 3, 4 and 12 degrees: GVS 3, 4, 12; GPS sqrt((9+16+144)/3).
        let curves: Vec<CycleCurve> = [("hip", 3.0), ("knee", -4.0), ("ankle", 12.0)]
            .iter()
            .map(|(j, o)| curve(Side::Left, j, *o))
            .collect();
        let s = Scores::compute(&curves, &norm);
        assert!((s.gvs_of(Side::Left, "knee").unwrap() - 4.0).abs() < 1e-12);
        let want = ((9.0 + 16.0 + 144.0) / 3.0f64).sqrt();
        assert!((s.gps_of(Some(Side::Left)).unwrap() - want).abs() < 1e-12);
        assert_eq!(s.gps_of(Some(Side::Right)), None, "no right curves");
        assert_eq!(s.gps_of(None), None, "overall needs both sides");
        assert!(s.csv().contains("gps_sagittal,left,,"));
    }
}
