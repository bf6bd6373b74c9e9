//! The written files, read back by ezc3d (the reference C3D implementation, pinned in
//! tools/export/setup_ezc3d.sh), must give back the markers, missing samples, rate, units and
//! events we put in. The test does not skip when Python or ezc3d is missing: it fails and says
//! how to set them up.

use std::path::{Path, PathBuf};
use std::process::Command;

use gait_c3d::{C3dData, Context, Event, EventKind, Marker};
use serde_json::Value;

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Python of the ezc3d venv, created by the setup script on first use.
fn ezc3d_python() -> PathBuf {
    let root = repo_root();
    let out = Command::new("bash")
        .arg(root.join("tools/export/setup_ezc3d.sh"))
        .output()
        .unwrap_or_else(|e| panic!("cannot run bash for tools/export/setup_ezc3d.sh: {e}"));
    assert!(
        out.status.success(),
        "this test needs ezc3d: run `bash tools/export/setup_ezc3d.sh` from the repository root \
         (needs python3 3.11 with venv, and PyPI reachable once). It failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let python = PathBuf::from(String::from_utf8_lossy(&out.stdout).trim());
    assert!(
        python.exists(),
        "setup_ezc3d.sh printed {python:?}, which does not exist"
    );
    python
}

/// What tools/export/check_c3d.py reports for `file`.
fn read_with_ezc3d(file: &Path) -> Value {
    let root = repo_root();
    let out = Command::new(ezc3d_python())
        .arg(root.join("tools/export/check_c3d.py"))
        .arg(file)
        .output()
        .expect("run check_c3d.py");
    assert!(
        out.status.success(),
        "ezc3d could not read {}:\n{}",
        file.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("check_c3d.py prints JSON")
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// The seconds a reader gets back from our [minutes, float32 seconds] pair.
fn float32_time(t: f64) -> f64 {
    let minutes = (t / 60.0).floor();
    minutes * 60.0 + f64::from((t - minutes * 60.0) as f32)
}

/// 4 markers x 300 frames of image coordinates around 1234.5678 px, with missing samples
/// (None, and one NaN which must count as missing), and 8 events of both sides and kinds.
fn walking_data() -> C3dData {
    let rate_hz = 29.97;
    let first_frame = 11;
    let labels = ["LHeel", "RHeel", "LBigToe", "RSmallToe"];
    let markers = labels
        .iter()
        .enumerate()
        .map(|(m, label)| {
            let xy = (0..300)
                .map(|i| {
                    if (i + 7 * m) % 37 == 0 || (m == 3 && (100..120).contains(&i)) {
                        return None;
                    }
                    let (i, m) = (i as f64, m as f64);
                    let x = 1234.5678 + 0.731 * i - 13.25 * m;
                    let y = 654.321 - 0.0917 * i + 3.5 * m + 20.0 * (i / 9.0).sin();
                    Some([x, if m == 2.0 && i == 150.0 { f64::NAN } else { y }])
                })
                .collect();
            Marker {
                label: label.to_string(),
                xy,
            }
        })
        .collect();
    let events = (0..8)
        .map(|i| Event {
            context: if i % 2 == 0 {
                Context::Left
            } else {
                Context::Right
            },
            kind: if (i / 2) % 2 == 0 {
                EventKind::FootStrike
            } else {
                EventKind::FootOff
            },
            // On a frame: C3D frame n is at (n - 1) / rate.
            time_s: (first_frame + 20 + 31 * i - 1) as f64 / rate_hz,
        })
        .collect();
    C3dData {
        rate_hz,
        first_frame,
        units: "px".into(),
        markers,
        events,
    }
}

#[test]
fn ezc3d_reads_markers_missing_samples_and_events() {
    let data = walking_data();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("keypoints.c3d");
    gait_c3d::write(&path, &data).unwrap();
    let got = read_with_ezc3d(&path);

    let labels: Vec<&str> = got["labels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(labels, ["LHeel", "RHeel", "LBigToe", "RSmallToe"]);
    let rate32 = f64::from(data.rate_hz as f32);
    assert_eq!(f(&got["rate"]), rate32);
    assert_eq!(f(&got["header_rate"]), rate32);
    assert_eq!(got["units"], "px");
    assert_eq!(got["first_frame"], 11);
    assert_eq!(got["last_frame"], 310);
    assert_eq!(got["frames"], 300);
    assert_eq!(got["analog_used"], 0);
    assert_eq!(got["analog_channels"], 0);

    let mut max_diff = 0.0f64;
    let (mut present, mut missing) = (0, 0);
    for (m, marker) in data.markers.iter().enumerate() {
        for (i, sample) in marker.xy.iter().enumerate() {
            let point = &got["points"][m][i];
            let residual = f(&got["residuals"][m][i]);
            match sample.filter(|p| p.iter().all(|v| v.is_finite())) {
                Some([x, y]) => {
                    present += 1;
                    assert!(
                        residual >= 0.0,
                        "{} frame {i}: residual {residual}",
                        marker.label
                    );
                    for (k, want) in [x, y, 0.0].into_iter().enumerate() {
                        let v = f(&point[k]);
                        // Stored as float32: exactly its rounding, within 1e-4 of the input.
                        assert_eq!(
                            v,
                            f64::from(want as f32),
                            "{} frame {i} axis {k}",
                            marker.label
                        );
                        assert!(
                            (v - want).abs() < 1e-4,
                            "{} frame {i} axis {k}: {v} vs {want}",
                            marker.label
                        );
                        max_diff = max_diff.max((v - want).abs());
                    }
                }
                None => {
                    missing += 1;
                    // ezc3d turns the residual -1 into NaN coordinates and keeps the -1.
                    assert!(
                        point.as_array().unwrap().iter().all(Value::is_null),
                        "{} frame {i}: {point}",
                        marker.label
                    );
                    assert_eq!(residual, -1.0, "{} frame {i}", marker.label);
                }
            }
        }
    }
    assert!(
        missing >= 50 && present > 1000,
        "{missing} missing, {present} present"
    );
    eprintln!("max |ezc3d - input| over {present} samples: {max_diff:e} (px); {missing} missing");

    let events = got["events"].as_array().unwrap();
    assert_eq!(events.len(), data.events.len());
    for (e, g) in data.events.iter().zip(events) {
        assert_eq!(g["context"], e.context.label());
        assert_eq!(g["label"], e.kind.label());
        let (icon, description) = match e.kind {
            EventKind::FootStrike => (1, "The instant the heel strikes the ground"),
            EventKind::FootOff => (2, "The instant the toe leaves the ground"),
        };
        assert_eq!(g["icon_id"], icon);
        assert_eq!(g["description"], description);
        assert_eq!(g["generic_flag"], 0);
        assert_eq!(f(&g["minutes"]), 0.0);
        // Exact up to float32: the seconds are the float32 rounding of the input.
        assert_eq!(
            f(&g["time_s"]),
            f64::from(e.time_s as f32),
            "event at {} s",
            e.time_s
        );
        assert!((f(&g["time_s"]) - e.time_s).abs() < 1e-6);
    }
}

/// Past 32767 frames (POINT:FRAMES no longer fits an int16) and past a minute (event times
/// carry whole minutes).
#[test]
fn ezc3d_reads_a_long_recording() {
    let frames = 40_000;
    let rate_hz = 100.0;
    let xy = (0..frames)
        .map(|i| {
            if i % 1000 == 0 {
                None
            } else {
                Some([i as f64 * 0.01, 1.5])
            }
        })
        .collect();
    let times = [0.0, 59.99, 60.0, 61.23, 399.99];
    let data = C3dData {
        rate_hz,
        first_frame: 1,
        units: "mm".into(),
        markers: vec![Marker {
            label: "Nose".into(),
            xy,
        }],
        events: times
            .iter()
            .map(|&time_s| Event {
                context: Context::Right,
                kind: EventKind::FootStrike,
                time_s,
            })
            .collect(),
    };
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("long.c3d");
    gait_c3d::write(&path, &data).unwrap();
    let got = read_with_ezc3d(&path);

    assert_eq!(got["frames"], frames);
    assert_eq!(got["last_frame"], frames);
    assert_eq!(got["units"], "mm");
    let points = got["points"][0].as_array().unwrap();
    assert_eq!(points.len(), frames);
    assert!(points[0][0].is_null() && points[39_000][0].is_null());
    assert_eq!(f(&points[39_999][0]), f64::from(399.99f32));
    assert_eq!(f(&points[12_345][1]), 1.5);

    let events = got["events"].as_array().unwrap();
    for (&t, g) in times.iter().zip(events) {
        assert_eq!(f(&g["minutes"]), (t / 60.0).floor(), "event at {t} s");
        assert_eq!(f(&g["time_s"]), float32_time(t), "event at {t} s");
        assert!((f(&g["time_s"]) - t).abs() < 1e-5, "event at {t} s");
    }
}

/// No events: EVENT:USED = 0 and nothing else in the group; ezc3d still reads the file.
#[test]
fn ezc3d_reads_a_file_without_events() {
    let data = C3dData {
        rate_hz: 60.0,
        first_frame: 1,
        units: "px".into(),
        markers: vec![Marker {
            label: "A".into(),
            xy: vec![Some([1.0, 2.0]), None],
        }],
        events: vec![],
    };
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("no-events.c3d");
    gait_c3d::write(&path, &data).unwrap();
    let got = read_with_ezc3d(&path);
    assert_eq!(got["events"], Value::Array(vec![]));
    assert_eq!(got["points"][0][0], serde_json::json!([1.0, 2.0, 0.0]));
    assert_eq!(got["frames"], 2);
}
