//! The planted deviations of tests/visit.rs seen through a pose model's jitter: each view as a
//! 30 fps video with BlazePose's jitter as measured on the sample, one or more passes a view,
//! combined as `gait visit` combines its passes. The figures of every case are printed
//! (BENCHMARKS.md, "Visit and checklist").

mod common;
mod planted;

#[path = "../crates/gait-kin/tests/jitter/mod.rs"]
mod jitter;
#[path = "../crates/gait-kin/tests/rng/mod.rs"]
mod rng;
use jitter::Jitter;

use std::collections::BTreeSet;
use std::path::Path;

use planted::{REQUIRED, VIEWS, bilateral, item_of, planted, visit_at, visit_passes};

/// A case's four views as 30 fps videos (every 5th frame) with BlazePose's jitter as measured
/// on the sample (crates/gait-kin/tests/jitter).
fn noisy_copy(case: &Path, to: &Path, seed: u64) {
    noisy_copy_at(case, to, seed, Jitter::Measured)
}

/// [`noisy_copy`] with the jitter `model`.
fn noisy_copy_at(case: &Path, to: &Path, seed: u64, model: Jitter) {
    for view in VIEWS {
        let f = std::fs::File::open(case.join(view).join("keypoints.csv")).unwrap();
        let seq = gait_core::dlc::read(f, None, 150.0).unwrap();
        let out = jitter::as_video(&seq, seed, model);
        std::fs::create_dir_all(to.join(view)).unwrap();
        let w = std::fs::File::create(to.join(view).join("keypoints.csv")).unwrap();
        gait_core::dlc::write(w, "noisy", &out).unwrap();
    }
}

/// The larger planted deviations as 30 fps videos with pose-model jitter (3 seeds): each is found
/// on the right in every seed and nothing on the left; circumduction only where it is planted (it
/// was called in 3 of the other 57 visits before its chord ran from stance to stance over the
/// swing alone); what else the jitter adds on the right is printed (BENCHMARKS.md). The 10 %
/// shorter stance was found in 2 of 3 seeds until a side view's hips drifting apart for two
/// frames stopped being taken as a front view (direction.rs): that lost a heel strike, a stride
/// and half the healthy walk's stance figures in the third seed.
#[test]
fn planted_deviations_under_pose_model_noise() {
    let data = planted();
    let work = tempfile::tempdir().unwrap();
    for trial in ["fukuchi2018", "gaitkit_pd"] {
        let subject = common::read_json(&data.join(trial).join("subject.json"));
        let height = subject["leg_length_cm"].as_f64().unwrap() / 100.0 / 0.491;
        for case in std::iter::once("none").chain(REQUIRED) {
            let src = data.join(trial).join(case);
            if !src.is_dir() {
                continue;
            }
            let mut found = Vec::new();
            for seed in 1..=3u64 {
                let dir = work.path().join(format!("{trial}-{case}-{seed}"));
                noisy_copy(&src, &dir.join("kp"), seed);
                found.push(visit_at(&dir.join("kp"), height, &dir.join("runs"), 30.0));
            }
            println!("NOISE {trial} {case}: {found:?}");
            for (seed, f) in found.iter().enumerate() {
                let expected_left = bilateral(case).then(|| format!("{} (left)", item_of(case)));
                let left: Vec<&String> = (f.iter())
                    .filter(|x| x.ends_with("(left)"))
                    .filter(|x| expected_left.as_ref() != Some(*x))
                    .collect();
                assert!(
                    left.is_empty(),
                    "{trial} {case} seed {}: on the left {left:?}",
                    seed + 1
                );
                assert!(
                    case == "circumduction_10" || !f.contains("circumduction (right)"),
                    "{trial} {case} seed {}: circumduction called in {f:?}",
                    seed + 1
                );
                if case != "none" {
                    let item = format!("{} (right)", item_of(case));
                    assert!(
                        f.contains(&item),
                        "{trial} {case} seed {}: no {item} in {f:?}",
                        seed + 1
                    );
                }
            }
        }
    }
}

/// Items present in each seed's visit of `case` filmed in `passes` passes a view, each pass with
/// its own jitter (`model`): a clinic's short walkway gives a stride or two a side per pass.
fn noisy_visits(
    data: &Path,
    (trial, case): (&str, &str),
    (seeds, passes): (u64, u64),
    model: Jitter,
    work: &Path,
) -> Vec<BTreeSet<String>> {
    let subject = common::read_json(&data.join(trial).join("subject.json"));
    let height = subject["leg_length_cm"].as_f64().unwrap() / 100.0 / 0.491;
    (1..=seeds)
        .map(|seed| {
            let dir = work.join(format!("{trial}-{case}-{seed}"));
            let mut list = Vec::new();
            for k in 0..passes {
                let kp = dir.join(format!("kp{k}"));
                noisy_copy_at(&data.join(trial).join(case), &kp, 100 * seed + k, model);
                list.extend(VIEWS.map(|v| (v, kp.join(v).join("keypoints.csv"))));
            }
            visit_passes(&list, height, &dir.join("runs"), 30.0)
        })
        .collect()
}

/// At the feet's own measured jitter (twice the hips', [`Jitter::MeasuredLimbs`]) a verdict
/// resting on one stride is not reliable: the unmodified healthy walk filmed once a view (one
/// stride a side from behind) read a whip in 3 of these 10 seeds. Filmed twice a view, the
/// visit pools each item's strides over the passes that see it alike and judges them together:
/// nothing is found in any seed. `GAIT_TEST_PASSES` and `GAIT_TEST_CASES` (comma-separated)
/// print other figures without asserting them (BENCHMARKS.md, "Passes of one view pooled").
#[test]
fn two_passes_a_view_find_nothing_in_an_unmodified_walk() {
    let data = planted();
    let work = tempfile::tempdir().unwrap();
    let passes: u64 = std::env::var("GAIT_TEST_PASSES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2);
    let cases = std::env::var("GAIT_TEST_CASES").unwrap_or_else(|_| "none".into());
    let figures_only = passes != 2 || cases != "none";
    for trial in ["fukuchi2018", "gaitkit_pd"] {
        for case in cases.split(',') {
            let found = noisy_visits(
                &data,
                (trial, case),
                (10, passes),
                Jitter::MeasuredLimbs,
                work.path(),
            );
            println!("POOLED {trial} {case} ({passes} passes): {found:?}");
            // The Parkinson's walker's own longer right step (planted_deviations_are_found_...).
            let real = (trial == "gaitkit_pd").then(|| "uneven_step_length (right)".to_string());
            for (seed, f) in found.iter().enumerate() {
                let false_ones: Vec<&String> =
                    f.iter().filter(|x| Some(*x) != real.as_ref()).collect();
                assert!(
                    figures_only || false_ones.is_empty(),
                    "{trial} seed {}: {false_ones:?}",
                    seed + 1
                );
            }
        }
    }
}
