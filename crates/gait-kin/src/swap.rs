//! Left/right leg label swaps: detection by whole-leg temporal continuity, and correction.

use crate::config::Side;
use crate::tracks::{LEG, Tracks, dist};

/// Finds the frames whose left/right leg labels are exchanged and exchanges them back.
/// Returns, per frame of `tracks`, whether it was swapped.
pub trait SwapCorrector {
    fn correct(&self, tracks: &mut Tracks) -> Vec<bool>;
}

/// Two-state (kept / swapped) Viterbi over frames. The cost of a labelling is how far each
/// relabelled leg keypoint lies from its constant-velocity prediction from the two previous
/// (relabelled) frames, summed over both legs and all keypoints seen on both legs, plus a price
/// for every frame whose labels are exchanged: the model's labels are trusted unless continuity
/// clearly says otherwise. Without that price a single ambiguous frame where the legs cross
/// lets the labels flip for free, and real 30 fps video (BlazePose on the bundled sample) then
/// had a whole second of correct labels "corrected" to cancel one glitch at its end.
#[derive(Debug, Clone)]
pub struct ContinuitySwap {
    /// Price of exchanged labels per second of video, in median leg lengths (hip to ankle).
    /// Per second, not per frame: the continuity evidence at the ends of a swapped run does not
    /// grow with the frame rate, so a per-frame price would mean something else at 150 Hz.
    pub swap_price: f64,
}

impl Default for ContinuitySwap {
    fn default() -> Self {
        // 0.2 leg lengths per frame at 30 fps; chosen on the bundled sample (see tests).
        Self { swap_price: 6.0 }
    }
}

/// Leg keypoint indices `[left, right]` for each leg part present on both sides.
fn leg_pairs(t: &Tracks) -> Vec<[usize; 2]> {
    LEG.iter()
        .filter_map(|p| Some([t.leg_index(Side::Left, p)?, t.leg_index(Side::Right, p)?]))
        .collect()
}

impl ContinuitySwap {
    /// Cost of labelling frame `i` with `s` given labels `s1` at `i-1` and `s2` at `i-2`,
    /// or `None` when no keypoint links frame `i` to frame `i-1`.
    fn cost(
        t: &Tracks,
        pairs: &[[usize; 2]],
        i: usize,
        s: usize,
        s1: usize,
        s2: usize,
    ) -> Option<f64> {
        let mut total = 0.0;
        let mut linked = false;
        for pair in pairs {
            let both = |f: usize| Some((t.at(pair[0], f)?, t.at(pair[1], f)?));
            let (Some(now), Some(prev)) = (both(i), both(i - 1)) else {
                continue;
            };
            linked = true;
            let before = if i >= 2 { both(i - 2) } else { None };
            let pick = |p: ((f64, f64), (f64, f64)), leg: usize, swapped: usize| {
                if (leg ^ swapped) == 0 { p.0 } else { p.1 }
            };
            for leg in 0..2 {
                let a = pick(now, leg, s);
                let b = pick(prev, leg, s1);
                let predicted = match before {
                    Some(bb) => {
                        let c = pick(bb, leg, s2);
                        (2.0 * b.0 - c.0, 2.0 * b.1 - c.1)
                    }
                    None => b,
                };
                total += dist(a, predicted);
            }
        }
        linked.then_some(total)
    }

