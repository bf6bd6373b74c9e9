//! `report.html` in headless Chromium: it loads without console errors and
//! the screenshot shows the plots. Needs the Debian package `chromium`
//! (or `CHROMIUM=/path/to/chromium`); fails, saying so, when it is missing.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use gait_core::{Frame, Keypoint, Pose, PoseSequence};
use gait_eval::{
    CycleCurve, EvalOptions, Side, StripOptions, evaluate_with_angles, read_angles_csv, read_poses,
    skeleton_strip,
};
use gait_report::Report;

fn chromium() -> PathBuf {
    gait_report::pdf::find_chromium().unwrap_or_else(|| {
        panic!(
            "headless Chromium not found: install the Debian package `chromium` (apt-get install -y chromium) or set CHROMIUM=/path/to/chromium"
        )
    })
}

/// Loads `page` and returns Chromium's console lines and the screenshot.
fn load(page: &Path, work: &Path) -> (Vec<String>, image::RgbImage) {
    let shot = work.join("shot.png");
    let profile = work.join("profile");
    let mut child = Command::new(chromium())
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--hide-scrollbars",
            "--enable-logging=stderr",
            "--v=0",
            "--window-size=1400,4200",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(format!("--screenshot={}", shot.display()))
        .arg(format!("file://{}", page.display()))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("starting chromium");
    let start = Instant::now();
    loop {
        if child.try_wait().expect("waiting for chromium").is_some() {
            break;
        }
        if start.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            panic!("chromium did not finish within 120 s");
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    let out = child.wait_with_output().expect("chromium output");
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    let console: Vec<String> = stderr
        .lines()
        .filter(|l| l.contains("CONSOLE"))
        .map(str::to_string)
        .collect();
    let img = image::open(&shot)
        .unwrap_or_else(|e| panic!("no screenshot ({e}); chromium said:\n{stderr}"))
        .to_rgb8();
    (console, img)
}

fn console_errors(console: &[String]) -> Vec<&String> {
    console
        .iter()
        .filter(|l| l.contains("ERROR") || l.contains("Uncaught") || l.contains("Failed to load"))
        .collect()
}

fn curves(shift: f64) -> Vec<CycleCurve> {
    let mut out = Vec::new();
    for side in Side::BOTH {
        for (j, joint) in ["hip", "knee", "ankle"].iter().enumerate() {
            let percent: Vec<f64> = (0..=100).map(f64::from).collect();
            let off = if side == Side::Right { 20.0 } else { 0.0 } + shift;
            let mean = percent
                .iter()
                .map(|p| off + 20.0 * (p / 100.0 * std::f64::consts::TAU + j as f64).sin())
                .collect();
            out.push(CycleCurve {
                side,
                joint: joint.to_string(),
                percent,
                mean,
                sd: vec![3.0; 101],
                n_cycles: 5,
            });
        }
    }
    out
}

/// Pixels within 12 of `rgb` inside the rows `y0..y1`.
fn count(img: &image::RgbImage, rgb: [u8; 3], rows: std::ops::Range<u32>) -> usize {
    rows.flat_map(|y| (0..img.width()).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            y < img.height()
                && img
                    .get_pixel(x, y)
                    .0
                    .iter()
                    .zip(rgb)
                    .all(|(a, b)| a.abs_diff(b) < 12)
        })
        .count()
}

#[test]
fn report_loads_in_chromium_and_shows_the_plots() {
    let fixtures =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../gait-eval/tests/fixtures/metrics");
    let truth = read_poses(&fixtures.join("truth.csv"), 30.0, None).unwrap();
    let pred = read_poses(&fixtures.join("pred_openpose"), 30.0, None).unwrap();
    let ta = read_angles_csv(&fixtures.join("truth_angles.csv")).unwrap();
    let pa = read_angles_csv(&fixtures.join("pred_angles.csv")).unwrap();
    let opts = EvalOptions {
        method: "OpenPose".into(),
        view: Some("right".into()),
        group: Some("Transtibial".into()),
        ..Default::default()
    };
    let eval = evaluate_with_angles(&truth, &pred, Some((&ta, &pa)), &opts).unwrap();

    let names: Vec<String> = gait_core::CANONICAL.iter().map(|s| s.to_string()).collect();
    let pose = |dx: f64| Pose {
        keypoints: names
            .iter()
            .enumerate()
            .map(|(i, n)| {
                Keypoint::new(
                    80.0 + dx + if n.starts_with("left") { -8.0 } else { 8.0 },
                    15.0 + 14.0 * i as f64,
                    1.0,
                )
            })
            .collect(),
    };
    let seq = PoseSequence {
        fps: 30.0,
        names: names.clone(),
        frames: (0..6).collect(),
        poses: (0..6).map(|i| pose(2.0 * i as f64)).collect(),
    };
    let frames: Vec<Frame> = (0..6)
        .map(|i| {
            Frame::new(
                i,
                image::RgbImage::from_pixel(160, 240, image::Rgb([120, 120, 120])),
            )
        })
        .collect();
    let report = Report {
        title: "Report <test>".into(),
        cycles: curves(0.0),
        truth_cycles: curves(0.0),
        method_cycles: vec![("OpenPose".into(), curves(6.0))],
        warnings: eval.warnings.clone(),
        evaluations: vec![eval],
        strip: Some(
            skeleton_strip(
                &seq,
                &frames,
                &StripOptions {
                    max_frames: 6,
                    height: 240,
                },
            )
            .unwrap(),
        ),
        manifest: Some(serde_json::json!({"tool": "gait", "frames": 60})),
        ..Default::default()
    };
    let work = tempfile::tempdir().unwrap();
    let page = report.write(work.path()).unwrap();
    let html = std::fs::read_to_string(&page).unwrap();
    for id in [
        "fig-gait_graphs",
        "fig-comparison",
        "fig-failure_modes",
        "fig-skeleton",
    ] {
        assert!(html.contains(id), "{id} in the page");
    }

    let (console, shot) = load(&page, work.path());
    assert!(
        console_errors(&console).is_empty(),
        "console errors: {console:#?}"
    );
    // The plots are the only red, blue, green and mid-gray areas on the page.
    let h = shot.height();
    let red = count(&shot, [214, 39, 40], 0..h);
    let blue = count(&shot, [31, 119, 180], 0..h);
    let green = count(&shot, [44, 160, 44], 0..h);
    let frame_gray = count(&shot, [120, 120, 120], 0..h);
    assert!(
        red > 3000 && blue > 3000 && green > 1000,
        "plot lines visible: red {red}, blue {blue}, green {green}"
    );
    assert!(
        frame_gray > 50_000,
        "skeleton strip image visible: {frame_gray} frame pixels"
    );
    // The first figure (kinematics) is near the top, right under the warnings.
    assert!(
        count(&shot, [214, 39, 40], 0..900) > 500,
        "kinematics figure near the top of the page"
    );
}

#[test]
fn console_errors_are_detected() {
    // The check above must be able to fail: a page with a script error.
    let work = tempfile::tempdir().unwrap();
    let page = work.path().join("broken.html");
    std::fs::write(
        &page,
        "<!DOCTYPE html><html><body><p>x</p><script>undefined_function();</script></body></html>",
    )
    .unwrap();
    let (console, _) = load(&page, work.path());
    assert!(
        !console_errors(&console).is_empty(),
        "a script error shows on the console: {console:#?}"
    );
}
