//! Plugins that fail, panic or return malformed data: every case is an error
//! saying what was wrong, and nothing malformed reaches the pipeline.

mod common;

use gait_core::{CANONICAL, EdgeMap, Frame, Resize, StageError};
use gait_plugin::{load_edge_detector, load_pose_estimator, load_regenerator};

fn frames() -> Vec<Frame> {
    vec![common::sample_frame(3), common::sample_frame(4)]
}

fn faulty_edge(fault: &str) -> Result<Vec<EdgeMap>, StageError> {
    let cfg = common::config("gait-testing-faulty-edge", &format!("fault = \"{fault}\""));
    let mut edge = load_edge_detector(&cfg, &common::ctx())?;
    edge.detect(&frames())
}

#[test]
fn raw_abi_plugin_works_when_it_behaves() {
    let maps = faulty_edge("none").unwrap();
    let frames = frames();
    for (m, f) in maps.iter().zip(&frames) {
        assert_eq!(m.index, f.index);
        let green: Vec<u8> = f.image.pixels().map(|p| p[1]).collect();
        assert_eq!(m.image.as_raw(), &green);
        assert_eq!(m.resize, Resize::identity(f.width(), f.height()));
    }
}

#[test]
fn malformed_edge_maps_are_refused() {
    for (fault, says) in [
        (
            "short_buffer",
            "needs 57600 bytes, but the buffer has 57599",
        ),
        ("wrong_width", "needs 57780 bytes, but the buffer has 57600"),
        ("huge", "4294967295x4294967295"),
        ("missing_map", "1 edge maps for 2 frames"),
        ("null_items", "null pointer with 2 items"),
        ("bad_resize", "must be finite"),
    ] {
        let err = faulty_edge(fault).unwrap_err().to_string();
        assert!(
            err.contains("testing-faulty-edge") && err.contains("malformed") && err.contains(says),
            "{fault}: {err}"
        );
    }
}

#[test]
fn plugin_errors_and_bad_statuses() {
    let err = faulty_edge("error").unwrap_err().to_string();
    assert!(err.contains("the edge model exploded"), "{err}");
    let err = faulty_edge("unknown_status").unwrap_err().to_string();
    assert!(err.contains("unknown status code 42"), "{err}");
    let err = faulty_edge("null_instance").unwrap_err().to_string();
    assert!(err.contains("returned no instance"), "{err}");
}

fn pose_config(options: &str) -> gait_plugin::PluginConfig {
    common::config("gait-testing-pose", options)
}

#[test]
fn pose_plugin_round_trip_and_reset() {
    let mut pose = load_pose_estimator(&pose_config(""), &common::ctx()).unwrap();
    let names = pose.keypoint_names();
    assert_eq!(&names[..15], &CANONICAL.map(String::from)[..]);
    assert_eq!(names[15], "tail");
    let poses = pose.estimate(&frames()).unwrap();
    assert_eq!(poses.len(), 2);
    assert_eq!(poses[1].keypoints[0].x, 1.0, "second frame seen");
    assert_eq!(poses[1].keypoints[0].y, 4.0, "frame index");
    assert_eq!(poses[0].keypoints[7].x, 7.0);
    assert_eq!(poses[0].keypoints[15].likelihood, 0.5);
    assert!(
        !poses[0].keypoints[14].is_found(),
        "(NaN, NaN, 0) is a missing keypoint"
    );
    pose.reset();
    let again = pose.estimate(&frames()).unwrap();
    assert_eq!(again[0].keypoints[0].x, 0.0, "reset reached the plugin");
}

#[test]
fn nan_and_infinite_keypoints_are_refused() {
    for bad in [
        "nan_x",
        "nan_likelihood",
        "inf_y",
        "missing_with_likelihood",
    ] {
        let mut pose =
            load_pose_estimator(&pose_config(&format!("bad = \"{bad}\"")), &common::ctx()).unwrap();
        let err = pose.estimate(&frames()).unwrap_err().to_string();
        assert!(
            err.contains("malformed") && err.contains("keypoint `left_knee` of frame 3"),
            "{bad}: {err}"
        );
    }
    let mut pose = load_pose_estimator(&pose_config("bad = \"short\""), &common::ctx()).unwrap();
    let err = pose.estimate(&frames()).unwrap_err().to_string();
    assert!(
        err.contains("14 keypoints per pose, but the plugin names 16"),
        "{err}"
    );
}

#[test]
fn panics_become_errors() {
    let err = load_pose_estimator(&pose_config("panic_in = \"create\""), &common::ctx())
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("panicked: testing-pose was asked to panic in create"),
        "{err}"
    );
    let err = load_pose_estimator(&pose_config("panic_in = \"names\""), &common::ctx())
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("keypoint_names failed: panicked"), "{err}");
    let mut pose =
        load_pose_estimator(&pose_config("panic_in = \"estimate\""), &common::ctx()).unwrap();
    let err = pose.estimate(&frames()).unwrap_err().to_string();
    assert!(err.contains("panicked: index out of bounds"), "{err}");
    // The instance survives its panic and can be called again.
    assert!(pose.estimate(&frames()).is_err());
}

#[test]
fn regenerator_plugin_with_and_without_edges() {
    let cfg = common::config("gait-testing-regen", "");
    let mut regen = load_regenerator(&cfg, &common::ctx()).unwrap();
    let frames = frames();
    let out = regen.regenerate(&frames, None).unwrap();
    for (o, f) in out.iter().zip(&frames) {
        assert_eq!(o.index, f.index);
        let p = f.image.get_pixel(10, 20);
        assert_eq!(
            o.image.get_pixel(10, 20).0,
            [255 - p[0], 255 - p[1], 255 - p[2]]
        );
    }
    let edges: Vec<EdgeMap> = frames
        .iter()
        .map(|f| EdgeMap {
            index: f.index,
            image: image::GrayImage::from_fn(f.width(), f.height(), |x, _| {
                [if x == 5 { 255 } else { 0 }].into()
            }),
            resize: Resize::identity(f.width(), f.height()),
        })
        .collect();
    let out = regen.regenerate(&frames, Some(&edges)).unwrap();
    assert_eq!(out[1].image.get_pixel(5, 9).0, [255, 0, 0]);
    let err = regen
        .regenerate(&frames, Some(&edges[..1]))
        .unwrap_err()
        .to_string();
    assert!(err.contains("1 edge maps for 2 frames"), "{err}");
}

#[test]
fn regenerator_wrong_size_and_failure() {
    let cfg = common::config("gait-testing-regen", "shrink = true");
    let mut regen = load_regenerator(&cfg, &common::ctx()).unwrap();
    let err = regen.regenerate(&frames(), None).unwrap_err().to_string();
    assert!(
        err.contains("image 0 is 319x180, but its frame is 320x180"),
        "{err}"
    );
    let cfg = common::config("gait-testing-regen", "fail = true");
    let mut regen = load_regenerator(&cfg, &common::ctx()).unwrap();
    let err = regen.regenerate(&frames(), None).unwrap_err().to_string();
    assert!(err.contains("no accelerator here"), "{err}");
}