    /// Swap state per frame (true = labels exchanged in the input).
    pub fn detect(&self, t: &Tracks) -> Vec<bool> {
        let n = t.len();
        let pairs = leg_pairs(t);
        if n == 0 || pairs.is_empty() {
            return vec![false; n];
        }
        // State (s_prev, s_cur) encoded as 2 * s_prev + s_cur.
        let fps = if t.fps > 0.0 { t.fps } else { 30.0 };
        let price = self.swap_price * median_leg_length(t).unwrap_or(0.0) / fps;
        let mut score = [0.0, price, 0.0, price];
        let mut back: Vec<[usize; 4]> = vec![[0; 4]; n];
        let mut linked = vec![false; n];
        for i in 1..n {
            let mut next = [f64::INFINITY; 4];
            for (state, slot) in next.iter_mut().enumerate() {
                let (s1, s) = (state >> 1, state & 1);
                for s2 in 0..2 {
                    let from = 2 * s2 + s1;
                    let c = match Self::cost(t, &pairs, i, s, s1, s2) {
                        Some(c) => {
                            linked[i] = true;
                            c
                        }
                        None => 0.0,
                    };
                    // A negligible price per label change breaks exact ties (legs on top of
                    // each other) in favour of fewer changes.
                    let v = score[from]
                        + c
                        + if s != s1 { 1e-6 } else { 0.0 }
                        + if s == 1 { price } else { 0.0 };
                    if v < *slot {
                        *slot = v;
                        back[i][state] = from;
                    }
                }
            }
            // Keep scores small; only differences matter.
            let m = next.iter().copied().fold(f64::INFINITY, f64::min);
            score = next.map(|v| v - m);
        }
        let mut state = (0..4)
            .min_by(|&a, &b| score[a].total_cmp(&score[b]))
            .unwrap_or(0);
        let mut swapped = vec![false; n];
        for i in (0..n).rev() {
            swapped[i] = state & 1 == 1;
            if i == 0 {
                break;
            }
            if i == 1 {
                swapped[0] = state >> 1 == 1;
                break;
            }
            state = back[i][state];
        }
        // A frame with no leg keypoint on either side cannot be "swapped".
        for (i, s) in swapped.iter_mut().enumerate() {
            if !pairs
                .iter()
                .any(|p| t.at(p[0], i).is_some() || t.at(p[1], i).is_some())
            {
                *s = false;
            }
        }
        swapped
    }
}

/// Median hip-to-ankle distance over frames and sides, in pixels.
fn median_leg_length(t: &Tracks) -> Option<f64> {
    let mut lengths = Vec::new();
    for side in [Side::Left, Side::Right] {
        let (Some(h), Some(a)) = (t.leg_index(side, "hip"), t.leg_index(side, "ankle")) else {
            continue;
        };
        lengths.extend((0..t.len()).filter_map(|i| Some(dist(t.at(h, i)?, t.at(a, i)?))));
    }
    if lengths.is_empty() {
        return None;
    }
    lengths.sort_by(f64::total_cmp);
    Some(lengths[lengths.len() / 2])
}

/// Exchanges the left and right leg keypoints (with likelihoods) at frame `i`.
pub fn swap_frame(t: &mut Tracks, i: usize) {
    for p in LEG {
        if let (Some(l), Some(r)) = (t.leg_index(Side::Left, p), t.leg_index(Side::Right, p)) {
            for v in [&mut t.x, &mut t.y, &mut t.likelihood] {
                let tmp = v[l][i];
                v[l][i] = v[r][i];
                v[r][i] = tmp;
            }
        }
    }
}

impl SwapCorrector for ContinuitySwap {
    fn correct(&self, tracks: &mut Tracks) -> Vec<bool> {
        let swapped = self.detect(tracks);
        for (i, &s) in swapped.iter().enumerate() {
            if s {
                swap_frame(tracks, i);
            }
        }
        swapped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two legs swinging in antiphase, as seen from the side.
    fn walking(n: usize) -> Tracks {
        let names: Vec<String> = ["left", "right"]
            .iter()
            .flat_map(|s| LEG.iter().map(move |p| format!("{s}_{p}")))
            .collect();
        let mut t = Tracks {
            fps: 30.0,
            first_frame: 0,
            names,
            x: vec![vec![0.0; n]; 10],
            y: vec![vec![0.0; n]; 10],
            likelihood: vec![vec![1.0; n]; 10],
        };
        for i in 0..n {
            for (side, phase) in [(0, 0.0), (1, std::f64::consts::PI)] {
                let a = (i as f64 * 0.2 + phase).sin() * 0.4;
                for (k, r) in [0.0, 100.0, 200.0, 210.0, 220.0].iter().enumerate() {
                    let j = side * 5 + k;
                    t.x[j][i] = 5.0 * i as f64 + r * a.sin() + if k == 4 { 40.0 } else { 0.0 };
                    t.y[j][i] = r * a.cos();
                }
            }
        }
        t
    }

    #[test]
    fn finds_and_undoes_injected_swaps() {
        let clean = walking(120);
        let mut t = clean.clone();
        for i in (30..38).chain(70..71) {
            swap_frame(&mut t, i);
        }
        let swapped = ContinuitySwap::default().correct(&mut t);
        let expect: Vec<bool> = (0..120).map(|i| (30..38).contains(&i) || i == 70).collect();
        assert_eq!(swapped, expect);
        assert_eq!(t.x, clean.x);
        assert!(ContinuitySwap::default().detect(&clean).iter().all(|s| !s));
    }
}
