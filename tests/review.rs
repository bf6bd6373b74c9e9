//! `gait review` end to end, on a real run of the sample video: the page driven in Debian's
//! headless Chromium over the DevTools protocol (tests/review/browser.cjs with puppeteer-core,
//! installed by tools/review/setup_puppeteer.sh), the server's security, and its bad input.
//! What the page saved and shows must equal what `gait kin --corrections` computes.

mod common;
#[path = "review/support.rs"]
mod support;

use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::sync::OnceLock;

use common::{fails_with, gait, read_json, run_ok, sample_video};
use support::{Server, in_browser};

/// One run of frames 40-200 of the sample, shared by the tests of this file.
fn sample_run() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap().keep().join("run");
        run_ok(&mut common::sample_run(&dir, 40, 200));
        dir
    })
}

/// A copy of the run's files (not its cache), so that each test has its own corrections.toml.
fn copy_run(to: &Path) -> PathBuf {
    std::fs::create_dir_all(to).unwrap();
    for f in ["run.json", "keypoints.csv"] {
        std::fs::copy(sample_run().join(f), to.join(f)).unwrap();
    }
    to.to_path_buf()
}

/// angles.csv as `column -> cells` (cells as written: 6 decimals, empty when undefined).
fn angles_csv(path: &Path) -> Vec<(String, Vec<String>)> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    header
        .iter()
        .enumerate()
        .map(|(c, h)| {
            (
                h.to_string(),
                rows.iter().map(|r| r[c].to_string()).collect(),
            )
        })
        .collect()
}

