//! Heel strikes and toe-offs from keypoints, or from a user's CSV.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::KinError;
use crate::config::Side;
use crate::direction::Direction;
use crate::tracks::Tracks;

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
}

/// Finds gait events in cleaned trajectories with a known direction per frame.
pub trait EventDetector {
    fn detect(&self, t: &Tracks, dirs: &[Direction]) -> Vec<Event>;
}

/// Zeni et al. (2008) coordinate method, refined by foot speed. Zeni: heel strike at the most
/// forward heel position relative to the pelvis, toe-off at the most backward toe position. At
/// those extrema the foot moves over the ground exactly as fast as the pelvis; at real contact
/// the heel is still. So each heel strike is moved forward to where the heel's speed over the
/// ground has fallen to `speed_fraction` of the walking speed, searched within `refine_s`.
/// Toe-offs use `toe_speed_fraction` the same way (backwards); its default 1 keeps Zeni's
/// extremum, because the toe point already moves while the foot rolls over the toes, before
/// the toe leaves the ground (on the independent trials in tests/independent_mocap.rs the
/// refined toe-off came 2-4 frames early). A fraction of 1 is plain Zeni.
///
/// Speeds are taken over the ground, not the image: the ground's image speed is the stance
/// foot's (per frame the slower foot, median over +-0.5 s), zero for a fixed camera over a
/// floor, minus the belt speed on a treadmill. The walking speed is the pelvis' speed over it.
#[derive(Debug, Clone)]
pub struct ZeniRefined {
    pub speed_fraction: f64,
    pub toe_speed_fraction: f64,
    pub refine_s: f64,
    /// Peaks closer than this (seconds) are merged, keeping the larger.
    pub min_stride_s: f64,
}

impl Default for ZeniRefined {
    fn default() -> Self {
        Self {
            speed_fraction: 0.5,
            toe_speed_fraction: 1.0,
            refine_s: 0.2,
            min_stride_s: 0.5,
        }
    }
}

/// Local maxima with at least `prominence`, at least `min_dist` samples apart (larger wins).
/// NaN splits the signal; extrema at the ends of a run are not peaks.
pub fn find_peaks(x: &[f64], prominence: f64, min_dist: usize) -> Vec<usize> {
    let n = x.len();
    let mut peaks = Vec::new();
    let mut i = 1;
    while i + 1 < n {
        if !(x[i].is_finite() && x[i - 1].is_finite()) || x[i] <= x[i - 1] {
            i += 1;
            continue;
        }
        // Plateau: take its middle.
        let mut j = i;
        while j + 1 < n && x[j + 1] == x[i] {
            j += 1;
        }
        if j + 1 < n && x[j + 1].is_finite() && x[j + 1] < x[i] {
            let p = (i + j) / 2;
            // Prominence: height above the higher of the two minima down to a higher point.
            let side_min = |range: &mut dyn Iterator<Item = usize>| {
                let mut m = x[p];
                for k in range {
                    if !x[k].is_finite() || x[k] > x[p] {
                        break;
                    }
                    m = m.min(x[k]);
                }
                m
            };
            let left = side_min(&mut (0..p).rev());
            let right = side_min(&mut (p + 1..n));
            if x[p] - left.max(right) >= prominence {
                peaks.push(p);
            }
        }
        i = j + 1;
    }
    // Enforce the minimum distance, highest peaks first.
    let mut order = peaks.clone();
    order.sort_by(|&a, &b| x[b].total_cmp(&x[a]));
    let mut keep: Vec<usize> = Vec::new();
    for p in order {
        if keep.iter().all(|&k| k.abs_diff(p) >= min_dist) {
            keep.push(p);
        }
    }
    keep.sort_unstable();
    keep
}

/// Forward speed (pixels/s) of keypoint `j` at frame `i` by central differences; NaN at the ends,
/// where a neighbour is missing, or where the direction is unknown.
fn forward_speed(t: &Tracks, dirs: &[Direction], j: usize, i: usize) -> f64 {
    let d = dirs.get(i).map_or(0.0, |d| d.sign());
    if i == 0 || i + 1 >= t.len() || d == 0.0 {
        return f64::NAN;
    }
    match (t.at(j, i - 1), t.at(j, i + 1)) {
        (Some(a), Some(b)) => d * (b.0 - a.0) * t.fps / 2.0,
        _ => f64::NAN,
    }
}

