//! One pass of a visit: a video of one view, analysed into its own run folder.

use std::path::{Path, PathBuf};

use gait_checklist::Side;
use gait_eval::plot::{CycleCurve, read_curves_csv, read_cycles_csv};
use gait_report::spatiotemporal::{StParam, read_spatiotemporal};

use crate::VisitError;

/// `left`, `right` (side views), `anterior`, `posterior` (front and back views).
pub const VIEWS: [&str; 4] = ["left", "right", "anterior", "posterior"];

/// A pass and what its run folder holds.
#[derive(Debug, Clone)]
pub struct Pass {
    pub view: String,
    pub video: PathBuf,
    /// The pass's run folder (as `gait run` writes it).
    pub dir: PathBuf,
    /// cycles.csv: the sagittal mean curves.
    pub sagittal: Vec<CycleCurve>,
    /// frontal_cycles.csv: the frontal mean curves.
    pub frontal: Vec<CycleCurve>,
    pub spatiotemporal: Vec<StParam>,
    /// run.json's `status` and `reason` (a run with nothing to measure).
    pub status: String,
    /// run.json's frame rate.
    pub fps: Option<f64>,
    /// run.json's warnings (a resampled frame rate, an HDR conversion, bridged keypoints).
    pub warnings: Vec<String>,
    /// The sides with an accepted cycle near the camera (a side view's walk toward the image's
    /// left shows the left side; a walk there and back shows both).
    pub near: Vec<String>,
    /// How large and how sharp the legs were in the pass's image (the run report's "Image"
    /// line), when it has strides.
    pub image: Option<String>,
}

impl Pass {
    /// Reads the run folder of a pass.
    pub fn read(view: &str, video: &Path, dir: &Path) -> Result<Self, VisitError> {
        let io = |e: gait_eval::EvalError| VisitError::Pass {
            dir: dir.to_path_buf(),
            message: e.to_string(),
        };
        let file = |name: &str| Some(dir.join(name)).filter(|p| p.exists());
        let sagittal = file("cycles.csv")
            .map(|p| read_cycles_csv(&p))
            .transpose()
            .map_err(io)?;
        let frontal = file("frontal_cycles.csv")
            .map(|p| read_curves_csv(&p, "measure"))
            .transpose()
            .map_err(io)?;
        let spatiotemporal = file("spatiotemporal.csv")
            .map(|p| read_spatiotemporal(&p))
            .transpose()
            .map_err(io)?;
        let manifest = file("run.json")
            .and_then(|p| std::fs::read_to_string(p).ok())
            .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
            .unwrap_or_default();
        let status = manifest["status"].as_str().unwrap_or("done").to_string();
        let status = match manifest["reason"].as_str() {
            Some(r) => format!("{status}: {r}"),
            None => status,
        };
        let warnings = manifest["warnings"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|w| w.as_str().map(str::to_string))
            .collect();
        Ok(Self {
            view: view.into(),
            video: video.to_path_buf(),
            dir: dir.to_path_buf(),
            sagittal: sagittal.unwrap_or_default(),
            frontal: frontal.unwrap_or_default(),
            spatiotemporal: spatiotemporal.unwrap_or_default(),
            status,
            fps: manifest["input"]["fps"].as_f64(),
            image: gait_report::subject_lines::legs_in_image(&manifest),
            warnings,
            near: near_sides(dir),
        })
    }

    pub fn is_frontal(&self) -> bool {
        self.view == "anterior" || self.view == "posterior"
    }

    /// Whether `side`'s curves in this pass come from cycles near the camera: by the walk's
    /// direction in its bouts where the run says, else by the view it was given as.
    pub fn near_camera(&self, side: &str) -> bool {
        if self.near.is_empty() {
            self.view == side
        } else {
            self.near.iter().any(|s| s == side)
        }
    }

    /// A short name: `left view (L.mp4)`.
    pub fn label(&self) -> String {
        let name = self
            .video
            .file_name()
            .map_or(String::new(), |n| n.to_string_lossy().into_owned());
        format!("{} view ({name})", self.view)
    }

    /// A pass of `view` from `video` with these sagittal curves and nothing else, for tests.
    #[cfg(test)]
    pub(crate) fn with_curves(view: &str, video: &str, sagittal: Vec<CycleCurve>) -> Self {
        Self {
            view: view.into(),
            video: PathBuf::from(video),
            dir: PathBuf::new(),
            sagittal,
            frontal: Vec::new(),
            spatiotemporal: Vec::new(),
            status: "done".into(),
            fps: Some(30.0),
            warnings: Vec::new(),
            near: Vec::new(),
            image: None,
        }
    }

    /// Accepted cycles of a side in this pass (the curves' largest n).
    pub fn cycles(&self, side: &str, frontal: bool) -> usize {
        let curves = if frontal {
            &self.frontal
        } else {
            &self.sagittal
        };
        curves
            .iter()
            .filter(|c| c.side.as_str() == side)
            .map(|c| c.n_cycles)
            .max()
            .unwrap_or(0)
    }
}

/// The sides with an accepted cycle in a bout walked toward that side of the image (the side
/// facing the camera), read as the checklist reads the folder; empty where the folder says
/// nothing of it (a front or back view's bouts go toward or away from the camera).
fn near_sides(dir: &Path) -> Vec<String> {
    let Ok(run) = gait_checklist::RunFiles::read(dir) else {
        return Vec::new();
    };
    Side::BOTH
        .into_iter()
        .filter(|&side| {
            let toward = if side == Side::Right { 1.0 } else { -1.0 };
            run.strides_of(side)
                .any(|s| run.direction(s.first) == Some(toward))
        })
        .map(|side| side.name().to_string())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A side view walked there and back shows both sides near the camera, each in the bout
    /// walked toward its side of the image; a rejected cycle counts for nothing.
    #[test]
    fn the_near_sides_are_read_from_the_bouts_directions() {
        let dir = tempfile::tempdir().unwrap();
        let write = |name: &str, text: &str| std::fs::write(dir.path().join(name), text).unwrap();
        write(
            "bouts.csv",
            "bout,first,last,direction,mean_speed\n0,53,185,left,1.6\n1,283,415,right,1.6\n",
        );
        write(
            "cycle_quality.csv",
            "side,first_frame,last_frame,accepted,reasons,bout\nleft,79,117,true,,0\nright,61,98,false,far_side,0\nright,309,347,true,,1\n",
        );
        assert_eq!(near_sides(dir.path()), ["left", "right"]);
        write(
            "cycle_quality.csv",
            "side,first_frame,last_frame,accepted,reasons,bout\nleft,79,117,true,,0\nright,61,98,true,,0\n",
        );
        assert_eq!(near_sides(dir.path()), ["left"]);
        std::fs::remove_file(dir.path().join("bouts.csv")).unwrap();
        assert!(near_sides(dir.path()).is_empty());
    }
}