#[test]
fn the_page_saves_corrections_that_gait_kin_reproduces() {
    let work = tempfile::tempdir().unwrap();
    let run = copy_run(&work.path().join("run"));
    let server = Server::start(&[run.as_os_str()]);
    let plan = serde_json::json!({
        "step_to": 90,
        "frames_to_time": (90..111).collect::<Vec<_>>(),
        "swap": [120, 131],
        "event": { "frame": 60, "button": "#add-rhs", "expect": "right,heel_strike,60" },
        "drag": { "frame": 100, "name": "right_ankle", "dx": 14, "dy": -9 },
        "bad_swap": [125, 140],
    });
    let shots = work.path().join("browser");
    std::fs::create_dir_all(&shots).unwrap();
    in_browser(
        "browser.cjs",
        &[
            server.url.as_ref(),
            shots.as_os_str(),
            plan.to_string().as_ref(),
        ],
    );
    drop(server);
    let page = read_json(&shots.join("result.json"));
    eprintln!(
        "review timings (not asserted): recompute median {:.0} ms per change {} (server {}); frame from memory median {:.1} ms {}; first request median {:.1} ms {}",
        page["recompute_ms_median"].as_f64().unwrap(),
        page["timings"]["recompute_ms"],
        page["timings"]["server_ms"],
        page["frame_ms_median"].as_f64().unwrap(),
        page["timings"]["frame_ms"],
        page["first_frame_ms_median"].as_f64().unwrap(),
        page["timings"]["first_frame_ms"],
    );

    // What was saved is what the page shows after the reload: the swap, the event and the
    // dragged keypoint.
    let saved = gait_kin::Corrections::read(&run.join("corrections.toml")).unwrap();
    let shown: gait_kin::Corrections = serde_json::from_value(page["corrections"].clone()).unwrap();
    assert_eq!(saved, shown);
    assert_eq!(saved.swap.len(), 1);
    assert_eq!((saved.swap[0].first, saved.swap[0].last), (120, 131));
    assert_eq!(saved.event.len(), 1);
    assert_eq!(saved.keypoint.len(), 1);
    assert_eq!(
        (saved.keypoint[0].frame, saved.keypoint[0].name.as_str()),
        (100, "right_ankle")
    );

    // `gait kin --corrections` on the same keypoints and file gives the page's angles and events.
    let kin = work.path().join("kin");
    run_ok(
        gait()
            .args(["kin", "--fps", "30", "--keypoints"])
            .arg(run.join("keypoints.csv"))
            .arg("--config")
            .arg(run.join("run.json"))
            .arg("--corrections")
            .arg(run.join("corrections.toml"))
            .arg("--out")
            .arg(&kin)
            .args(["--set", "kinematics.frame_size=[1768, 994]"]),
    );
    let columns = angles_csv(&kin.join("angles.csv"));
    let first = page["first_frame"].as_u64().unwrap() as usize;
    let frames: Vec<usize> = columns[0].1.iter().map(|f| f.parse().unwrap()).collect();
    assert_eq!(frames[0], first);
    let mut compared = 0;
    for (name, cells) in &columns[2..] {
        let series = page["angles"][name].as_array().unwrap();
        assert_eq!(series.len(), cells.len(), "{name}");
        for (i, (v, cell)) in series.iter().zip(cells).enumerate() {
            let shown = v.as_f64().map_or(String::new(), |v| format!("{v:.6}"));
            assert_eq!(&shown, cell, "{name} at frame {}", first + i);
            compared += usize::from(!cell.is_empty());
        }
    }
    assert!(compared > 500, "only {compared} angle values to compare");
    let events: Vec<String> = std::fs::read_to_string(kin.join("events.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').take(3).collect::<Vec<_>>().join(","))
        .collect();
    let shown: Vec<String> = page["events"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| {
            format!(
                "{},{},{}",
                e["side"].as_str().unwrap(),
                e["event"].as_str().unwrap(),
                e["frame"]
            )
        })
        .collect();
    assert_eq!(shown, events);
    assert!(events.contains(&"right,heel_strike,60".to_string()));

    // The page's checklist, recomputed with the corrections, is the one `gait kin` writes.
    let mut r = csv::Reader::from_path(kin.join("checklist.csv")).unwrap();
    let written: Vec<(String, String, String)> = r
        .records()
        .map(|x| x.unwrap())
        .map(|x| (x[0].to_string(), x[1].to_string(), x[2].replace(' ', "_")))
        .collect();
    let shown: Vec<(String, String, String)> =
        serde_json::from_value(page["checklist"].clone()).unwrap();
    assert_eq!(shown, written);
    assert!(written.len() > 20, "{written:?}");
    let panel = page["checklist_panel"].as_str().unwrap();
    assert!(
        panel.contains("absent:"),
        "the checklist panel shows {panel:?}"
    );
}

#[test]
fn only_the_token_holder_gets_the_run_s_data_and_only_the_page_frames_and_data() {
    let work = tempfile::tempdir().unwrap();
    let run = copy_run(&work.path().join("run"));
    let server = Server::start(&[run.as_os_str()]);
    for target in [
        "/api/run",
        "/api/analysis",
        "/api/frame/50",
        "/api/run?token=0123",
    ] {
        let (status, _) = server.request("GET", target, "");
        assert_eq!(status, 403, "{target}");
    }
    // The page itself holds nothing of the run (a report's frame link opens it without the
    // token, which the page keeps in the browser for this address).
    let (status, page) = server.request("GET", "/?frame=90", "");
    assert_eq!(status, 200);
    assert!(
        !page.contains(&*run.to_string_lossy()) && !page.contains("\"config\""),
        "the tokenless page shows run data"
    );
    let (status, _) = server.request("POST", "/api/corrections", "{}");
    assert_eq!(status, 403);
    assert!(!run.join("corrections.toml").exists());
    assert_eq!(server.get("/").0, 200);
    assert_eq!(server.get("/api/frame/50").0, 200);
    for target in [
        "/run.json",
        "/keypoints.csv",
        "/api/frame/..%2Frun.json",
        "/api/frame/../../run.json",
        "/api/frame/5000",
        "/api/frame/50?kind=../run.json",
        "/api/frame/50?kind=regenerated",
    ] {
        let (status, body) = server.get(target);
        assert!(status >= 400, "{target} gave {status}: {body}");
        assert!(!body.contains("\"config\""), "{target}: {body}");
    }
    // A bad edit is refused with the entry named, and nothing is written.
    let (status, body) = server.request(
        "POST",
        &format!("/api/corrections?token={}", server.token()),
        r#"{"swap":[{"first":120,"last":131},{"first":125,"last":140}]}"#,
    );
    assert_eq!(status, 400);
    assert!(
        body.contains("[[swap]] #2") && body.contains("overlaps"),
        "{body}"
    );
    let (status, body) = server.request(
        "POST",
        &format!("/api/corrections?token={}", server.token()),
        r#"{"swap":[{"first":120,"last":131}],"colour":"red"}"#,
    );
    assert_eq!(status, 400);
    assert!(body.contains("colour"), "{body}");
    assert!(!run.join("corrections.toml").exists());
    let files: Vec<String> = std::fs::read_dir(&run)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .collect();
    assert_eq!(files.len(), 2, "{files:?}");
}

#[test]
fn a_run_without_its_video_shows_the_plots_and_says_why() {
    let work = tempfile::tempdir().unwrap();
    let run = copy_run(&work.path().join("run"));
    let manifest = run.join("run.json");
    let mut v = read_json(&manifest);
    v["input"]["path"] = serde_json::json!("moved.mp4");
    v["input"]["absolute_path"] = serde_json::json!(work.path().join("moved.mp4"));
    std::fs::write(&manifest, v.to_string()).unwrap();
    let server = Server::start(&[run.as_os_str()]);
    let (status, body) = server.get("/api/run");
    assert_eq!(status, 200);
    let data: serde_json::Value = serde_json::from_str(&body).unwrap();
    let why = data["no_video"].as_str().unwrap();
    assert!(
        why.contains("moved.mp4") && why.contains("--video"),
        "{why}"
    );
    let (status, body) = server.get("/api/frame/50");
    assert_eq!(status, 404);
    assert!(body.contains("moved.mp4"), "{body}");
    assert_eq!(server.get("/api/analysis").0, 200);
    // --video gives it back.
    drop(server);
    let video = sample_video();
    let server = Server::start(&[run.as_os_str(), "--video".as_ref(), video.as_os_str()]);
    assert_eq!(server.get("/api/frame/50").0, 200);
}

/// A `gait kin` folder opens as `gait review DIR` (the command its checklist prints), with the
/// keypoints, frame rate and settings of kin.json: the same events as the folder's events.csv,
/// and corrections saved in the folder.
#[test]
fn a_gait_kin_folder_opens_with_its_own_settings() {
    let work = tempfile::tempdir().unwrap();
    let keypoints =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/sample-subject/keypoints.csv");
    let out = work.path().join("kin");
    run_ok(
        gait()
            .args(["kin", "--fps", "30", "--keypoints"])
            .arg(&keypoints)
            .arg("--out")
            .arg(&out)
            .args(["--set", "kinematics.prosthetic_side=\"right\""])
            .args(["--set", "report.pdf=false"]),
    );
    let manifest = read_json(&out.join("kin.json"));
    assert_eq!(manifest["fps"], serde_json::json!(30.0));
    assert_eq!(
        manifest["config"]["kinematics"]["prosthetic_side"],
        serde_json::json!("right")
    );
    let events = std::fs::read_to_string(out.join("events.csv")).unwrap();
    let server = Server::start(&[out.as_os_str()]);
    let (status, body) = server.get("/api/analysis");
    assert_eq!(status, 200, "{body}");
    let data: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(
        data["events"].as_array().map(Vec::len),
        Some(events.lines().count() - 1),
        "{body}"
    );
    let (status, body) = server.request(
        "POST",
        &format!("/api/corrections?token={}", server.token()),
        r#"{"event":[{"side":"right","kind":"heel_strike","frame":60,"action":"add"}]}"#,
    );
    assert_eq!(status, 200, "{body}");
    assert!(out.join("corrections.toml").is_file());
}

#[test]
fn keypoints_and_a_video_without_a_run_folder() {
    let work = tempfile::tempdir().unwrap();
    let keypoints =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/sample-subject/keypoints.csv");
    let file = work.path().join("fixes.toml");
    let video = sample_video();
    let server = Server::start(&[
        "--keypoints".as_ref(),
        keypoints.as_os_str(),
        "--video".as_ref(),
        video.as_os_str(),
        "--fps".as_ref(),
        "30".as_ref(),
        "--corrections".as_ref(),
        file.as_os_str(),
    ]);
    let (status, body) = server.get("/api/run");
    assert_eq!(status, 200);
    let data: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert!(data["no_video"].is_null(), "{body}");
    assert_eq!(data["frame_size"], serde_json::json!([1768, 994]));
    let (status, body) = server.request(
        "POST",
        &format!("/api/corrections?token={}", server.token()),
        r#"{"event":[{"side":"right","kind":"heel_strike","frame":60,"action":"add"}]}"#,
    );
    assert_eq!(status, 200, "{body}");
    let saved = gait_kin::Corrections::read(&file).unwrap();
    assert_eq!(saved.event.len(), 1);
    assert_eq!(server.get("/api/frame/60").0, 200);
}

#[test]
fn bad_input_is_one_line() {
    let work = tempfile::tempdir().unwrap();
    let run = copy_run(&work.path().join("run"));
    std::fs::write(
        run.join("corrections.toml"),
        "[[swap]]\nfirst = 120\nlast = 131\n[[swap]]\nfirst = 125\nlast = 140\n",
    )
    .unwrap();
    fails_with(
        gait().arg("review").arg(&run),
        &["corrections.toml", "[[swap]] #2", "overlaps [[swap]] #1"],
    );
    std::fs::write(run.join("corrections.toml"), "[[swapp]]\nfirst = 1\n").unwrap();
    fails_with(
        gait().arg("review").arg(&run),
        &["corrections.toml", "swapp"],
    );
    fails_with(
        gait().arg("review").arg(work.path().join("nothing")),
        &["no such folder"],
    );
    fails_with(
        gait().arg("review").arg(work.path()),
        &["run.json", "gait run"],
    );
    // A visit folder (a clinician's first try): its passes are the run folders to review.
    let visit = work.path().join("visit");
    copy_run(&visit.join("passes/1-left"));
    std::fs::write(visit.join("visit.json"), "{}").unwrap();
    fails_with(
        gait().arg("review").arg(&visit),
        &["a visit folder", "gait review", "passes/1-left"],
    );
}

#[test]
fn a_zero_shot_run_shows_its_regenerated_frames() {
    // The tiny random SD 1.5 + ControlNet of gait-diffuse's fixtures: noise images, real wiring.
    let work = tempfile::tempdir().unwrap();
    let run = work.path().join("zs");
    let mut cmd = common::sample_run(&run, 150, 152);
    for s in common::tiny_controlnet_sets() {
        cmd.args(["--set", &s]);
    }
    run_ok(&mut cmd);
    let server = Server::start(&[run.as_os_str()]);
    let (status, body) = server.get("/api/run");
    assert_eq!(status, 200);
    let data: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(data["regenerated"], serde_json::json!([150, 151, 152]));
    let (status, png) = server.get("/api/frame/151?kind=regenerated");
    assert_eq!(status, 200);
    assert!(
        png.starts_with("\u{fffd}PNG"),
        "{:?}",
        &png[..8.min(png.len())]
    );
    assert_eq!(server.get("/api/frame/151").0, 200);
    assert_eq!(server.get("/api/frame/149?kind=regenerated").0, 404);
}

/// Saving corrections into a folder a `gait run` is writing (it reads corrections.toml at its
/// end) is refused at once, naming the run's pid; nothing is written.
#[test]
fn a_save_while_a_run_writes_the_folder_is_refused() {
    let work = tempfile::tempdir().unwrap();
    let run = copy_run(&work.path().join("run"));
    let server = Server::start(&[run.as_os_str()]);
    let mut writer = common::sample_run(&run, 40, 200)
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let lock = run.join(".gait.lock");
    let pid = writer.id().to_string();
    let start = std::time::Instant::now();
    while !std::fs::read_to_string(&lock).is_ok_and(|t| t.starts_with(&pid)) {
        assert!(
            start.elapsed().as_secs() < 60 && writer.try_wait().unwrap().is_none(),
            "the run never took the folder"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let (status, body) = server.request(
        "POST",
        &format!("/api/corrections?token={}", server.token()),
        r#"{"event":[{"side":"right","kind":"heel_strike","frame":60,"action":"add"}]}"#,
    );
    let _ = writer.kill();
    let _ = writer.wait();
    assert_eq!(status, 400, "{body}");
    assert!(body.contains(&pid) && body.contains("in use"), "{body}");
    assert!(!run.join("corrections.toml").exists());
}

/// A walk away from the camera (issue 38): the page gets the frontal measures instead of the
/// sagittal angles, and an event removed by hand is recomputed as for a side view.
#[test]
fn a_back_view_shows_its_frontal_measures_and_takes_corrections() {
    let work = tempfile::tempdir().unwrap();
    let keypoints = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data/frontal/gaitkit_pd_posterior/keypoints.csv");
    let file = work.path().join("fixes.toml");
    let server = Server::start(&[
        "--keypoints".as_ref(),
        keypoints.as_os_str(),
        "--fps".as_ref(),
        "150".as_ref(),
        "--corrections".as_ref(),
        file.as_os_str(),
        "--frame".as_ref(),
        "300".as_ref(),
    ]);
    // The page opens at the frame asked for (a checklist names `gait review RUN --frame N`).
    assert!(server.url.ends_with("&frame=300"), "{}", server.url);
    let (status, body) = server.get("/api/analysis");
    assert_eq!(status, 200, "{body}");
    let an: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(an["view"], "posterior");
    for key in [
        "left_pelvic_obliquity",
        "right_trunk_lean",
        "left_hip_adduction",
        "right_knee_varus",
    ] {
        let n = an["angles"][key]
            .as_array()
            .map_or(0, |v| v.iter().filter(|x| x.is_number()).count());
        assert!(n > 500, "{key}: {n} values");
    }
    assert!(an["angles"]["left_hip"].is_null());
    let strike = an["events"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["event"] == "heel_strike")
        .unwrap()
        .clone();
    let before = an["events"].as_array().unwrap().len();
    let (status, body) = server.request(
        "POST",
        &format!("/api/corrections?token={}", server.token()),
        &format!(
            r#"{{"event":[{{"side":{},"kind":"heel_strike","frame":{},"action":"remove"}}]}}"#,
            strike["side"], strike["frame"]
        ),
    );
    assert_eq!(status, 200, "{body}");
    let after: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(after["view"], "posterior");
    assert_eq!(after["events"].as_array().unwrap().len(), before - 1);
}

/// A checklist finding followed from the report into `gait review`: the frame link of a
/// report's finding opens the running review of that folder at its frame, the finding's row
/// marked in the page's checklist. The link cannot carry the session's token (the report is
/// written before the review starts): the page keeps it from the URL `gait review` printed.
#[test]
fn a_report_s_frame_link_opens_the_running_review_at_its_frame() {
    let work = tempfile::tempdir().unwrap();
    let out = work.path().join("kin");
    // A tight normative band (0.2 SD) makes a finding of the sample's healthy walk.
    run_ok(
        gait()
            .args(["kin", "--keypoints"])
            .arg(sample_run().join("keypoints.csv"))
            .arg("--out")
            .arg(&out)
            .args([
                "--set",
                "checklist.norm_sd=0.2",
                "--set",
                "report.pdf=false",
            ]),
    );
    let report = std::fs::read_to_string(out.join("report.html")).unwrap();
    let link = report
        .split("class=\"review-link\" href=\"")
        .nth(1)
        .and_then(|rest| rest.split('"').next())
        .unwrap_or_else(|| panic!("no frame link in the report's checklist"));
    let frame: usize = link.split("frame=").nth(1).unwrap().parse().unwrap();

    let server = Server::start(&[out.as_os_str()]);
    assert!(
        link.starts_with(&format!("http://{}/", server.addr())),
        "the report links to {link}, the review serves {}",
        server.url
    );
    // Without the token the page loads but none of the run's data does.
    assert_eq!(
        server.request("GET", &format!("/?frame={frame}"), "").0,
        200
    );
    assert_eq!(server.request("GET", "/api/run", "").0, 403);

    let result = work.path().join("link.json");
    in_browser(
        "link.cjs",
        &[server.url.as_ref(), link.as_ref(), result.as_os_str()],
    );
    let shown = read_json(&result);
    assert_eq!(shown["frame"], serde_json::json!(frame), "{shown}");
    assert_ne!(shown["opened"], serde_json::json!(frame), "{shown}");
    assert!(
        shown["marked"].as_array().is_some_and(|m| !m.is_empty()),
        "no checklist row marked at frame {frame}: {shown}"
    );
    assert_eq!(shown["problems"], serde_json::json!([]), "{shown}");
}
