//! Which foot keypoints the pose model gives, and what follows for the events and the ankle
//! angle: a model without feet (OpenPose COCO-18, COCO-17 models) has its events taken from
//! the ankles and no ankle angle, and the warnings say so.

use std::collections::BTreeMap;

use crate::config::{KinematicsConfig, Side};
use crate::events;
use crate::tracks::Tracks;

/// The keypoints each side's events come from, with a warning where a model without feet leaves
/// only the ankle (none when the events come from a file).
pub(crate) fn event_keypoints(
    t: &Tracks,
    kin: &KinematicsConfig,
    warnings: &mut Vec<String>,
) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    if kin.events_csv.is_some() || t.is_empty() {
        return out;
    }
    for side in Side::BOTH {
        let Some(k) = events::EventKeypoints::of(t, side) else {
            continue;
        };
        let used = k.describe(t);
        if t.names[k.heel_strike].ends_with("_ankle") || t.names[k.toe_off].ends_with("_ankle") {
            warnings.push(format!(
                "no {0} heel or toe keypoint in any frame: {0} events from {used} (Zeni's method on the ankle)",
                side.name()
            ));
        }
        out.insert(side.name().to_string(), used);
    }
    out
}

/// Without a toe there is no foot segment: say so instead of leaving the reader to wonder why
/// the ankle column is empty (OpenPose COCO-18 has no feet).
pub(crate) fn warn_missing_toes(t: &Tracks, warnings: &mut Vec<String>) {
    for side in ["left", "right"] {
        let toe = format!("{side}_toe");
        let seen = t
            .names
            .iter()
            .position(|name| *name == toe)
            .is_some_and(|j| t.x[j].iter().any(|v| v.is_finite()));
        if !t.is_empty() && !seen {
            warnings.push(format!(
                "no {toe} keypoint in any frame (the pose model may have no feet, e.g. OpenPose COCO-18): the {side} ankle angle is unavailable"
            ));
        }
    }
}
