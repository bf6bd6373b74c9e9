//! Recomputing the kinematics for a set of corrections, and what the page gets of them.

use std::collections::BTreeMap;
use std::time::Instant;

use gait_checklist::Verdict;
use gait_core::keypoint::LOWER_LIMB;
use gait_kin::{Bout, Corrections, CycleQuality, Event, KinResult, Param, SideCounts};
use serde::Serialize;

use crate::source::ReviewSource;

/// The kinematics of the keypoints with one set of corrections, as the page draws them.
#[derive(Debug, Clone, Serialize)]
pub struct AnalysisView {
    /// Input frame number of the first sample of every series.
    pub first_frame: usize,
    pub n_frames: usize,
    /// `left_hip` ... `right_ankle`, degrees, null where undefined; a front or back view's
    /// `left_trunk_lean` ... `right_knee_varus` instead.
    pub angles: BTreeMap<String, Vec<f64>>,
    /// `sagittal`, `anterior` or `posterior`: which plots the page shows.
    pub view: &'static str,
    /// Lower-limb keypoints after cleaning (keypoints_filtered.csv): name -> [x series, y series].
    pub filtered: BTreeMap<String, [Vec<f64>; 2]>,
    pub events: Vec<Event>,
    pub bouts: Vec<Bout>,
    /// Every stride found, accepted or rejected with its reasons.
    pub cycles: Vec<CycleQuality>,
    pub accepted: SideCounts,
    pub rejected: SideCounts,
    pub spatiotemporal: Vec<Param>,
    pub warnings: Vec<String>,
    /// The gait-deviation checklist of this result (as the run's checklist.csv would be).
    pub checklist: Vec<Verdict>,
    /// The corrections applied, as saved.
    pub corrections: Corrections,
    /// Seconds the recomputation took on the server.
    pub seconds: f64,
}

impl AnalysisView {
    fn new(r: KinResult, checklist: Vec<Verdict>, corrections: &Corrections, seconds: f64) -> Self {
        let mut angles = BTreeMap::new();
        for (side, leg) in [("left", &r.angles.left), ("right", &r.angles.right)] {
            for (joint, v) in [
                ("hip", &leg.hip),
                ("knee", &leg.knee),
                ("ankle", &leg.ankle),
            ] {
                angles.insert(format!("{side}_{joint}"), v.clone());
            }
        }
        if let Some(fr) = &r.frontal {
            angles.clear();
            for side in gait_kin::Side::BOTH {
                for (m, v) in gait_kin::frontal::MEASURES.iter().zip(fr.angles.side(side)) {
                    angles.insert(format!("{}_{m}", side.name()), v.clone());
                }
            }
        }
        let f = &r.filtered;
        let filtered = LOWER_LIMB
            .iter()
            .filter_map(|name| {
                let j = f.index_of(name)?;
                let xs = f.poses.iter().map(|p| p.keypoints[j].x).collect();
                let ys = f.poses.iter().map(|p| p.keypoints[j].y).collect();
                Some((name.to_string(), [xs, ys]))
            })
            .collect();
        AnalysisView {
            first_frame: r.first_frame,
            n_frames: r.n_frames,
            angles,
            view: gait_kin::frontal::view_name(r.view.view),
            filtered,
            events: r.events,
            bouts: r.bouts,
            cycles: r.cycle_quality,
            accepted: r.cycles_accepted,
            rejected: r.cycles_rejected,
            spatiotemporal: r.spatiotemporal,
            warnings: r.warnings,
            checklist,
            corrections: corrections.clone(),
            seconds,
        }
    }
}

/// The bytes saved as corrections.toml for `c`.
pub fn toml_bytes(c: &Corrections) -> Vec<u8> {
    c.to_toml().into_bytes()
}

/// The kinematics of `src` with `c`, exactly as `gait kin --corrections` computes them from
/// the file holding [`toml_bytes`] of `c`.
pub fn recompute(src: &ReviewSource, c: &Corrections) -> Result<AnalysisView, gait_kin::KinError> {
    let t = Instant::now();
    let sha = gait_kin::corrections::sha256_hex(&toml_bytes(c));
    let mut r =
        gait_kin::analyse_corrected(&src.seq, &src.post, &src.kin, c, &src.corrections_path, sha)?;
    let list = crate::checklist::judge(&r, &src.checklist).unwrap_or_else(|why| {
        r.warnings.push(why);
        Vec::new()
    });
    Ok(AnalysisView::new(r, list, c, t.elapsed().as_secs_f64()))
}
