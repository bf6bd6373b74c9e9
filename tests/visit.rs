//! A patient's visit and the gait-deviation checklist (issue 39) on deviations of known size
//! planted in real motion capture: tools/visit/plant.py plants each deviation on the right side
//! of the Fukuchi 2018 and gaitkit Parkinson's trials in 3-D and projects them to the left,
//! right, front and back views; each view runs through `gait kin`, the four runs are combined
//! as `gait visit` combines its passes, and the visit's checklist must report the deviation on
//! the right, nothing new on the left, and nothing in the unmodified trials but what the
//! subject really has. The figures of every case are printed (BENCHMARKS.md).

mod common;

#[path = "../crates/gait-kin/tests/jitter/mod.rs"]
mod jitter;
#[path = "../crates/gait-kin/tests/rng/mod.rs"]
mod rng;
use jitter::Jitter;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use common::{gait, run_ok};

const VIEWS: [&str; 4] = ["left", "right", "anterior", "posterior"];

/// The planted data, made once per target folder (a few seconds; the gaitkit sdist is fetched
/// by pip into target/ the first time), and again when it lacks a required case (made by an
/// older plant.py: a missing case would otherwise be skipped silently).
fn planted() -> PathBuf {
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
fn visit(case: &Path, height_m: f64, work: &Path) -> BTreeSet<String> {
    visit_at(case, height_m, work, 150.0)
}

/// [`visit`] of keypoints at `fps`.
fn visit_at(case: &Path, height_m: f64, work: &Path, fps: f64) -> BTreeSet<String> {
    visit_of(case, &VIEWS, height_m, work, fps)
}

/// The visit of the `views` of one case (`case/VIEW/keypoints.csv`) at `fps`.
fn visit_of(case: &Path, views: &[&str], height_m: f64, work: &Path, fps: f64) -> BTreeSet<String> {
    let passes: Vec<(&str, PathBuf)> = (views.iter())
        .map(|&v| (v, case.join(v).join("keypoints.csv")))
        .collect();
    visit_passes(&passes, height_m, work, fps)
}

/// The visit of `passes` (view, keypoints.csv; a view may come more than once) at `fps`.
fn visit_passes(
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
fn item_of(case: &str) -> &'static str {
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
fn bilateral(case: &str) -> bool {
    case.starts_with("trunk_flexion")
}

/// The larger size of each deviation (the stance's and the trunk flexion's only size), which
/// must be found. Terminal swing impact is planted and printed but not required: the healthy
/// walk's knee thrown 4 times as fast into extension reads 1.9, under the 2.0 (BENCHMARKS.md).
const REQUIRED: [&str; 10] = [
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

#[test]
fn planted_deviations_are_found_on_their_side_only() {
    let data = planted();
    let work = tempfile::tempdir().unwrap();
    let mut failures = Vec::new();
    for trial in ["fukuchi2018", "gaitkit_pd"] {
        let subject = common::read_json(&data.join(trial).join("subject.json"));
        let height = subject["leg_length_cm"].as_f64().unwrap() / 100.0 / 0.491;
        let cases = common::read_json(&data.join(trial).join("cases.json"));
        let baseline = visit(
            &data.join(trial).join("none"),
            height,
            &work.path().join(trial).join("none"),
        );
        println!("{trial} none: present {baseline:?}");
        // The Parkinson's walker's right steps are 27-32 % longer than the left in both side
        // views of the unmodified trial: a real asymmetry, which the checklist reports.
        let real: BTreeSet<String> = match trial {
            "gaitkit_pd" => ["uneven_step_length (right)".to_string()].into(),
            _ => BTreeSet::new(),
        };
        if baseline != real {
            failures.push(format!(
                "{trial} unmodified: {baseline:?}, expected {real:?}"
            ));
        }
        for case in cases["written"]
            .as_array()
            .unwrap()
            .iter()
            .filter_map(|c| c.as_str())
        {
            if case == "none" {
                continue;
            }
            let found = visit(
                &data.join(trial).join(case),
                height,
                &work.path().join(trial).join(case),
            );
            let item = item_of(case);
            let on_right = found.contains(&format!("{item} (right)"));
            let both = !bilateral(case) || found.contains(&format!("{item} (left)"));
            let expected_left = format!("{item} (left)");
            let new_left: Vec<&String> = found
                .iter()
                .filter(|f| f.ends_with("(left)") && !baseline.contains(*f))
                .filter(|f| !bilateral(case) || **f != expected_left)
                .collect();
            println!(
                "{trial} {case}: {item} on the right {on_right}; new on the left {new_left:?}; all {found:?}"
            );
            if !new_left.is_empty() {
                failures.push(format!("{trial} {case}: on the left {new_left:?}"));
            }
            if REQUIRED.contains(&case) && !(on_right && both) {
                failures.push(format!(
                    "{trial} {case}: {item} not found on the right ({found:?})"
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// `(side, curve) -> means` of the sagittal rows of a visit_cycles.csv or a run's cycles.csv.
fn curves(
    path: &Path,
    side_col: usize,
    name_col: usize,
    mean_col: usize,
) -> std::collections::BTreeMap<(String, String), Vec<f64>> {
    let mut out: std::collections::BTreeMap<(String, String), Vec<f64>> = Default::default();
    let mut r = csv::Reader::from_path(path).unwrap();
    for rec in r.records() {
        let rec = rec.unwrap();
        if rec.len() > 6 && &rec[0] != "sagittal" {
            continue;
        }
        out.entry((rec[side_col].to_string(), rec[name_col].to_string()))
            .or_default()
            .push(rec[mean_col].parse().unwrap_or(f64::NAN));
    }
    out
}

/// `gait visit` on the bundled sample (a left view: the walker's left side faces the camera)
/// and its mirror image (as a right view): each side's curves come from the view where that
/// limb is near the camera, equal to that pass's own curves; the visit report names them.
#[test]
fn a_visit_of_the_sample_and_its_mirror_takes_each_side_from_its_near_view() {
    let work = tempfile::tempdir().unwrap();
    let mirrored = work.path().join("mirrored.mp4");
    let video = common::sample_video();
    let status = std::process::Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-i"])
        .arg(&video)
        .args(["-vf", "hflip", "-c:v", "libx264", "-crf", "12"])
        .arg(&mirrored)
        .status()
        .expect("ffmpeg runs");
    assert!(status.success());
    let out = work.path().join("visit");
    let o = run_ok(
        gait()
            .args(["visit", "--no-progress", "--left"])
            .arg(&video)
            .arg("--right")
            .arg(&mirrored)
            .arg("--out")
            .arg(&out)
            .args(["--set", "report.pdf=false", "--set", "report.overlay=false"]),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("visit of 2 pass(es) combined in"), "{err}");
    let visit = curves(&out.join("visit_cycles.csv"), 1, 2, 4);
    for (side, pass) in [("left", "1-left"), ("right", "2-right")] {
        let own = curves(&out.join("passes").join(pass).join("cycles.csv"), 0, 1, 3);
        for joint in ["hip", "knee", "ankle"] {
            let key = (side.to_string(), joint.to_string());
            let (a, b) = (&visit[&key], &own[&key]);
            let d = a
                .iter()
                .zip(b)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
            assert!(
                d < 1e-3,
                "{side} {joint}: visit differs from its pass by {d}"
            );
        }
    }
    // The mirror's right limb is the original's left limb seen from the other side: how close
    // they come is printed (re-encoding alone moves events, BENCHMARKS.md "Robustness").
    let original = curves(&out.join("passes/1-left/cycles.csv"), 0, 1, 3);
    let mirror = curves(&out.join("passes/2-right/cycles.csv"), 0, 1, 3);
    for joint in ["hip", "knee", "ankle"] {
        let (a, b) = (
            &original[&("left".into(), joint.into())],
            &mirror[&("right".into(), joint.into())],
        );
        let rms =
            (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64).sqrt();
        println!("{joint}: original left vs mirrored right, RMS {rms:.2} deg");
    }
    // Vaulting weighs one heel against the other, and each view sees one heel near and one far
    // (the left view alone reads +3 % of the leg on the right): the visit pools both views'
    // cycles, so each side's value rests on both.
    let vaulting = |file: &Path, side: &str| {
        let mut r = csv::Reader::from_path(file).unwrap();
        let h = r.headers().unwrap().clone();
        let at = |name: &str| h.iter().position(|c| c == name).unwrap();
        let (item, s, n) = (at("item"), at("side"), at("n"));
        let row = r.records().map(Result::unwrap);
        let row = row
            .into_iter()
            .find(|x| &x[item] == "vaulting" && &x[s] == side);
        let row = row.expect("a vaulting row per side");
        let from = h
            .iter()
            .position(|c| c == "pass")
            .map(|p| row[p].to_string());
        (row[n].parse::<usize>().unwrap(), from)
    };
    for side in ["left", "right"] {
        let (pooled, from) = vaulting(&out.join("visit_checklist.csv"), side);
        let from = from.unwrap_or_default();
        assert!(
            from.ends_with("both sides, cycles pooled"),
            "{side}: {from}"
        );
        let passes = out.join("passes");
        let each = |p: &str| vaulting(&passes.join(p).join("checklist.csv"), side).0;
        assert_eq!(pooled, each("1-left") + each("2-right"), "{side}");
    }
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(
        html.contains("left sagittal curves: left view (sports2d-demo.mp4) (near the camera)"),
        "report names the sources"
    );
    assert!(html.contains("right sagittal curves: right view (mirrored.mp4) (near the camera)"));
    assert!(html.contains("Amputee gait-deviation checklist"));
    // Each pass says how large and sharp the legs were: the sample and its mirror alike.
    assert_eq!(
        html.matches("In the image: the legs ").count(),
        2,
        "each pass's image line"
    );
}

/// Progress across visits: the Parkinson's walk unmodified, then with the right hip hiking 10
/// deg in swing. `gait progress` calls the change on hip hiking of the right side and nothing
/// on the left.
#[test]
fn progress_calls_the_planted_change_and_nothing_on_the_other_side() {
    let calls = progress_calls("hip_hike_10");
    assert!(
        calls.iter().any(|c| c.0 == "hip_hiking" && c.1 == "right"),
        "{calls:?}"
    );
    assert!(
        calls.iter().all(|c| c.1 == "right"),
        "a change on the left: {calls:?}"
    );
}

/// A side-view item's change passes its video floor (the knee's MDC95 of re-encoding and
/// keypoint noise, 4.7 deg): the right knee 15 deg more flexed in stance is called, on the right
/// only.
#[test]
fn progress_calls_a_side_view_change_over_its_video_floor() {
    let calls = progress_calls("knee_flexed_15");
    assert!(
        calls
            .iter()
            .any(|c| c.0 == "excessive_knee_flexion_stance" && c.1 == "right"),
        "{calls:?}"
    );
    assert!(
        calls.iter().all(|c| c.1 == "right"),
        "a change on the left: {calls:?}"
    );
}

/// `gait progress` between the Parkinson's walk unmodified and with `case` planted: the calls
/// of change as (item, side, difference).
fn progress_calls(case: &str) -> Vec<(String, String, String)> {
    let data = planted();
    let work = tempfile::tempdir().unwrap();
    let subject = common::read_json(&data.join("gaitkit_pd/subject.json"));
    let height = subject["leg_length_cm"].as_f64().unwrap() / 100.0 / 0.491;
    let before = work.path().join("none");
    let after = work.path().join(case);
    visit(&data.join("gaitkit_pd/none"), height, &before);
    visit(&data.join("gaitkit_pd").join(case), height, &after);
    let out = work.path().join("progress");
    let o = run_ok(
        gait()
            .arg("progress")
            .arg(before.join("visit"))
            .arg(after.join("visit"))
            .arg("--out")
            .arg(&out),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    let mut r = csv::Reader::from_path(out.join("progress.csv")).unwrap();
    let calls: Vec<(String, String, String)> = r
        .records()
        .map(|x| x.unwrap())
        .filter(|x| &x[7] == "change")
        .map(|x| (x[0].to_string(), x[1].to_string(), x[4].to_string()))
        .collect();
    println!("{err}\n{calls:?}");
    let html = std::fs::read_to_string(out.join("progress.html")).unwrap();
    for part in [
        "Progress across visits",
        "Gait Profile Score",
        "GPS, right (deg)",
        "Symmetry indices",
        "Mean curves, visit by visit",
    ] {
        assert!(html.contains(part), "progress.html lacks {part}");
    }
    calls
}

/// Two visits made of the two halves of one long walk (the 12 s treadmill trial of
/// tests/data/gaitalytics_treadmill, 100 Hz, seen from the right: 5-6 cycles a side in each
/// half) are the same patient on the same day: progress must call no change on any item.
#[test]
fn progress_between_two_halves_of_one_walk_calls_no_change() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let src = root.join("tests/data/gaitalytics_treadmill/keypoints.csv");
    let seq = gait_core::dlc::read(std::fs::File::open(&src).unwrap(), None, 100.0).unwrap();
    let work = tempfile::tempdir().unwrap();
    let half = seq.poses.len() / 2;
    let mut visits = Vec::new();
    for (name, range) in [("first", 0..half), ("second", half..seq.poses.len())] {
        let mut part = seq.clone();
        part.poses = seq.poses[range.clone()].to_vec();
        part.frames = (0..part.poses.len()).collect();
        let case = work.path().join(name);
        std::fs::create_dir_all(case.join("right")).unwrap();
        let w = std::fs::File::create(case.join("right/keypoints.csv")).unwrap();
        gait_core::dlc::write(w, "half", &part).unwrap();
        let runs = work.path().join(format!("{name}-runs"));
        let found = visit_of(&case, &["right"], 1.75, &runs, 100.0);
        println!("{name} half: present {found:?}");
        visits.push(runs.join("visit"));
    }
    let out = work.path().join("progress");
    run_ok(gait().arg("progress").args(&visits).arg("--out").arg(&out));
    let mut r = csv::Reader::from_path(out.join("progress.csv")).unwrap();
    let rows: Vec<csv::StringRecord> = r.records().map(|x| x.unwrap()).collect();
    for x in &rows {
        println!("{}", x.iter().collect::<Vec<_>>().join(", "));
    }
    let judged = rows.iter().filter(|x| &x[7] == "no change").count();
    let changes: Vec<String> = rows
        .iter()
        .filter(|x| &x[7] == "change")
        .map(|x| format!("{} {} {}", &x[0], &x[1], &x[4]))
        .collect();
    assert!(
        changes.is_empty(),
        "changes between the halves: {changes:?}"
    );
    assert!(judged >= 6, "only {judged} items judged: {rows:?}");
}

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

/// The same walk brought to two visits: the bundled sample and its mirror as left and right
/// views, then the same two passes with sensor-like noise (as another camera or a phone's copy
/// would give). `gait progress` must call no change: before the checklist measures had video
/// floors it called five false changes over seven such copies (terminal impact ratios, a
/// vaulting moved by one misplaced stride of the other foot, a knee 2.4 deg, and step lengths in
/// pixels of a 720p copy).
#[test]
fn a_re_filmed_copy_of_the_same_walk_calls_no_change() {
    let work = tempfile::tempdir().unwrap();
    let w = work.path();
    let encode = |from: &Path, filter: &str, to: &Path| {
        let st = std::process::Command::new("ffmpeg")
            .args(["-loglevel", "error", "-y", "-i"])
            .arg(from)
            .args([
                "-vf", filter, "-c:v", "libx264", "-preset", "veryfast", "-crf", "18",
            ])
            .arg(to)
            .status()
            .expect("ffmpeg runs");
        assert!(st.success());
    };
    let sample = common::sample_video();
    encode(&sample, "hflip", &w.join("mirror.mp4"));
    encode(&sample, "noise=alls=10:allf=t", &w.join("noisy.mp4"));
    encode(&w.join("noisy.mp4"), "hflip", &w.join("noisy_mirror.mp4"));
    let visit = |name: &str, date: &str, left: &Path, right: &Path| {
        run_ok(
            gait()
                .args(["visit", "--no-progress", "--out"])
                .arg(w.join(name))
                .arg("--left")
                .arg(left)
                .arg("--right")
                .arg(right)
                .args(["--subject", "P", "--session", name, "--date", date])
                .args(["--set", "kinematics.prosthetic_side=\"left\""])
                .args(["--set", "report.overlay=false", "--set", "report.pdf=false"]),
        );
    };
    visit("first", "2026-11-06", &sample, &w.join("mirror.mp4"));
    visit(
        "second",
        "2026-12-06",
        &w.join("noisy.mp4"),
        &w.join("noisy_mirror.mp4"),
    );
    run_ok(
        gait()
            .arg("progress")
            .arg(w.join("first"))
            .arg(w.join("second"))
            .arg("--out")
            .arg(w.join("progress")),
    );
    let mut r = csv::Reader::from_path(w.join("progress/progress.csv")).unwrap();
    let calls: Vec<(String, String, String)> = r
        .records()
        .map(|x| x.unwrap())
        .map(|x| (x[0].to_string(), x[1].to_string(), x[7].to_string()))
        .collect();
    let changes: Vec<_> = calls.iter().filter(|c| c.2 == "change").collect();
    assert!(changes.is_empty(), "false changes: {changes:?}");
    let judged = calls.iter().filter(|c| c.2 == "no change").count();
    assert!(judged >= 10, "only {judged} items judged: {calls:?}");
}
