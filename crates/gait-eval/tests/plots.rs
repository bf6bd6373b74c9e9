//! Figures render to PNG and SVG with visible lines, bars and text.

use gait_core::{Frame, Keypoint, Pose, PoseSequence};
use gait_eval::failure::{Count, Failures};
use gait_eval::{
    CycleCurve, FailureEntry, Figure, GraphContext, Side, StripOptions, comparison_plot,
    failure_bars, gait_graphs, skeleton_strip,
};

pub fn curves(offset: f64) -> Vec<CycleCurve> {
    let mut out = Vec::new();
    for side in Side::BOTH {
        for (j, joint) in ["hip", "knee", "ankle"].iter().enumerate() {
            let percent: Vec<f64> = (0..=100).map(f64::from).collect();
            let shift = if side == Side::Right { 25.0 } else { 0.0 };
            let mean = percent
                .iter()
                .map(|p| {
                    offset + shift + 20.0 * (p / 100.0 * std::f64::consts::TAU + j as f64).sin()
                })
                .collect();
            out.push(CycleCurve {
                side,
                joint: joint.to_string(),
                percent,
                mean,
                sd: vec![4.0; 101],
                n_cycles: 4,
            });
        }
    }
    out
}

/// Pixels close to `rgb` in the PNG.
fn count_colour(fig: &Figure, rgb: [u8; 3]) -> usize {
    let img = image::load_from_memory(&fig.png)
        .expect("PNG decodes")
        .to_rgb8();
    img.pixels()
        .filter(|p| p.0.iter().zip(rgb).all(|(a, b)| a.abs_diff(b) < 12))
        .count()
}

fn dark_pixels(fig: &Figure) -> usize {
    let img = image::load_from_memory(&fig.png).unwrap().to_rgb8();
    img.pixels().filter(|p| p.0.iter().all(|&c| c < 80)).count()
}

#[test]
fn kinematics_and_comparison_plots() {
    let ctx = GraphContext {
        prosthetic: Some(Side::Right),
        normative: None,
        toe_off: [Some(60.0), Some(62.0)],
    };
    let k = gait_graphs(&curves(0.0), ctx).unwrap();
    assert!(
        count_colour(&k, [214, 39, 40]) > 500,
        "left (red) line visible"
    );
    assert!(
        count_colour(&k, [31, 119, 180]) > 500,
        "right (blue) line visible"
    );
    assert!(
        k.svg.contains("right (prosthetic), n="),
        "legend names the roles"
    );
    assert!(dark_pixels(&k) > 500, "axis text is rendered");
    assert!(
        k.svg.contains("Knee flexion") && k.svg.contains("<polyline"),
        "SVG has text and lines"
    );
    let c = comparison_plot(
        &curves(0.0),
        &[
            ("OpenPose".into(), curves(5.0)),
            ("Zero-shot".into(), curves(2.0)),
        ],
        Side::Right,
    )
    .unwrap();
    assert!(
        count_colour(&c, [44, 160, 44]) > 500,
        "ground truth visible"
    );
    assert!(c.svg.contains("Zero-shot") && c.svg.contains("prosthetic (right)"));
    let dir = tempfile::tempdir().unwrap();
    let paths = c.write(dir.path()).unwrap();
    assert!(paths.iter().all(|p| p.exists()));
}

fn failures(ni: f64, sw: f64) -> Failures {
    let c = |p: f64| Count {
        frames: (p * 1.8) as usize,
        percent: p,
    };
    Failures {
        frames: 180,
        not_identified: c(ni),
        swapped: c(sw),
        misidentified: c(3.0),
        any: c(ni + sw + 3.0),
        by_side: vec![],
        reference_length_px: 100.0,
        misid_threshold_px: 50.0,
        swap_margin_px: 10.0,
        not_identified_frames: vec![],
        swapped_frames: vec![],
        misidentified_frames: vec![],
    }
}

#[test]
fn failure_bars_per_view() {
    let entries: Vec<FailureEntry> = ["anterior", "posterior", "left", "right"]
        .iter()
        .flat_map(|v| {
            [
                ("OpenPose", failures(40.0, 2.0)),
                ("Zero-shot", failures(5.0, 8.0)),
            ]
            .map(|(m, f)| FailureEntry {
                view: v.to_string(),
                method: m.into(),
                failures: f,
            })
        })
        .collect();
    let f = failure_bars(&entries).unwrap();
    assert!(count_colour(&f, [31, 119, 180]) > 2000 && count_colour(&f, [214, 39, 40]) > 500);
    assert!(f.svg.contains("posterior") && f.svg.contains("Left/right swapped"));
    assert!(failure_bars(&[]).is_err());
}

#[test]
fn skeleton_strip_over_frames() {
    let names: Vec<String> = gait_core::CANONICAL.iter().map(|s| s.to_string()).collect();
    let pose = |dx: f64| Pose {
        keypoints: names
            .iter()
            .enumerate()
            .map(|(i, n)| {
                let x = 100.0 + dx + if n.starts_with("left") { -10.0 } else { 10.0 };
                Keypoint::new(x, 20.0 + 15.0 * i as f64, 0.9)
            })
            .collect(),
    };
    let seq = PoseSequence {
        fps: 30.0,
        names: names.clone(),
        frames: (0..10).collect(),
        poses: (0..10).map(|i| pose(i as f64)).collect(),
    };
    let gray = image::RgbImage::from_pixel(200, 260, image::Rgb([128, 128, 128]));
    let frames: Vec<Frame> = (0..5).map(|i| Frame::new(i, gray.clone())).collect();
    let s = skeleton_strip(
        &seq,
        &frames,
        &StripOptions {
            max_frames: 4,
            height: 260,
        },
    )
    .unwrap();
    let img = image::load_from_memory(&s.png).unwrap().to_rgb8();
    assert_eq!(img.height(), 260);
    assert!(
        count_colour(&s, [128, 128, 128]) > 20_000,
        "frame pixels under the skeleton"
    );
    assert!(
        count_colour(&s, [214, 39, 40]) > 100 && count_colour(&s, [31, 119, 180]) > 100,
        "both legs drawn"
    );
    assert!(s.svg.contains("frame 9"), "last frame is in the strip");
    assert!(
        skeleton_strip(
            &PoseSequence {
                poses: vec![],
                frames: vec![],
                ..seq
            },
            &[],
            &StripOptions::default()
        )
        .is_err()
    );
}
