//! Every target on its seeds and on every input that once crashed it (fuzz/regressions/), then
//! a short, fixed-seed fuzz run per target: no panic. (Aborts end this test binary, which fails
//! it too.) The long runs are `gait-fuzz run` (tools/test.sh, and BENCHMARKS.md).

use gait_fuzz::engine::{self, Budget};
use gait_fuzz::targets::{Scratch, TARGETS};

#[test]
fn every_target_has_seeds_and_survives_them_and_its_regressions() {
    let scratch = Scratch::new().unwrap();
    for t in TARGETS {
        for p in engine::regressions(t) {
            if let Err(e) = engine::read_input(&p) {
                panic!("{}: regression case unreadable: {e}", t.name);
            }
        }
        let seeds = engine::seeds(t);
        assert!(!seeds.is_empty(), "{}: no seed files", t.name);
        for (path, bytes) in &seeds {
            if let Err(why) = engine::run_one(t, &scratch, bytes) {
                panic!("{} on {}: {why}", t.name, path.display());
            }
        }
    }
}

#[test]
fn a_short_fuzz_run_of_every_target_finds_nothing() {
    let crashes = tempfile::tempdir().unwrap();
    for t in TARGETS {
        // The video target spawns ffmpeg per input: fewer of them.
        let inputs = if t.name == "video" { 20 } else { 300 };
        let stats = engine::fuzz(
            t,
            Budget {
                inputs,
                seconds: 60.0,
            },
            12345,
            crashes.path(),
            None,
        );
        assert!(stats.crashes.is_empty(), "{}: {:?}", t.name, stats.crashes);
        assert!(stats.inputs > 0, "{}", t.name);
    }
}
