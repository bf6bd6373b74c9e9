//! Libraries that cannot be used: each refused with an error naming the
//! problem, before any of their stage code runs.

mod common;

use std::path::PathBuf;

use gait_plugin::abi::ABI_VERSION;
use gait_plugin::{PluginConfig, load_edge_detector, load_pose_estimator, load_regenerator};

#[test]
fn missing_library() {
    let cfg = PluginConfig {
        path: PathBuf::from("no/such/libplugin.so"),
        options: Default::default(),
    };
    let err = load_edge_detector(&cfg, &common::ctx())
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("no/such/libplugin.so") && err.contains("not found"),
        "{err}"
    );
    let cwd = std::env::current_dir().unwrap();
    assert!(
        err.contains(&cwd.display().to_string()),
        "relative path not resolved from the current directory: {err}"
    );
}

#[test]
fn not_a_shared_library() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("libfake.so");
    std::fs::write(&path, b"not an ELF file").unwrap();
    let cfg = PluginConfig {
        path,
        options: Default::default(),
    };
    let err = load_edge_detector(&cfg, &common::ctx())
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("cannot load plugin library") && err.contains("libfake.so"),
        "{err}"
    );
}

#[test]
fn library_without_entry_symbol() {
    let cfg = common::config("gait-testing-no-entry", "");
    let err = load_edge_detector(&cfg, &common::ctx())
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("gait_plugin_entry") && err.contains("not a gait plugin"),
        "{err}"
    );
}

#[test]
fn other_abi_version_names_both_versions() {
    let cfg = common::config("gait-testing-old-abi", "");
    let err = load_pose_estimator(&cfg, &common::ctx())
        .err()
        .unwrap()
        .to_string();
    let plugin = format!("ABI version {}", ABI_VERSION + 1);
    let host = format!("ABI version {ABI_VERSION}");
    assert!(err.contains(&plugin) && err.contains(&host), "{err}");
}

#[test]
fn wrong_family_names_table_and_kind() {
    let cfg = common::config("gait-sobel-edge", "");
    let err = load_pose_estimator(&cfg, &common::ctx())
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("an edge detector")
            && err.contains("[pose]")
            && err.contains("a pose estimator"),
        "{err}"
    );
    let cfg = common::config("gait-testing-pose", "");
    let err = load_regenerator(&cfg, &common::ctx())
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("a pose estimator") && err.contains("[regenerator]"),
        "{err}"
    );
}

#[test]
fn stage_error_kind() {
    // Option problems are the user's input; load problems are the plugin's.
    let cfg = common::config("gait-sobel-edge", "nope = 1");
    let err = load_edge_detector(&cfg, &common::ctx()).err().unwrap();
    assert!(matches!(err, gait_core::StageError::BadInput(_)), "{err:?}");
    let cfg = common::config("gait-testing-no-entry", "");
    let err = load_edge_detector(&cfg, &common::ctx()).err().unwrap();
    assert!(
        matches!(err, gait_core::StageError::Backend { .. }),
        "{err:?}"
    );
}
