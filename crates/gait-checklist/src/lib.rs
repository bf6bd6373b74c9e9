//! The amputee gait-deviation checklist, quantified. The items are those of the published
//! observational checklists (Berger, "Analysis of amputee gait", Atlas of Limb Prosthetics,
//! 2nd ed. 1992; the Northwestern University Prosthetic-Orthotic Center's transfemoral and
//! transtibial lists): each is judged by a named measure against a threshold with its source
//! (a normative band ± `checklist.norm_sd` SD, or a documented default in `[checklist]`), per
//! side: present, absent, or not assessable with the reason (the view it needs, too few
//! cycles, the keypoints it needs). [`assess`] reads a run folder's files, so any
//! run's checklist can be made again from them; checklist.csv and the report's section are
//! written from its [`Checklist`].

mod camera;
mod config;
mod frontal_items;
mod html;
mod judge;
mod pool;
mod review_link;
mod run_files;
mod sagittal_items;
mod trunk_arms;
mod vaulting;
mod verdict;
mod whip;

use std::path::Path;

use gait_eval::normative::Normative;
use serde::Serialize;

pub use config::ChecklistConfig;
pub use gait_kin::Side;
pub use pool::{POOLED_OVER_VIEWS, pool_groups, pooled};
pub use review_link::{review_port, review_url};
pub use run_files::{Param, RunFiles};
pub use sagittal_items::pooled_timing;
pub use verdict::{Item, Status, Verdict};

#[derive(Debug, thiserror::Error)]
pub enum ChecklistError {
    #[error("invalid configuration: {0}")]
    Config(String),
    #[error("{0}")]
    Input(String),
}

/// A run's checklist.
#[derive(Debug, Clone, Serialize)]
pub struct Checklist {
    pub view: String,
    pub prosthetic: Option<Side>,
    /// `transtibial`, `transfemoral`, or unset: the items of both.
    pub amputation: Option<String>,
    pub verdicts: Vec<Verdict>,
}

/// The checklist of the run folder `dir`: `norm` is the report's sagittal normative set (its
/// speed stratum also picks the frontal bands).
pub fn assess(
    dir: &Path,
    cfg: &ChecklistConfig,
    norm: Option<&Normative>,
    prosthetic: Option<Side>,
    amputation: Option<&str>,
) -> Result<Checklist, ChecklistError> {
    cfg.validate()?;
    let run = RunFiles::read(dir)?;
    let frontal_norm = norm.and_then(|n| gait_eval::normative_frontal::for_sagittal(Some(&n.name)));
    let mut verdicts = Vec::new();
    for side in Side::BOTH {
        verdicts.extend(frontal_items::assess(
            &run,
            side,
            cfg,
            frontal_norm.as_ref(),
        ));
    }
    verdicts.extend(sagittal_items::assess(&run, cfg, norm));
    verdicts.extend(vaulting::assess(&run, cfg));
    verdicts.extend(trunk_arms::assess(&run, cfg));
    verdicts.extend(whip::assess(&run, cfg));
    camera::gate(&mut verdicts, &run);
    let here = dir.display().to_string();
    for v in &mut verdicts {
        v.run.clone_from(&here);
    }
    Ok(Checklist {
        view: run.view,
        prosthetic,
        amputation: amputation.map(String::from),
        verdicts,
    })
}

impl Checklist {
    /// checklist.csv.
    pub fn csv(&self) -> String {
        verdict::csv(&self.verdicts)
    }

    /// The items found present, as `item (side)`.
    pub fn present(&self) -> Vec<String> {
        self.verdicts
            .iter()
            .filter(|v| v.status == Status::Present)
            .map(|v| format!("{} ({})", v.item.id, v.side.name()))
            .collect()
    }
}
