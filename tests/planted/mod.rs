//! The planted deviations of tools/visit/plant.py and the visits made of them, shared by
//! tests/visit.rs and tests/visit_noise.rs (both declare `mod common` beside it).
#![allow(dead_code)]

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use crate::common::{self, gait, run_ok};

pub const VIEWS: [&str; 4] = ["left", "right", "anterior", "posterior"];

/// The planted data, made once per target folder (a few seconds; the gaitkit sdist is fetched
/// by pip into target/ the first time), and again when it lacks a required case (made by an
/// older plant.py: a missing case would otherwise be skipped silently).
pub fn planted() -> PathBuf {
    static MADE: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    MADE.get_or_init(|| {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let out = root.join("target/planted");
        let cases = out.join("gaitkit_pd/cases.json");
        let complete = cases.is_file() && {
            let c = common::read_json(&cases);
            REQUIRED.iter().all(|case| {
                c["written"]
                    .as_array()
                    .is_some_and(|w| w.iter().any(|x| x == case))
                    || c["skipped"].get(case).is_some()
            })
        };
        if !complete {
            let status = std::process::Command::new("python3")
                .arg(root.join("tools/visit/plant.py"))
                .arg("--out")
                .arg(&out)
                .status()
                .expect("python3 runs");
            assert!(status.success(), "tools/visit/plant.py failed");
        }
        out
    })
    .clone()
}

/// The visit of one case: its four views through `gait kin`, combined; the checklist items
/// present, as `item (side)`.
pub fn visit(case: &Path, height_m: f64, work: &Path) -> BTreeSet<String> {
    visit_at(case, height_m, work, 150.0)
}

/// [`visit`] of keypoints at `fps`.
pub fn visit_at(case: &Path, height_m: f64, work: &Path, fps: f64) -> BTreeSet<String> {
    visit_of(case, &VIEWS, height_m, work, fps)
}

/// The visit of the `views` of one case (`case/VIEW/keypoints.csv`) at `fps`.
pub fn visit_of(
    case: &Path,
    views: &[&str],
    height_m: f64,
    work: &Path,
    fps: f64,
) -> BTreeSet<String> {
    let passes: Vec<(&str, PathBuf)> = (views.iter())
        .map(|&v| (v, case.join(v).join("keypoints.csv")))
        .collect();
    visit_passes(&passes, height_m, work, fps)
}

/// The visit of `passes` (view, keypoints.csv; a view may come more than once) at `fps`.
pub fn visit_passes(
    passes_in: &[(&str, PathBuf)],
    height_m: f64,
    work: &Path,
    fps: f64,
) -> BTreeSet<String> {
    let mut passes = Vec::new();
    for (k, (view, keypoints)) in passes_in.iter().enumerate() {
        let (view, keypoints) = (*view, keypoints.as_path());
        let dir = work.join(format!("{k}-{view}"));
        run_ok(
            gait()
                .args(["kin", "--fps", &fps.to_string(), "--keypoints"])
                .arg(keypoints)
                .arg("--out")
                .arg(&dir)
                .args(["--set", &format!("kinematics.subject_height_m={height_m}")])
                .args(["--set", "kinematics.prosthetic_side=\"right\""])
                .args(["--set", &format!("kinematics.view=\"{view}\"")])
                .args(["--set", "report.pdf=false"]),
        );
        passes.push(gait_visit::Pass::read(view, keypoints, &dir).expect("pass"));
    }
    let cfg = gait_checklist::ChecklistConfig::default();
    let o = gait_visit::VisitOptions {
        checklist: &cfg,
        normative: Some(gait_eval::Normative::load("schwartz2008_free").unwrap()),
        prosthetic: Some(gait_checklist::Side::Right),
        amputation: None,
        label: gait_visit::VisitLabel {
            subject: "S".into(),
            // The case's folder (`case/VIEW/keypoints.csv`).
            session: (passes_in[0].1.parent().and_then(Path::parent))
                .and_then(Path::file_name)
                .unwrap()
                .to_string_lossy()
                .into_owned(),
            date: String::new(),
            prosthetic: None,
        },
        notes: Vec::new(),
    };
    let summary = gait_visit::write(&work.join("visit"), &passes, &o).expect("visit");
    assert!(
        work.join("visit/report.html").is_file()
            && work.join("visit/visit_checklist.csv").is_file()
    );
    summary.present.into_iter().collect()
}

/// The item a planted deviation should show as.
pub fn item_of(case: &str) -> &'static str {
    match case.rsplit_once('_').map_or(case, |(d, _)| d) {
        "trunk_lean" => "lateral_trunk_bending",
        "wide_base" => "abducted_gait",
        "circumduction" => "circumduction",
        "hip_hike" => "hip_hiking",
        "knee_flexed" => "excessive_knee_flexion_stance",
        "short_stance" => "uneven_stance_time",
        "vaulting" => "vaulting",
        "trunk_flexion" => "excessive_trunk_flexion",
        "foot_slap" => "foot_slap",
        "medial_whip" => "medial_lateral_whip",
        "terminal_impact" => "terminal_swing_impact",
        other => panic!("unknown case {other}"),
    }
}

/// Planted on both sides (the trunk bent forward all the time): found on both, nothing else new.
pub fn bilateral(case: &str) -> bool {
    case.starts_with("trunk_flexion")
}

/// The larger size of each deviation (the stance's and the trunk flexion's only size), which
/// must be found. Terminal swing impact is planted and printed but not required: the healthy
/// walk's knee thrown 4 times as fast into extension reads 1.9, under the 2.0 (BENCHMARKS.md).
pub const REQUIRED: [&str; 10] = [
    "trunk_flexion_15",
    "foot_slap_30",
    "medial_whip_8",
    "trunk_lean_10",
    "wide_base_10",
    "circumduction_10",
    "hip_hike_10",
    "knee_flexed_15",
    "vaulting_6",
    "short_stance_10",
];
