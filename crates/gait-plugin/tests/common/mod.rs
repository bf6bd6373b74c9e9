//! Builds the plugin crates of the workspace once per test binary, with the
//! same target folder and profile as the test itself, and finds their
//! libraries.

#![allow(dead_code, reason = "each test binary uses part of these helpers")]

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use gait_core::{Frame, StageContext};
use gait_plugin::PluginConfig;

const PLUGINS: [&str; 6] = [
    "gait-sobel-edge",
    "gait-testing-faulty-edge",
    "gait-testing-pose",
    "gait-testing-regen",
    "gait-testing-old-abi",
    "gait-testing-no-entry",
];

/// `<target>/<profile>`: the test binary lives in its `deps/`.
fn profile_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("test binary path");
    let deps = exe.parent().expect("deps folder");
    deps.parent().expect("profile folder").to_path_buf()
}

fn build_plugins() -> PathBuf {
    let dir = profile_dir();
    let parent = dir.parent().expect("target folder");
    // Tests built with `--target <triple>` (e.g. for sanitizers) live one
    // level deeper, in `<target>/<triple>/<profile>`; cargo marks the target
    // folder with CACHEDIR.TAG (and the triple folder too).
    let (target, triple) = match parent.parent() {
        Some(root) if root.join("CACHEDIR.TAG").is_file() => {
            (root, parent.file_name().and_then(|n| n.to_str()))
        }
        _ => (parent, None),
    };
    let profile = match dir.file_name().and_then(|n| n.to_str()) {
        Some("debug") => "dev".to_string(),
        Some(other) => other.to_string(),
        None => panic!("cannot tell the cargo profile from {}", dir.display()),
    };
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| env!("CARGO").to_string());
    let mut cmd = Command::new(cargo);
    cmd.arg("build")
        .arg("--profile")
        .arg(&profile)
        .arg("--target-dir")
        .arg(target)
        .arg("--manifest-path")
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../Cargo.toml"));
    if let Some(triple) = triple {
        cmd.arg("--target").arg(triple);
    }
    for p in PLUGINS {
        cmd.arg("-p").arg(p);
    }
    let status = cmd
        .status()
        .expect("cannot run cargo to build the test plugins");
    assert!(
        status.success(),
        "building the test plugins failed: {cmd:?}"
    );
    dir
}

/// The shared library of plugin crate `krate` (e.g. "gait-sobel-edge").
pub fn library(krate: &str) -> PathBuf {
    static BUILT: OnceLock<PathBuf> = OnceLock::new();
    let dir = BUILT.get_or_init(build_plugins);
    let file = format!(
        "{}{}{}",
        std::env::consts::DLL_PREFIX,
        krate.replace('-', "_"),
        std::env::consts::DLL_SUFFIX
    );
    let path = dir.join(file);
    assert!(path.is_file(), "{} was not built", path.display());
    path
}

/// A plugin table for `krate` with `options` (TOML).
pub fn config(krate: &str, options: &str) -> PluginConfig {
    PluginConfig {
        path: library(krate),
        options: options.parse().expect("options TOML"),
    }
}

pub fn ctx() -> StageContext {
    StageContext::new("/nonexistent/models")
}

/// The committed real frame (a downscaled frame of the sample video).
pub fn sample_frame(index: usize) -> Frame {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/sobel/frame.png");
    let image = image::open(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8();
    Frame::new(index, image)
}
