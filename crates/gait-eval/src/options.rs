//! Evaluation options (the `[eval]` table of a config, or CLI flags).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::EvalError;
use crate::names::Side;

/// Options of [`crate::evaluate`]. Every key has a default.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EvalOptions {
    /// Method name shown as the table column (e.g. "OpenPose", "Zero-shot").
    pub method: String,
    /// Row group of the table, e.g. the amputation type ("Transtibial").
    pub group: Option<String>,
    /// Camera view the video was taken from (e.g. "right"), for failure-mode bars.
    pub view: Option<String>,
    /// The side with the prosthesis; the other leg is the intact one.
    pub prosthetic_side: Side,
    /// Keypoint names of either file -> canonical names, tried before the
    /// built-in spellings (`RKnee`, `knee_r`, ...).
    pub name_map: BTreeMap<String, String>,
    /// A predicted keypoint counts as identified when found with at least this likelihood.
    pub min_likelihood: f64,
    /// Length in pixels that the failure thresholds are fractions of; by
    /// default the median ground-truth thigh (hip-knee) length.
    pub reference_length_px: Option<f64>,
    /// A keypoint is obviously misidentified when its error exceeds this
    /// fraction of the reference length.
    pub misid_fraction: f64,
    /// A frame's legs are swapped when the cross-side error beats the same-side
    /// error by more than this fraction of the reference length per keypoint pair.
    pub swap_fraction: f64,
}

impl Default for EvalOptions {
    fn default() -> Self {
        Self {
            method: "prediction".into(),
            group: None,
            view: None,
            prosthetic_side: Side::Right,
            name_map: BTreeMap::new(),
            min_likelihood: 0.0,
            reference_length_px: None,
            misid_fraction: 0.5,
            swap_fraction: 0.1,
        }
    }
}

impl EvalOptions {
    /// Rejects values that make no sense, naming the key.
    pub fn validate(&self) -> Result<(), EvalError> {
        let bad = |key, reason: &str| {
            Err(EvalError::Option {
                key,
                reason: reason.to_string(),
            })
        };
        if !(0.0..=1.0).contains(&self.min_likelihood) {
            return bad("min_likelihood", "must be in [0, 1]");
        }
        if !(self.misid_fraction.is_finite() && self.misid_fraction > 0.0) {
            return bad("misid_fraction", "must be a positive number");
        }
        if !(self.swap_fraction.is_finite() && self.swap_fraction >= 0.0) {
            return bad("swap_fraction", "must be zero or positive");
        }
        if let Some(l) = self.reference_length_px
            && !(l.is_finite() && l > 0.0)
        {
            return bad("reference_length_px", "must be a positive number of pixels");
        }
        Ok(())
    }

    /// "prosthetic" or "intact" for a side.
    pub fn role(&self, side: Side) -> Role {
        if side == self.prosthetic_side {
            Role::Prosthetic
        } else {
            Role::Intact
        }
    }
}

/// Whether a leg carries the prosthesis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Role {
    Prosthetic,
    Intact,
}

impl Role {
    pub fn as_str(self) -> &'static str {
        match self {
            Role::Prosthetic => "prosthetic",
            Role::Intact => "intact",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn toml_defaults_and_unknown_keys() {
        let o: EvalOptions =
            toml::from_str("prosthetic_side = \"left\"\nmethod = \"Zero-shot\"").unwrap();
        assert_eq!(o.prosthetic_side, Side::Left);
        assert_eq!(o.misid_fraction, 0.5);
        let e = toml::from_str::<EvalOptions>("misid = 3")
            .unwrap_err()
            .to_string();
        assert!(e.contains("misid") && e.contains("misid_fraction"), "{e}");
        let o = EvalOptions {
            swap_fraction: -1.0,
            ..Default::default()
        };
        assert!(
            o.validate()
                .unwrap_err()
                .to_string()
                .contains("swap_fraction")
        );
    }
}
