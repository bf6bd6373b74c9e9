//! Left/right leg label swaps: detection by whole-leg temporal continuity, and correction.

use crate::config::Side;
use crate::tracks::{LEG, LOWER_LEG, Tracks, dist};

/// Finds the frames whose left/right leg labels are exchanged and exchanges them back.
/// Returns, per frame of `tracks`, whether it was swapped.
pub trait SwapCorrector {
    fn correct(&self, tracks: &mut Tracks) -> Vec<bool>;

    /// As [`Self::correct`], and per frame whether its labels are a guess rather than evidence
    /// (the cycle check rejects strides with many: `cycle_max_swapped_share`). By default every
    /// exchanged frame counts as one.
    fn correct_judged(&self, tracks: &mut Tracks) -> Labels {
        let swapped = self.correct(tracks);
        Labels {
            unsure: swapped.clone(),
            swapped,
        }
    }
}

/// A swap correction's verdict per frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Labels {
    /// The labels were exchanged (and have been exchanged back).
    pub swapped: Vec<bool>,
    /// The labels, exchanged or not, are in doubt.
    pub unsure: Vec<bool>,
}

/// Two-state (kept / swapped) Viterbi over frames. The cost of a labelling is how far each
/// relabelled leg keypoint lies from its constant-velocity prediction from the two previous
/// (relabelled) observed frames, summed over both legs and all keypoints seen on both legs
/// (see [`ContinuitySwap::detect`] for frames without lower legs in between), plus a price
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
    /// Observed frames further apart than this (seconds) are not linked: after a long gap the
    /// labels are free. 0.15 s bridges a dropped collapse (`collapse::CollapseRule`, up to
    /// 0.1 s) with a frame to spare.
    pub max_link_s: f64,
    /// A frame's labels are in doubt when the labelling the other way round would cost less
    /// than this many frames' `swap_price` more: the continuity evidence hardly outweighs the
    /// trust in the model. A clean exchange of a leg, even for a single frame, wins by ten
    /// times that (2-8 leg lengths on the bundled sample and its re-encodings); legs that
    /// cross or that the model draws half on each other are decided by 0.05-0.3.
    pub doubt_frames: f64,
}

impl Default for ContinuitySwap {
    fn default() -> Self {
        // 0.2 leg lengths per frame at 30 fps; chosen on the bundled sample (see tests).
        Self {
            swap_price: 6.0,
            max_link_s: 0.15,
            doubt_frames: 1.5,
        }
    }
}

/// Leg keypoint indices `[left, right]` for each leg part present on both sides.
fn leg_pairs(t: &Tracks) -> Vec<[usize; 2]> {
    LEG.iter()
        .filter_map(|p| Some([t.leg_index(Side::Left, p)?, t.leg_index(Side::Right, p)?]))
        .collect()
}

impl ContinuitySwap {
    /// `swap_price` for one frame of `t`, in pixels of continuity cost.
    fn frame_price(&self, t: &Tracks) -> f64 {
        let fps = if t.fps > 0.0 { t.fps } else { 30.0 };
        self.swap_price * median_leg_length(t).unwrap_or(0.0) / fps
    }

    /// Cost of labelling observed frame `a` with `s`, given labels `s1` at the previous observed
    /// frame `b` and `s2` at the one before, `c`; `None` when no keypoint links `a` to `b`.
    /// Frames need not be adjacent: the constant-velocity prediction is scaled by the frame
    /// spacing, so a frame dropped in between (a collapse, a gated keypoint) does not cut the
    /// evidence.
    fn cost(
        t: &Tracks,
        pairs: &[[usize; 2]],
        (a, b, c): (usize, usize, Option<usize>),
        (s, s1, s2): (usize, usize, usize),
    ) -> Option<f64> {
        let mut total = 0.0;
        let mut linked = false;
        for pair in pairs {
            let both = |f: usize| Some((t.at(pair[0], f)?, t.at(pair[1], f)?));
            let (Some(now), Some(prev)) = (both(a), both(b)) else {
                continue;
            };
            linked = true;
            let before = c.and_then(|c| Some((c, both(c)?)));
            let pick = |p: ((f64, f64), (f64, f64)), leg: usize, swapped: usize| {
                if (leg ^ swapped) == 0 { p.0 } else { p.1 }
            };
            for leg in 0..2 {
                let x = pick(now, leg, s);
                let y = pick(prev, leg, s1);
                let predicted = match before {
                    Some((c, cc)) => {
                        let z = pick(cc, leg, s2);
                        let k = (a - b) as f64 / (b - c) as f64;
                        (y.0 + k * (y.0 - z.0), y.1 + k * (y.1 - z.1))
                    }
                    None => y,
                };
                total += dist(x, predicted);
            }
        }
        linked.then_some(total)
    }