/// Per-frame forward image speed of the ground under the feet: the slower foot's speed (the
/// stance foot never moves faster than the ground, a swinging one does), median over +-0.5 s
/// to bridge double support and noise. 0 where no foot is seen.
pub(crate) fn ground_speed(t: &Tracks, dirs: &[Direction]) -> Vec<f64> {
    let n = t.len();
    let feet: Vec<Vec<usize>> = Side::BOTH
        .iter()
        .map(|&s| {
            ["heel", "toe"]
                .iter()
                .filter_map(|p| t.leg_index(s, p))
                .collect()
        })
        .collect();
    let raw: Vec<f64> = (0..n)
        .map(|i| {
            feet.iter()
                .filter(|f| !f.is_empty())
                .map(|f| {
                    f.iter().map(|&j| forward_speed(t, dirs, j, i)).sum::<f64>() / f.len() as f64
                })
                .filter(|v| v.is_finite())
                .fold(f64::NAN, f64::min)
        })
        .collect();
    let w = (0.5 * t.fps).round().max(1.0) as usize;
    (0..n)
        .map(|i| {
            let mut win: Vec<f64> = raw[i.saturating_sub(w)..(i + w + 1).min(n)]
                .iter()
                .copied()
                .filter(|v| v.is_finite())
                .collect();
            if win.is_empty() {
                return 0.0;
            }
            win.sort_by(f64::total_cmp);
            win[win.len() / 2]
        })
        .collect()
}

impl ZeniRefined {
    fn side_events(
        &self,
        t: &Tracks,
        dirs: &[Direction],
        ground: &[f64],
        side: Side,
        leg: f64,
    ) -> Vec<Event> {
        let n = t.len();
        let fps = t.fps;
        let pick = |parts: &[&str]| parts.iter().find_map(|p| t.leg_index(side, p));
        let (Some(heel), Some(toe)) = (pick(&["heel", "ankle"]), pick(&["toe", "ankle"])) else {
            return Vec::new();
        };
        let d = |i: usize| dirs.get(i).map_or(0.0, |d| d.sign());
        let rel = |j: usize, i: usize| match (t.at(j, i), t.pelvis(i)) {
            (Some(a), Some(p)) if d(i) != 0.0 => d(i) * (a.0 - p.0),
            _ => f64::NAN,
        };
        let heel_rel: Vec<f64> = (0..n).map(|i| rel(heel, i)).collect();
        let toe_back: Vec<f64> = (0..n).map(|i| -rel(toe, i)).collect();
        let min_dist = (self.min_stride_s * fps).round() as usize;
        let prom = 0.1 * leg;
        // Speeds over the ground (pixels/s).
        let speed = |j: usize, i: usize| forward_speed(t, dirs, j, i) - ground[i];
        let walking_speed = |i: usize| -> f64 {
            let w = (0.25 * fps).round().max(1.0) as usize;
            let (lo, hi) = (i.saturating_sub(w), (i + w).min(n - 1));
            match (t.pelvis(lo), t.pelvis(hi)) {
                (Some(a), Some(b)) if hi > lo => {
                    d(i) * (b.0 - a.0) * fps / (hi - lo) as f64 - ground[i]
                }
                _ => f64::NAN,
            }
        };
        let steps = (self.refine_s * fps).round() as usize;
        // Where foot speed crosses `fraction * walking speed`, as a rounded fractional frame.
        let refine = |j: usize, p: usize, forward: bool, fraction: f64| -> usize {
            let vp = walking_speed(p);
            if fraction >= 1.0 || !(vp.is_finite() && vp > 0.0) {
                return p;
            }
            let target = fraction * vp;
            for k in 0..steps {
                let (a, b) = if forward {
                    (p + k, p + k + 1)
                } else {
                    match (p.checked_sub(k + 1), p.checked_sub(k)) {
                        (Some(a), Some(b)) => (a, b),
                        _ => return p,
                    }
                };
                if b >= n {
                    return p;
                }
                let (va, vb) = (speed(j, a), speed(j, b));
                if !(va.is_finite() && vb.is_finite()) {
                    return p;
                }
                let crossed = if forward {
                    va > target && vb <= target
                } else {
                    va <= target && vb > target
                };
                if crossed {
                    let f = (va - target) / (va - vb);
                    return if f < 0.5 { a } else { b };
                }
            }
            p
        };
        let stable = |p: usize| {
            let w = (0.1 * fps).round() as usize;
            let lo = p.saturating_sub(w);
            let hi = (p + w).min(n - 1);
            (lo..=hi).all(|i| dirs.get(i) == dirs.get(p))
        };
        let mut out = Vec::new();
        for p in find_peaks(&heel_rel, prom, min_dist) {
            if stable(p) {
                let frame = refine(heel, p, true, self.speed_fraction);
                out.push(Event {
                    side,
                    event: EventKind::HeelStrike,
                    frame: t.first_frame + frame,
                });
            }
        }
        for p in find_peaks(&toe_back, prom, min_dist) {
            if stable(p) {
                let frame = refine(toe, p, false, self.toe_speed_fraction);
                out.push(Event {
                    side,
                    event: EventKind::ToeOff,
                    frame: t.first_frame + frame,
                });
            }
        }
        out
    }
}

