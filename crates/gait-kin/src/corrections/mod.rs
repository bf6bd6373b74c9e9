//! Corrections a person or a script writes (`corrections.toml`), applied by the analysis.
//!
//! Set `[kinematics] corrections = "corrections.toml"` (or `--set
//! kinematics.corrections=corrections.toml`) and [`crate::analyse`] reads the file, checks it
//! against the keypoints ([`Corrections::validate`]) and applies it. Every table is optional and
//! may repeat; frames are input frame numbers, as in `events.csv` and `angles.csv`, and ranges
//! include both ends.
//!
//! ```toml
//! [[swap]]          # exchange the left and right leg labels, frames inclusive
//! first = 120
//! last = 131
//!
//! [[event]]
//! side = "left"     # "left" | "right"
//! kind = "heel_strike"   # "heel_strike" | "toe_off"
//! frame = 152
//! action = "add"    # "add" | "remove" (remove: the automatic event nearest this frame, within 3 frames)
//!
//! [[exclude]]       # frames left out of events and cycles
//! first = 186
//! last = 229
//!
//! [[keypoint]]      # set one keypoint in one frame (likelihood 1)
//! frame = 140
//! name = "right_ankle"
//! x = 812.5
//! y = 901.0
//! ```
//!
//! What each table does, and where in the chain (see the crate docs for the chain):
//!
//! - `[[swap]]`: after the automatic swap correction, the left and right leg keypoints (hip,
//!   knee, ankle, heel, toe, with their likelihoods) are exchanged over the range, so the
//!   automatic correction cannot undo a person's decision. The labels there are then the
//!   person's: frames in a `[[swap]]` range never count as swapped for the cycle quality
//!   (`cycle_max_swapped_share`), not even where the automatic correction had exchanged them.
//!   Swap ranges must not overlap.
//! - `[[event]]`: after event detection (or `events_csv`) and the bout filter, `remove` deletes
//!   the event of that side and kind nearest `frame`, which must lie within 3 frames of it (the
//!   analysis stops with an error otherwise); `add` inserts one, kept even outside the walking
//!   bouts. Removals come before additions, so an `add` is never removed; an `add` may not lie in
//!   an `[[exclude]]` range.
//! - `[[exclude]]`: events in the range are dropped, and a stride (heel strike to heel strike)
//!   overlapping it is rejected with the reason `excluded` in `cycle_quality.csv`, leaves the
//!   median stride time alone and gives no steps to the spatiotemporal parameters. Bouts and
//!   angles are not changed. Ranges may overlap.
//! - `[[keypoint]]`: the keypoint is set to (x, y) with likelihood 1, in the labels of the
//!   output (`keypoints_filtered.csv`, after both swap corrections), before gap filling and
//!   smoothing; so it also counts as seen by the pose model for the quality rules. `name` is a
//!   keypoint of the input (e.g. `right_ankle`); one entry per keypoint and frame.
//!
//! Unknown tables or keys, a frame outside the input's frames, `last` before `first`, an
//! unknown keypoint name and a non-finite coordinate are refused with a one-line message that
//! names the file and the entry (entries are numbered from 1 in the file's order), e.g.
//! `corrections.toml: [[swap]] #2 (frames 120-131) overlaps [[swap]] #1 (frames 125-140)`.

mod apply;
mod format;

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::config::Side;
use crate::events::EventKind;

pub(crate) use apply::{
    apply_events, apply_keypoints, apply_swaps, excluded_overlap, summary, warning,
};
pub(crate) use format::load;
pub use format::sha256_hex;

/// The contents of a `corrections.toml` (see the module docs).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Corrections {
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub swap: Vec<FrameRange>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub event: Vec<EventEdit>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub exclude: Vec<FrameRange>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub keypoint: Vec<KeypointEdit>,
}

/// Input frames `first..=last`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameRange {
    pub first: usize,
    pub last: usize,
}

impl FrameRange {
    pub fn contains(&self, frame: usize) -> bool {
        (self.first..=self.last).contains(&frame)
    }

    /// Whether the range shares a frame with `first..=last`.
    pub fn overlaps(&self, first: usize, last: usize) -> bool {
        self.first <= last && first <= self.last
    }

    /// Number of frames (0 when `last < first`).
    pub fn frames(&self) -> usize {
        (self.last + 1).saturating_sub(self.first)
    }
}

/// `[[event]]`: add or remove one gait event.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EventEdit {
    pub side: Side,
    pub kind: EventKind,
    pub frame: usize,
    pub action: EventAction,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EventAction {
    /// Insert the event.
    Add,
    /// Delete the event of that side and kind nearest the frame, within 3 frames.
    Remove,
}

/// `[[keypoint]]`: one keypoint at one frame, set by hand (likelihood 1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeypointEdit {
    pub frame: usize,
    pub name: String,
    pub x: f64,
    pub y: f64,
}

/// What an analysis applied from a corrections file (for run.json).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct CorrectionsSummary {
    /// The file as configured (`kinematics.corrections`).
    pub path: PathBuf,
    /// SHA-256 of the file's bytes, lower-case hex.
    pub sha256: String,
    /// `[[swap]]` entries, and the frames they cover.
    pub swaps: usize,
    pub swapped_frames: usize,
    /// `[[event]]` entries with `action = "add"` / `"remove"`.
    pub events_added: usize,
    pub events_removed: usize,
    /// `[[exclude]]` entries, and the frames they cover together.
    pub excludes: usize,
    pub excluded_frames: usize,
    /// `[[keypoint]]` entries.
    pub keypoints: usize,
}

/// Events a `remove` may be this many frames from the frame it names.
pub(crate) const REMOVE_WITHIN_FRAMES: usize = 3;
