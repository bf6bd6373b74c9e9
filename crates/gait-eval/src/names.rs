//! Body sides and the mapping of foreign keypoint names onto [`gait_core::CANONICAL`].

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// A body side.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    Left,
    Right,
}

impl Side {
    pub const BOTH: [Side; 2] = [Side::Left, Side::Right];

    pub fn as_str(self) -> &'static str {
        match self {
            Side::Left => "left",
            Side::Right => "right",
        }
    }

    pub fn other(self) -> Side {
        match self {
            Side::Left => Side::Right,
            Side::Right => Side::Left,
        }
    }

    /// The side a canonical name belongs to (`left_knee` -> left), if any.
    pub fn of(name: &str) -> Option<Side> {
        if name.starts_with("left_") {
            Some(Side::Left)
        } else if name.starts_with("right_") {
            Some(Side::Right)
        } else {
            None
        }
    }
}

impl std::str::FromStr for Side {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "left" => Ok(Side::Left),
            "right" => Ok(Side::Right),
            _ => Err(format!("`{s}` is not a side; use `left` or `right`")),
        }
    }
}

/// The lower-limb parts evaluated per leg, proximal to distal.
pub const LEG_PARTS: [&str; 5] = ["hip", "knee", "ankle", "heel", "toe"];

/// Canonical name of `part` on `side`, e.g. (`Left`, "knee") -> "left_knee".
pub fn leg_name(side: Side, part: &str) -> String {
    format!("{}_{part}", side.as_str())
}

/// Maps a keypoint name from a file onto a canonical name: first through the
/// user's `map`, then canonical names as they are, then common spellings of
/// labelled data (`RKnee`, `knee_r`, `Right Knee`, `LBigToe`, `MidHip`, ...).
/// Returns `None` for names with no canonical counterpart.
pub fn to_canonical(name: &str, map: &BTreeMap<String, String>) -> Option<String> {
    if let Some(m) = map.get(name) {
        return Some(m.clone());
    }
    if gait_core::keypoint::canonical_index(name).is_some() {
        return Some(name.to_string());
    }
    let norm: String = name
        .chars()
        .filter(|c| c.is_ascii_alphanumeric())
        .collect::<String>()
        .to_ascii_lowercase();
    let part_of = |p: &str| -> Option<&'static str> {
        match p {
            "hip" => Some("hip"),
            "knee" => Some("knee"),
            "ankle" => Some("ankle"),
            "heel" => Some("heel"),
            "toe" | "toes" | "bigtoe" => Some("toe"),
            "shoulder" => Some("shoulder"),
            _ => None,
        }
    };
    match norm.as_str() {
        "nose" => return Some("nose".into()),
        "neck" => return Some("neck".into()),
        "midhip" | "pelvis" => return Some("mid_hip".into()),
        _ => {}
    }
    // Side as a prefix or suffix, long forms first so "right" is not read as "r" + "ight".
    for (token, side) in [
        ("left", Side::Left),
        ("right", Side::Right),
        ("l", Side::Left),
        ("r", Side::Right),
    ] {
        let rest = norm
            .strip_prefix(token)
            .or_else(|| norm.strip_suffix(token));
        if let Some(part) = rest.and_then(part_of) {
            return Some(leg_name(side, part));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_common_spellings() {
        let none = BTreeMap::new();
        for (from, to) in [
            ("RKnee", "right_knee"),
            ("knee_r", "right_knee"),
            ("Left Ankle", "left_ankle"),
            ("LBigToe", "left_toe"),
            ("right_toe", "right_toe"),
            ("MidHip", "mid_hip"),
            ("toe_left", "left_toe"),
        ] {
            assert_eq!(to_canonical(from, &none).as_deref(), Some(to), "{from}");
        }
        assert_eq!(to_canonical("LSmallToe", &none), None);
        assert_eq!(to_canonical("elbow", &none), None);
        let map = BTreeMap::from([("foo".to_string(), "left_knee".to_string())]);
        assert_eq!(to_canonical("foo", &map).as_deref(), Some("left_knee"));
    }
}
