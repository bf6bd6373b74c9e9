//! Swap detection on real pose-estimator output: BlazePose on the bundled sample video, with
//! leg labels checked by eye (tests/data/sample-blazepose/README.md).

use gait_kin::{ContinuitySwap, KeypointGate, LikelihoodThreshold, Tracks};

#[test]
fn real_glitches_are_found_and_correct_labels_kept() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../tests/data/sample-blazepose/keypoints.csv"
    );
    let seq = gait_core::dlc::read(std::fs::File::open(path).unwrap(), None, 30.0).unwrap();
    let mut t = Tracks::from_sequence(&seq);
    LikelihoodThreshold(0.5).apply(&mut t);
    let swapped = ContinuitySwap::default().detect(&t);
    let found: Vec<usize> = (0..t.len())
        .filter(|&i| swapped[i])
        .map(|i| i + t.first_frame)
        .collect();
    println!("frames judged swapped: {found:?}");
    for f in [122, 159] {
        assert!(
            found.contains(&f),
            "BlazePose's swap at {f} missed: {found:?}"
        );
    }
    // Correct labels over a whole stride must stay; before the per-second swap price the
    // detector exchanged 129-158 to cancel the glitch at 159.
    let wrong: Vec<usize> = found
        .iter()
        .copied()
        .filter(|f| (121..=158).contains(f) && *f != 122)
        .collect();
    assert!(wrong.is_empty(), "correct labels exchanged at {wrong:?}");
}
