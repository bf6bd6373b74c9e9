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

/// plotters' SVG with each text element's content on the element's line (`<text ...>100</text>`).
fn svg_text(fig: &Figure) -> String {
    fig.svg.replace(">\n", ">").replace("\n</text>", "</text>")
}

/// `attr="value"` of an SVG element's text, as a number.
fn attr(element: &str, name: &str) -> f64 {
    let key = format!("{name}=\"");
    let start = element.find(&key).unwrap() + key.len();
    element[start..].split('"').next().unwrap().parse().unwrap()
}

/// The SVG elements `<tag ...>` (their opening text).
fn elements<'a>(svg: &'a str, tag: &str) -> Vec<&'a str> {
    svg.split(&format!("<{tag} "))
        .skip(1)
        .map(|e| e.split('>').next().unwrap())
        .collect()
}

#[test]
fn cycle_axes_read_whole_percents_and_keep_the_last_tick_inside() {
    let ctx = GraphContext {
        prosthetic: None,
        normative: None,
        toe_off: [None, None],
    };
    let k = gait_graphs(&curves(0.0), ctx).unwrap();
    let svg = svg_text(&k);
    assert!(
        !svg.contains(">10.0<") && !k.svg.contains(">100.0<"),
        "percent ticks read 10, not 10.0"
    );
    let width = attr(elements(&svg, "svg")[0], "width");
    let hundreds: Vec<f64> = svg
        .split("<text ")
        .filter(|t| t.contains(">100</text>"))
        .map(|t| attr(t, "x"))
        .collect();
    assert_eq!(hundreds.len(), 3, "one 100 tick per panel");
    // "100" is about 22 px wide at 12 px, centred on its tick.
    let last = hundreds.iter().cloned().fold(0.0, f64::max);
    assert!(
        last + 11.0 <= width,
        "the 100 tick at {last} is cut by the edge at {width}"
    );
}

#[test]
fn map_legend_is_above_the_bars_and_the_axis_has_four_ticks() {
    let norm = gait_eval::report_config::ReportConfig::default()
        .load_normative()
        .unwrap()
        .unwrap();
    let mut high = curves(0.0);
    for c in &mut high {
        c.mean.iter_mut().for_each(|v| *v += 30.0);
    }
    let scores = gait_eval::Scores::compute(&high, &norm);
    let map = gait_eval::map_bars(&scores, Some((6.0, "healthy".into()))).unwrap();
    let svg = svg_text(&map);
    let rects = elements(&svg, "rect");
    let bars: Vec<&&str> = rects
        .iter()
        .filter(|r| (r.contains("#D62728") || r.contains("#1F77B4")) && attr(r, "width") > 20.0)
        .collect();
    assert_eq!(bars.len(), 8, "two bars per group: {rects:?}");
    let legend = rects
        .iter()
        .rfind(|r| r.contains("#FFFFFF") && r.contains("opacity=\"0.8\""))
        .expect("legend box");
    let legend_bottom = attr(legend, "y") + attr(legend, "height");
    let top_of_bars = bars.iter().map(|r| attr(r, "y")).fold(f64::MAX, f64::min);
    assert!(
        top_of_bars > legend_bottom,
        "the legend (to y {legend_bottom}) covers a bar (from y {top_of_bars})"
    );
    for g in ["hip", "knee", "ankle", "GPS"] {
        assert!(svg.contains(&format!(">{g}</text>")), "{g}");
    }
    // The tallest bar's group sits in the last quarter: no fifth, empty segment after GPS.
    let gps_bar = bars
        .iter()
        .map(|r| attr(r, "x") + attr(r, "width"))
        .fold(0.0, f64::max);
    let plot_right = attr(elements(&svg, "svg")[0], "width") - 10.0;
    assert!(
        plot_right - gps_bar < 40.0,
        "empty space after the GPS bars: {gps_bar} of {plot_right}"
    );
}
