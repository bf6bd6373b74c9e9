//! The CPU-cost settings of issue 30 end to end on the bundled video, with the
//! tiny random SD 1.5 + ControlNet (the images are noise; the wiring is real):
//! crops around the subject, DeepCache, token merging and the start from the
//! previous frame's latent, killed mid-run and resumed byte-identical.

mod common;

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

use common::{read_json, run_ok};

/// The preset's savings at the tiny models' scale (64x128 crops, 4 steps).
fn cpu_sets() -> Vec<String> {
    let mut sets = common::tiny_controlnet_sets();
    sets.extend(
        [
            "regenerator.steps=4",
            "regenerator.scheduler=\"dpmpp2m\"",
            "regenerator.region=\"subject\"",
            "regenerator.crop_size=[64, 128]",
            "edge.resolution=0",
            "regenerator.cache_interval=2",
            "regenerator.token_merge_ratio=0.5",
            "regenerator.init=\"previous\"",
            "regenerator.strength=0.5",
            "run.batch_size=1",
        ]
        .map(String::from),
    );
    sets
}

/// The run on frames 100-139 with `cpu_sets`, less the keys `drop` names,
/// plus `extra`.
fn run_args(out: &Path, drop: &[&str], extra: &[&str]) -> std::process::Command {
    let mut cmd = common::sample_run(out, 100, 139);
    let sets = cpu_sets();
    let kept = sets
        .iter()
        .map(String::as_str)
        .filter(|s| !drop.iter().any(|d| s.starts_with(&format!("{d}="))));
    for s in kept.chain(extra.iter().copied()) {
        cmd.args(["--set", s]);
    }
    cmd
}

/// Files of the regenerator cache with extension `ext`.
fn regenerator_files(out: &Path, ext: &str) -> usize {
    std::fs::read_dir(out.join("cache"))
        .into_iter()
        .flatten()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with("regenerator-"))
        .flat_map(|e| std::fs::read_dir(e.path()).into_iter().flatten().flatten())
        .filter(|e| e.path().extension().is_some_and(|x| x == ext))
        .count()
}

#[test]
fn subject_crops_and_previous_latents_resume_byte_identical() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let mut child = run_args(&out, &[], &[])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(600);
    while regenerator_files(&out, "png") < 4 {
        assert!(Instant::now() < deadline, "no progress");
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before it could be interrupted"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let before = regenerator_files(&out, "png");
    assert!(before < 40, "the run finished before it was killed");
    // Each regenerated frame has the latent the next one starts from beside it.
    assert!(regenerator_files(&out, "state") >= before);

    run_ok(&mut run_args(&out, &[], &[]));
    let manifest = read_json(&out.join("run.json"));
    // Frames done before the kill are not redrawn again.
    let regen = &manifest["stages"]["regenerator"];
    let computed = regen["computed"].as_u64().unwrap() as usize;
    assert!(computed + before <= 40, "{regen}");

    // The regenerated frames (cached) equal those of an uninterrupted run.
    let clean = dir.path().join("clean");
    run_ok(&mut run_args(&clean, &[], &[]));
    let read = |p: &Path| std::fs::read_to_string(p.join("keypoints.csv")).unwrap();
    assert_eq!(read(&out), read(&clean));
    let (resumed, uninterrupted) = (regenerated(&out), regenerated(&clean));
    assert_eq!(resumed.len(), uninterrupted.len());
    assert!(resumed.len() >= 30, "{} regenerated frames", resumed.len());
    assert!(
        resumed == uninterrupted,
        "resumed run's frames differ from a clean one's"
    );

    // The start from the previous latent changes the frames (all but those
    // that start a run of frames, from noise either way): the state is used.
    let fresh = dir.path().join("fresh");
    let drop = ["regenerator.init", "regenerator.strength"];
    run_ok(&mut run_args(&fresh, &drop, &[]));
    let fresh = regenerated(&fresh);
    let same = fresh
        .values()
        .zip(uninterrupted.values())
        .filter(|(a, b)| a == b)
        .count();
    assert!(
        (1..fresh.len() / 4).contains(&same),
        "{same} of {} frames equal with and without init = \"previous\"",
        fresh.len()
    );
}

/// The regenerated frames in a run's cache, by file name.
fn regenerated(out: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(out.join("cache"))
        .into_iter()
        .flatten()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with("regenerator-"))
        .flat_map(|e| std::fs::read_dir(e.path()).into_iter().flatten().flatten())
        .filter(|e| e.path().extension().is_some_and(|x| x == "png"))
        .map(|e| {
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect()
}

/// The cache entry `name` of the stage whose folder starts with `stage`.
fn entry(out: &Path, stage: &str, name: &str) -> std::path::PathBuf {
    std::fs::read_dir(out.join("cache"))
        .unwrap()
        .flatten()
        .find(|e| e.file_name().to_string_lossy().starts_with(stage))
        .map(|e| e.path().join(name))
        .filter(|p| p.exists())
        .unwrap_or_else(|| panic!("no {stage}*/{name}"))
}

/// A corrupt saved state of the regenerator (`init = "previous"`) is rebuilt by redrawing its
/// frame again from the state before it, not by starting afresh: the next frame, redrawn again,
/// is the uninterrupted run's, and so are the keypoints.
#[test]
fn a_corrupt_regenerator_state_is_rebuilt() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let run = || {
        let mut cmd = common::sample_run(&out, 100, 109);
        for s in cpu_sets() {
            cmd.args(["--set", &s]);
        }
        cmd
    };
    run_ok(&mut run());
    let redrawn = entry(&out, "regenerator-", "000105.png");
    let (image, keypoints) = (
        std::fs::read(&redrawn).unwrap(),
        std::fs::read(out.join("keypoints.csv")).unwrap(),
    );
    // The state after 104 flipped; 105's redrawn frame and pose cut short, so 105 is redrawn
    // and needs that state.
    let state = entry(&out, "regenerator-", "000104.state");
    let mut bytes = std::fs::read(&state).unwrap();
    bytes[2] ^= 0x40;
    std::fs::write(&state, bytes).unwrap();
    for path in [redrawn.clone(), entry(&out, "pose-", "000105.json")] {
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
    }
    run_ok(&mut run());
    let warnings = read_json(&out.join("run.json"))["warnings"].to_string();
    assert!(warnings.contains("000104.state"), "{warnings}");
    assert!(
        std::fs::read(&redrawn).unwrap() == image,
        "frame 105 redrawn differently"
    );
    assert_eq!(std::fs::read(out.join("keypoints.csv")).unwrap(), keypoints);
}