    /// Swap state per frame (true = labels exchanged in the input).
    ///
    /// The Viterbi runs over the observed frames: those with a lower-leg keypoint (knee, ankle,
    /// heel or toe) on both sides. Consecutive observed frames up to `max_link_s` apart are
    /// linked. A frame in between with some leg keypoints (one side only, or the hips only)
    /// takes the labels of the observed frame before it (after it at the start).
    pub fn detect(&self, t: &Tracks) -> Vec<bool> {
        self.decide(t).0
    }

    /// [`Self::detect`]'s swap state per frame, and per frame how sure it is: the margin, in
    /// pixels of continuity cost, by which the best labelling with that frame the other way
    /// round loses (infinite where a frame has no leg keypoint).
    pub fn decide(&self, t: &Tracks) -> (Vec<bool>, Vec<f64>) {
        let n = t.len();
        let pairs = leg_pairs(t);
        let mut margins = vec![f64::INFINITY; n];
        if n == 0 || pairs.is_empty() {
            return (vec![false; n], margins);
        }
        let fps = if t.fps > 0.0 { t.fps } else { 30.0 };
        let lower: Vec<[usize; 2]> = LOWER_LEG
            .iter()
            .filter_map(|p| Some([t.leg_index(Side::Left, p)?, t.leg_index(Side::Right, p)?]))
            .collect();
        let obs: Vec<usize> = (0..n)
            .filter(|&i| {
                lower
                    .iter()
                    .any(|p| t.at(p[0], i).is_some() && t.at(p[1], i).is_some())
            })
            .collect();
        let m = obs.len();
        let mut swapped = vec![false; n];
        if m == 0 {
            return (swapped, margins);
        }
        let max_link = ((self.max_link_s * fps).round() as usize).max(1);
        let near = |x: usize, y: usize| x - y <= max_link;
        let price = self.frame_price(t);
        // steps[k][4 * s2 + 2 * s1 + s]: the cost of the step into observed frame k with labels
        // s there, s1 at k - 1 and s2 at k - 2 (1 = exchanged).
        let steps: Vec<[f64; 8]> = (0..m)
            .map(|k| {
                let mut c = [0.0; 8];
                if k == 0 {
                    return c;
                }
                let (a, b) = (obs[k], obs[k - 1]);
                let before = (k >= 2 && near(b, obs[k - 2])).then(|| obs[k - 2]);
                for (i, v) in c.iter_mut().enumerate() {
                    let (s2, s1, s) = (i >> 2, (i >> 1) & 1, i & 1);
                    let fit = if near(a, b) {
                        Self::cost(t, &pairs, (a, b, before), (s, s1, s2)).unwrap_or(0.0)
                    } else {
                        0.0
                    };
                    // A negligible price per label change breaks exact ties (legs on top of
                    // each other) in favour of fewer changes.
                    *v = fit + if s != s1 { 1e-6 } else { 0.0 } + if s == 1 { price } else { 0.0 };
                }
                c
            })
            .collect();
        let (on_obs, margin_obs) = viterbi(&steps, price);
        // Every frame with a leg keypoint takes the state of the last observed frame up to it;
        // a frame with no leg keypoint on either side cannot be "swapped".
        let mut k = 0;
        for (i, s) in swapped.iter_mut().enumerate() {
            while k + 1 < m && obs[k + 1] <= i {
                k += 1;
            }
            let any = pairs
                .iter()
                .any(|p| t.at(p[0], i).is_some() || t.at(p[1], i).is_some());
            *s = any && on_obs[k];
            margins[i] = if any { margin_obs[k] } else { f64::INFINITY };
        }
        (swapped, margins)
    }
}

