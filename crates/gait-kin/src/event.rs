//! One gait event: a foot, a kind and a time.

use serde::{Deserialize, Serialize};

use crate::config::Side;

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EventKind {
    HeelStrike,
    ToeOff,
}

impl EventKind {
    pub fn name(self) -> &'static str {
        match self {
            EventKind::HeelStrike => "heel_strike",
            EventKind::ToeOff => "toe_off",
        }
    }
}

/// One gait event at a frame index of the input (not a position in the timeline).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Event {
    pub side: Side,
    pub event: EventKind,
    pub frame: usize,
    /// Where between frames the event fell (input frames, within half a frame of `frame`),
    /// when the detector interpolates its threshold crossing; `None` for events placed on a
    /// frame (a user's CSV, a correction, an extremum). Durations use it: at 30 fps a frame is
    /// 5 % of a stance, so whole frames alone tip a stance-time ratio or a stride time.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at: Option<f64>,
}

impl Event {
    /// An event placed on a frame.
    pub fn on_frame(side: Side, event: EventKind, frame: usize) -> Self {
        Self {
            side,
            event,
            frame,
            at: None,
        }
    }

    /// An event at sub-frame time `at` (input frames), on its nearest frame.
    pub fn between_frames(side: Side, event: EventKind, at: f64) -> Self {
        Self {
            side,
            event,
            frame: at.round() as usize,
            at: Some(at),
        }
    }

    /// The event's time in input frames, sub-frame where known.
    pub fn time(&self) -> f64 {
        self.at.unwrap_or(self.frame as f64)
    }

    /// What identifies an event, whatever its sub-frame time.
    pub fn key(&self) -> (Side, EventKind, usize) {
        (self.side, self.event, self.frame)
    }
}

/// Sorts events by frame, then side, then kind.
pub fn sort(ev: &mut [Event]) {
    ev.sort_by_key(|e| (e.frame, e.side == Side::Right, e.event));
}
