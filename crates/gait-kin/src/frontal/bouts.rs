//! Walking bouts in a front or back view: the frames where the whole body is seen and grows
//! (toward the camera) or shrinks (away) steadily, as a walker does and a person standing,
//! turning or stepping on the spot does not.

use crate::bouts::Bout;
use crate::config::{KinematicsConfig, Side};
use crate::direction::Direction;
use crate::frontal::scale::Scale;
use crate::tracks::Tracks;
use crate::view::View;

/// A walk along the camera axis changes the body's size by `speed / distance` per second:
/// 0.15 /s at 1.2 m/s from 8 m, 0.4 /s from 3 m. Standing changes it by nothing but noise.
const MIN_RATE: f64 = 0.04;

/// The bouts of `t` (input frame ranges), walking the way `view` says.
pub fn find(t: &Tracks, view: View, scale: &Scale, kin: &KinematicsConfig) -> Vec<Bout> {
    if let Some(given) = &kin.bouts {
        return given
            .iter()
            .map(|&[first, last]| bout(first, last))
            .collect();
    }
    let n = t.len();
    let fps = t.fps;
    let w = ((0.25 * fps).round() as usize).max(1);
    let sign = if view == View::Posterior { -1.0 } else { 1.0 };
    let walking: Vec<bool> = (0..n)
        .map(|i| {
            let (lo, hi) = (i.saturating_sub(w), (i + w).min(n - 1));
            let (a, b) = (scale.size[lo], scale.size[hi]);
            let rate = (b / a).ln() / ((hi - lo) as f64 / fps);
            whole_body(t, i, kin) && rate.is_finite() && sign * rate > MIN_RATE
        })
        .collect();
    let bridge = (kin.bout_bridge_s * fps).round() as usize;
    let min_len = (kin.bout_min_s * fps).round() as usize;
    runs(&walking, bridge)
        .into_iter()
        .filter(|&(a, b)| b + 1 - a >= min_len.max(1))
        .map(|(a, b)| bout(t.first_frame + a, t.first_frame + b))
        .collect()
}

fn bout(first: usize, last: usize) -> Bout {
    Bout {
        first,
        last,
        direction: Direction::Unknown,
        mean_speed: f64::NAN,
    }
}

/// Hips, knees and ankles of both legs seen, inside the frame's margin when its size is known.
fn whole_body(t: &Tracks, i: usize, kin: &KinematicsConfig) -> bool {
    Side::BOTH.iter().all(|&side| {
        ["hip", "knee", "ankle"].iter().all(|p| {
            let Some(pt) = t.leg_index(side, p).and_then(|j| t.at(j, i)) else {
                return false;
            };
            kin.frame_size.is_none_or(|[w, h]| {
                let m = kin.bout_edge_margin * w as f64;
                pt.0 >= m && pt.0 <= w as f64 - m && pt.1 >= m && pt.1 <= h as f64 - m
            })
        })
    })
}

/// Runs of `true`, joined across gaps of at most `bridge` samples (inclusive index pairs).
fn runs(on: &[bool], bridge: usize) -> Vec<(usize, usize)> {
    let mut out: Vec<(usize, usize)> = Vec::new();
    for (i, &v) in on.iter().enumerate() {
        if !v {
            continue;
        }
        match out.last_mut() {
            Some(last) if i - last.1 - 1 <= bridge => last.1 = i,
            _ => out.push((i, i)),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    #[test]
    fn short_pauses_are_bridged() {
        let on = [true, true, false, true, false, false, false, true];
        assert_eq!(super::runs(&on, 1), vec![(0, 3), (7, 7)]);
        assert_eq!(super::runs(&on, 3), vec![(0, 7)]);
    }
}
