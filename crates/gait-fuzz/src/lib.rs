//! Fuzzing every input parser of gait: [`targets`] lists one target per parser, [`mutate`]
//! makes inputs from real seed files, [`engine`] runs a target over them and keeps any input
//! that panics, aborts, allocates beyond the limit or hangs. The `gait-fuzz` binary runs the
//! targets in child processes for a time or input budget (CI and long runs); the crate's tests
//! replay the seeds and every saved crash (`fuzz/regressions/`, whole or as a [`patch`] of a seed).
//!
//! Why this engine and not libFuzzer or AFL++: both need instrumented builds that the stable
//! toolchain of this project's machines cannot make without nightly flags, and CI must build
//! with what a fresh machine has. A mutational fuzzer over real files (the way clinics' files go
//! wrong: truncated, hand-edited, written by another version) runs as plain Rust, in CI and as
//! tests, and is reproducible from its seed. It is not coverage-guided; the seeds are.

pub mod engine;
pub mod mutate;
pub mod patch;
pub mod recording;
pub mod targets;

use std::path::PathBuf;

/// The repository root (seeds and regressions are named from it).
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}