impl EventDetector for ZeniRefined {
    fn detect(&self, t: &Tracks, dirs: &[Direction]) -> Vec<Event> {
        let leg = t.leg_length();
        if !leg.is_finite() || t.fps <= 0.0 {
            return Vec::new();
        }
        let ground = ground_speed(t, dirs);
        let mut ev: Vec<Event> = Side::BOTH
            .iter()
            .flat_map(|&s| self.side_events(t, dirs, &ground, s, leg))
            .collect();
        sort(&mut ev);
        ev
    }
}

/// Sorts events by frame, then side, then kind.
pub fn sort(ev: &mut [Event]) {
    ev.sort_by_key(|e| (e.frame, e.side == Side::Right, e.event));
}

/// Reads `side,event,frame[,time_s]` (header required; extra columns ignored).
pub fn read_csv(path: &Path) -> Result<Vec<Event>, KinError> {
    let bad = |why: String| KinError::EventsCsv {
        path: path.to_path_buf(),
        reason: why,
    };
    let mut r = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(path)
        .map_err(|e| bad(e.to_string()))?;
    let headers = r.headers().map_err(|e| bad(e.to_string()))?.clone();
    let col = |name: &str| {
        headers
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| bad(format!("no `{name}` column (need side,event,frame)")))
    };
    let (cs, ce, cf) = (col("side")?, col("event")?, col("frame")?);
    let mut out = Vec::new();
    for (row, rec) in r.records().enumerate() {
        let rec = rec.map_err(|e| bad(e.to_string()))?;
        let line = row + 2;
        let get = |c: usize| rec.get(c).unwrap_or("");
        let side = match get(cs) {
            "left" => Side::Left,
            "right" => Side::Right,
            s => return Err(bad(format!("line {line}: side `{s}` is not left or right"))),
        };
        let event = match get(ce) {
            "heel_strike" => EventKind::HeelStrike,
            "toe_off" => EventKind::ToeOff,
            s => {
                return Err(bad(format!(
                    "line {line}: event `{s}` is not heel_strike or toe_off"
                )));
            }
        };
        let frame = get(cf).parse::<usize>().map_err(|_| {
            bad(format!(
                "line {line}: frame `{}` is not a frame number",
                get(cf)
            ))
        })?;
        out.push(Event { side, event, frame });
    }
    sort(&mut out);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peaks_need_prominence_and_distance() {
        let x = [0.0, 1.0, 0.0, 5.0, 4.9, 5.1, 0.0, f64::NAN, 3.0, 0.0];
        assert_eq!(find_peaks(&x, 0.5, 1), vec![1, 5]);
        assert_eq!(find_peaks(&x, 2.0, 1), vec![5]);
        assert_eq!(find_peaks(&x, 0.5, 5), vec![5]);
        assert_eq!(find_peaks(&[f64::NAN, 0.0, 3.0, 0.0], 1.0, 1), vec![2]);
        assert!(find_peaks(&[1.0, 2.0, 3.0], 0.0, 1).is_empty());
    }

    #[test]
    fn reads_and_rejects_event_files() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("e.csv");
        std::fs::write(
            &p,
            "side,event,frame,time_s\nright,toe_off,20,0.6\nleft,heel_strike,3,0.1\n",
        )
        .unwrap();
        let ev = read_csv(&p).unwrap();
        assert_eq!(
            ev[0],
            Event {
                side: Side::Left,
                event: EventKind::HeelStrike,
                frame: 3
            }
        );
        std::fs::write(&p, "side,event,frame\nleft,foot_flat,3\n").unwrap();
        let e = read_csv(&p).unwrap_err().to_string();
        assert!(e.contains("foot_flat") && e.contains("line 2"), "{e}");
        std::fs::write(&p, "side,kind\n").unwrap();
        assert!(read_csv(&p).unwrap_err().to_string().contains("`event`"));
    }
}
