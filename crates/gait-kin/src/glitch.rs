//! Frames where the pose jumped to someone else for a moment.
//!
//! Where the subject passes in front of or behind another person, a pose model's crop holds
//! both, and for a frame or a few it may draw the other person, or half of each. The pelvis then
//! leaves the subject's path and comes back. Those frames are not the subject: their keypoints
//! are dropped, like the frames with collapsed legs, and the gap filler bridges them. Before,
//! the bout rules took each such frame for a tracker jump and ended the bout there; which frames
//! were affected changed with the encoding (the bundled sample, where the walker passes the man
//! on the box, lost 1 to 3 of its 4 cycles under H.264 CRF 28 and HEVC).
//!
//! A jump that does not come back within `max_run_s` is a real change of person (or the
//! subject leaving) and is left to the bout rules.

use crate::tracks::{Tracks, dist};

/// The glitch test: a frame's pelvis further than `tolerance` leg lengths from where the
/// subject's path predicts it (plus `spread` leg lengths for the frame and each frame without
/// a pose since the last one on the path), in a run of at most `max_run_s` after which the
/// pelvis is back on the path.
#[derive(Debug, Clone)]
pub struct GlitchRule {
    pub tolerance: f64,
    pub spread: f64,
    pub max_run_s: f64,
}

impl Default for GlitchRule {
    fn default() -> Self {
        // A walking pelvis moves about 0.05 leg lengths a frame at 30 fps and a pose model's
        // pelvis jitters by a few pixels: a quarter of a leg off the path is neither. The run
        // limit is the gap filler's (`postprocess.max_gap_s`), so every dropped run is bridged.
        Self {
            tolerance: 0.25,
            spread: 0.05,
            max_run_s: 0.33,
        }
    }
}

impl GlitchRule {
    /// Per frame of `t`, whether its pose left the subject's path for a moment.
    pub fn find(&self, t: &Tracks) -> Vec<bool> {
        let n = t.len();
        let mut out = vec![false; n];
        let leg = t.leg_length();
        if !(leg.is_finite() && leg > 0.0 && t.fps > 0.0) {
            return out;
        }
        let max_run = ((self.max_run_s * t.fps).round() as usize).max(1);
        let base = (0.2 * t.fps).round().max(1.0) as usize;
        // Frames on the path so far (frame, pelvis).
        let mut path: Vec<(usize, (f64, f64))> = Vec::new();
        let mut i = 0;
        while i < n {
            let Some(p) = t.pelvis(i) else {
                i += 1;
                continue;
            };
            // The prediction's uncertainty grows over frames without a pose, not over frames
            // whose pose is off the path (else a lasting offset would come back "on" it).
            let off = |j: usize, q: (f64, f64), path: &[(usize, (f64, f64))]| {
                predict(path, j, base).is_some_and(|(pred, last)| {
                    let unseen = (last + 1..j).filter(|&k| t.pelvis(k).is_none()).count();
                    let allowed = (self.tolerance + self.spread * (1 + unseen) as f64) * leg;
                    dist(q, pred) > allowed
                })
            };
            if !off(i, p, &path) {
                path.push((i, p));
                i += 1;
                continue;
            }
            // Off the path: a glitch if some frame within `max_run` is back on it.
            let back = (i + 1..(i + max_run + 1).min(n))
                .find(|&j| t.pelvis(j).is_some_and(|q| !off(j, q, &path)));
            match back {
                Some(j) => {
                    for flag in &mut out[i..j] {
                        *flag = true;
                    }
                    i = j;
                }
                None => {
                    // Someone else from here on, or the subject after a real jump: a new path.
                    path.clear();
                    path.push((i, p));
                    i += 1;
                }
            }
        }
        out
    }
}

/// Drops every keypoint of the frames [`GlitchRule::default`] finds, with a warning naming them.
pub(crate) fn drop_glitches(t: &mut Tracks, warnings: &mut Vec<String>) {
    let glitches = GlitchRule::default().find(t);
    let frames: Vec<usize> = (0..t.len()).filter(|&i| glitches[i]).collect();
    if frames.is_empty() {
        return;
    }
    for &i in &frames {
        for j in 0..t.names.len() {
            t.x[j][i] = f64::NAN;
            t.y[j][i] = f64::NAN;
        }
    }
    let at: Vec<String> = gait_core::ranges(frames.iter().map(|i| t.first_frame + i))
        .iter()
        .map(|[a, b]| {
            if a == b {
                a.to_string()
            } else {
                format!("{a}-{b}")
            }
        })
        .collect();
    warnings.push(format!(
        "pose dropped in {} frames ({}) where it left the subject's path for a moment (someone else drawn)",
        frames.len(),
        at.join(", ")
    ));
}

/// Where the path predicts the pelvis at frame `j` (constant velocity over the last `base`
/// frames of the path), and the last frame of the path; `None` on an empty path.
fn predict(path: &[(usize, (f64, f64))], j: usize, base: usize) -> Option<((f64, f64), usize)> {
    let &(last, p) = path.last()?;
    let earlier = path
        .iter()
        .rev()
        .find(|(k, _)| last - k >= base)
        .filter(|(k, _)| last - k <= 3 * base);
    let pred = match earlier {
        Some(&(k, q)) => {
            let s = (j - last) as f64 / (last - k) as f64;
            (p.0 + s * (p.0 - q.0), p.1 + s * (p.1 - q.1))
        }
        None => p,
    };
    Some((pred, last))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::walker;

    /// Walking right at 13 px a frame; for frames 50-52 the pose is drawn on someone 150 px
    /// behind: those frames are glitches. From frame 90 on it stays there: not a glitch.
    #[test]
    fn a_moment_on_someone_else_is_a_glitch_a_lasting_jump_is_not() {
        let mut t = walker(30.0, 120, |i| 100.0 + 13.0 * i as f64);
        for i in (50..53).chain(90..120) {
            for x in t.x.iter_mut() {
                x[i] -= 150.0;
            }
        }
        let g = GlitchRule::default().find(&t);
        let flagged: Vec<usize> = (0..120).filter(|&i| g[i]).collect();
        assert_eq!(flagged, vec![50, 51, 52]);
        let clean = walker(30.0, 120, |i| 100.0 + 13.0 * i as f64);
        assert!(GlitchRule::default().find(&clean).iter().all(|&f| !f));
    }
}