/// Best labels per observed frame over a two-frame-memory chain (state `2 * s_prev + s`), and
/// each frame's margin: how much more the best labelling with that frame's labels the other
/// way round would cost (forward and backward min-costs).
fn viterbi(steps: &[[f64; 8]], price: f64) -> (Vec<bool>, Vec<f64>) {
    let m = steps.len();
    let norm = |v: [f64; 4]| {
        let low = v.iter().copied().fold(f64::INFINITY, f64::min);
        v.map(|x| x - low)
    };
    let mut fwd = vec![[0.0, price, 0.0, price]; m];
    let mut back: Vec<[usize; 4]> = vec![[0; 4]; m];
    for k in 1..m {
        let mut next = [f64::INFINITY; 4];
        for (state, slot) in next.iter_mut().enumerate() {
            let (s1, s) = (state >> 1, state & 1);
            for s2 in 0..2 {
                let v = fwd[k - 1][2 * s2 + s1] + steps[k][4 * s2 + 2 * s1 + s];
                if v < *slot {
                    *slot = v;
                    back[k][state] = 2 * s2 + s1;
                }
            }
        }
        fwd[k] = norm(next);
    }
    let mut bwd = vec![[0.0; 4]; m];
    for k in (0..m.saturating_sub(1)).rev() {
        let mut here = [f64::INFINITY; 4];
        for (state, slot) in here.iter_mut().enumerate() {
            let (s1, s) = (state >> 1, state & 1);
            for s_next in 0..2 {
                let v = steps[k + 1][4 * s1 + 2 * s + s_next] + bwd[k + 1][2 * s + s_next];
                *slot = slot.min(v);
            }
        }
        bwd[k] = norm(here);
    }
    let mut state = (0..4)
        .min_by(|&a, &b| fwd[m - 1][a].total_cmp(&fwd[m - 1][b]))
        .unwrap_or(0);
    let mut on_obs = vec![false; m];
    for k in (0..m).rev() {
        on_obs[k] = state & 1 == 1;
        if k == 0 {
            break;
        }
        if k == 1 {
            on_obs[0] = state >> 1 == 1;
            break;
        }
        state = back[k][state];
    }
    let margins = (0..m)
        .map(|k| {
            let best = |s: usize| {
                let total = |s1: usize| fwd[k][2 * s1 + s] + bwd[k][2 * s1 + s];
                total(0).min(total(1))
            };
            (best(0) - best(1)).abs()
        })
        .collect();
    (on_obs, margins)
}

/// Median hip-to-ankle distance over frames and sides, in pixels.
pub(crate) fn median_leg_length(t: &Tracks) -> Option<f64> {
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
        self.correct_judged(tracks).swapped
    }

    fn correct_judged(&self, tracks: &mut Tracks) -> Labels {
        let (swapped, margins) = self.decide(tracks);
        for (i, &s) in swapped.iter().enumerate() {
            if s {
                swap_frame(tracks, i);
            }
        }
        let price = self.frame_price(tracks);
        let unsure = margins
            .iter()
            .map(|&m| m < self.doubt_frames * price)
            .collect();
        Labels { swapped, unsure }
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

    /// A clean exchange is corrected without doubt, even for one frame; a frame where the model
    /// drew both legs half on each other is in doubt whatever labels it gets. (A longer run of
    /// such frames keeps the model's labels by the price of exchanging them all: the doubt
    /// is per frame.) The first frame has no evidence before it.
    #[test]
    fn doubt_where_continuity_cannot_tell() {
        let clean = walking(120);
        let mut t = clean.clone();
        swap_frame(&mut t, 40);
        for i in [80, 100] {
            for k in 0..5 {
                for v in [&mut t.x, &mut t.y] {
                    let mean = (v[k][i] + v[5 + k][i]) / 2.0;
                    (v[k][i], v[5 + k][i]) = (mean, mean);
                }
            }
        }
        let labels = ContinuitySwap::default().correct_judged(&mut t);
        assert!(labels.swapped[40] && !labels.unsure[40]);
        let unsure: Vec<usize> = (0..120).filter(|&i| labels.unsure[i]).collect();
        assert_eq!(unsure, vec![0, 80, 100]);
    }

    /// Labels exchanged from just after a frame without lower legs (a dropped collapse) up to
    /// where the legs next cross (78-79, where any labels fit): only the link across the
    /// dropped frame shows the exchange. A frame in the run with one leg only (74) takes the
    /// run's labels.
    #[test]
    fn links_across_a_dropped_frame() {
        let clean = walking(120);
        let mut t = clean.clone();
        for i in 71..=78 {
            swap_frame(&mut t, i);
        }
        for j in (1..5).chain(6..10) {
            t.x[j][70] = f64::NAN;
            t.y[j][70] = f64::NAN;
        }
        for j in 5..10 {
            t.x[j][74] = f64::NAN;
            t.y[j][74] = f64::NAN;
        }
        let swapped = ContinuitySwap::default().detect(&t);
        let found: Vec<usize> = (0..120).filter(|&i| swapped[i]).collect();
        assert!(
            found.first() == Some(&71) && (77..=79).contains(found.last().unwrap()),
            "{found:?}"
        );
        assert_eq!(found.len(), found.last().unwrap() - 70, "{found:?}");
        // Without links across gaps, 71-73 (between the two gaps) have no evidence.
        let unlinked = ContinuitySwap {
            max_link_s: 0.0,
            ..Default::default()
        }
        .detect(&t);
        assert!((71..=73).all(|i| !unlinked[i]));
    }
}
