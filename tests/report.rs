//! The clinical outputs of a real run on the whole sample video: overlay.mp4
//! (ffprobe), keypoints.c3d (read back by ezc3d), report.html in headless
//! Chromium (no broken image, every section, no overlapping boxes, from the
//! page's own layout), report.pdf (A4), scores in run.json, `gait export`.
//! Needs ffmpeg, Chromium and the ezc3d venv (tools/setup.sh installs them);
//! fails, saying so, when one is missing.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use common::{fails_with, gait, read_json, run_ok, run_on, sample_video};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// One full run with every output on, shared by the tests of this file.
fn sample_run() -> &'static Path {
    static RUN: OnceLock<PathBuf> = OnceLock::new();
    RUN.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("gait-report-test-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        run_ok(run_on(&sample_video(), &dir).args([
            "--set",
            "report.overlay=true",
            "--set",
            "report.pdf=true",
            "--set",
            "export.formats=[\"c3d\",\"trc\",\"mot\",\"openpose\"]",
        ]));
        dir
    })
}

fn tool(cmd: &str, args: &[&str]) -> String {
    let out = Command::new(cmd)
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("{cmd} is needed (tools/setup.sh installs it): {e}"));
    assert!(
        out.status.success(),
        "{cmd} {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).to_string()
}

/// ffprobe's `entries` of the first video stream of `file`, in output format `of`
/// (`count`: decode every frame so `nb_read_frames` is exact).
fn ffprobe(file: &str, entries: &str, of: &str, count: bool) -> String {
    let mut args = vec![
        "-v",
        "error",
        "-select_streams",
        "v:0",
        "-show_entries",
        entries,
        "-of",
        of,
        file,
    ];
    if count {
        args.insert(2, "-count_frames");
    }
    tool("ffprobe", &args)
}

/// Input frames with a row in a DeepLabCut CSV (after its 3 header lines).
fn csv_frames(path: &Path) -> Vec<usize> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(3)
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .collect()
}

#[test]
fn overlay_has_one_frame_per_analysed_frame_and_decodes() {
    let run = sample_run();
    let video = run.join("overlay.mp4");
    let probe = ffprobe(
        video.to_str().unwrap(),
        "stream=nb_read_frames,codec_name,r_frame_rate",
        "csv=p=0",
        true,
    );
    let analysed = csv_frames(&run.join("keypoints.csv")).len();
    let fields: Vec<&str> = probe.trim().split(',').collect();
    assert_eq!(
        fields,
        ["h264", "30/1", &analysed.to_string()],
        "ffprobe: {probe}"
    );
    let out = Command::new("ffmpeg")
        .args([
            "-v",
            "error",
            "-i",
            video.to_str().unwrap(),
            "-f",
            "null",
            "-",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success() && out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn ezc3d(file: &Path) -> serde_json::Value {
    let py = tool(
        "bash",
        &[repo().join("tools/export/setup_ezc3d.sh").to_str().unwrap()],
    );
    let json = tool(
        py.trim(),
        &[
            repo().join("tools/export/check_c3d.py").to_str().unwrap(),
            file.to_str().unwrap(),
        ],
    );
    serde_json::from_str(&json).unwrap()
}

#[test]
fn c3d_reads_back_in_ezc3d_as_the_filtered_keypoints_and_events() {
    let run = sample_run();
    let c3d = ezc3d(&run.join("keypoints.c3d"));
    let csv = std::fs::read_to_string(run.join("keypoints_filtered.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    // DeepLabCut layout: scorer, bodyparts, coords (x, y, likelihood) rows.
    let parts: Vec<&str> = lines[1].split(',').skip(1).step_by(3).collect();
    let labels: Vec<&str> = c3d["labels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l.as_str().unwrap())
        .collect();
    assert_eq!(labels, parts);
    assert_eq!(c3d["units"], "px");
    assert_eq!(c3d["rate"].as_f64(), Some(30.0));
    assert_eq!(c3d["analog_channels"].as_u64(), Some(0));
    let rows: Vec<Vec<&str>> = lines[3..].iter().map(|l| l.split(',').collect()).collect();
    assert_eq!(
        c3d["first_frame"].as_u64(),
        Some(rows[0][0].parse::<u64>().unwrap() + 1)
    );
    let mut worst = 0.0f64;
    let mut compared = 0;
    for (m, _) in parts.iter().enumerate() {
        for (f, row) in rows.iter().enumerate() {
            let p = &c3d["points"][m][f];
            let (x, y) = (row[1 + 3 * m], row[2 + 3 * m]);
            if x.is_empty() {
                assert!(
                    p[0].is_null(),
                    "marker {m} frame {f} is missing in the CSV but not in the c3d"
                );
                continue;
            }
            let (x, y): (f64, f64) = (x.parse().unwrap(), y.parse().unwrap());
            worst = worst
                .max((p[0].as_f64().unwrap() - x).abs())
                .max((p[1].as_f64().unwrap() - y).abs());
            assert_eq!(p[2].as_f64(), Some(0.0));
            compared += 1;
        }
    }
    assert!(
        compared > 1000 && worst <= 1e-4,
        "{compared} values, worst {worst}"
    );
    let events = std::fs::read_to_string(run.join("events.csv")).unwrap();
    let want: Vec<(String, String, f64)> = events
        .lines()
        .skip(1)
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            let context = if c[0] == "left" { "Left" } else { "Right" };
            let label = if c[1] == "heel_strike" {
                "Foot Strike"
            } else {
                "Foot Off"
            };
            (
                context.into(),
                label.into(),
                c[2].parse::<f64>().unwrap() / 30.0,
            )
        })
        .collect();
    let got: Vec<(String, String, f64)> = c3d["events"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| {
            (
                e["context"].as_str().unwrap().into(),
                e["label"].as_str().unwrap().into(),
                e["time_s"].as_f64().unwrap(),
            )
        })
        .collect();
    assert_eq!(got.len(), want.len());
    for (g, w) in got.iter().zip(&want) {
        assert_eq!((&g.0, &g.1), (&w.0, &w.1));
        // Exact up to the float32 a c3d stores.
        assert_eq!(g.2, f64::from(w.2 as f32), "{g:?} vs {w:?}");
    }
}

/// The page's own layout, measured by a script added to a copy of the page
/// and read back from Chromium's DOM dump.
const LAYOUT_CHECK: &str = r#"<script>
window.addEventListener('load', () => {
  const r = { broken: [], overlaps: [], ids: [...document.querySelectorAll('[id]')].map(e => e.id) };
  for (const img of document.images) if (!img.complete || img.naturalWidth === 0) r.broken.push(img.alt || img.src.slice(0, 40));
  const boxes = (els) => els.map(e => [e, e.getBoundingClientRect()]).filter(([, b]) => b.width > 0 && b.height > 0);
  const check = (els) => {
    const b = boxes(els);
    for (let i = 0; i < b.length; i++) for (let j = i + 1; j < b.length; j++) {
      const [p, q] = [b[i][1], b[j][1]];
      const w = Math.min(p.right, q.right) - Math.max(p.left, q.left);
      const h = Math.min(p.bottom, q.bottom) - Math.max(p.top, q.top);
      if (w > 1 && h > 1) r.overlaps.push(b[i][0].tagName + '#' + b[i][0].id + ' / ' + b[j][0].tagName + '#' + b[j][0].id);
    }
  };
  check([...document.body.children].filter(e => e.tagName !== 'SCRIPT' && e.tagName !== 'PRE' || e.id !== 'layout'));
  for (const f of document.querySelectorAll('figure, li, tr')) check([...f.children]);
  const out = document.createElement('pre'); out.id = 'layout'; out.textContent = 'LAYOUT' + JSON.stringify(r) + 'END';
  document.body.appendChild(out);
});
</script>"#;

fn layout_of(page: &Path, work: &Path) -> serde_json::Value {
    let html = std::fs::read_to_string(page)
        .unwrap()
        .replace("</body>", &format!("{LAYOUT_CHECK}</body>"));
    let copy = page.with_file_name("layout-check.html");
    std::fs::write(&copy, html).unwrap();
    let chromium = gait_eval_chromium();
    let out = Command::new(chromium)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--window-size=1400,1000",
            "--virtual-time-budget=10000",
            "--dump-dom",
        ])
        .arg(format!(
            "--user-data-dir={}",
            work.join("profile").display()
        ))
        .arg(format!("file://{}", copy.canonicalize().unwrap().display()))
        .output()
        .unwrap();
    let _ = std::fs::remove_file(&copy);
    let dom = String::from_utf8_lossy(&out.stdout);
    let start = dom.find("LAYOUT{").unwrap_or_else(|| {
        panic!(
            "no layout result in the DOM: {}",
            String::from_utf8_lossy(&out.stderr)
        )
    });
    let end = dom[start..].find("}END").unwrap() + start + 1;
    serde_json::from_str(
        &dom[start + 6..end]
            .replace("&quot;", "\"")
            .replace("&amp;", "&"),
    )
    .unwrap()
}

fn gait_eval_chromium() -> PathBuf {
    gait_report::pdf::find_chromium()
        .expect("headless Chromium is needed: apt-get install chromium (tools/setup.sh does)")
}

#[test]
fn report_in_chromium_has_every_section_no_broken_image_and_no_overlap() {
    let run = sample_run();
    let work = tempfile::tempdir().unwrap();
    let r = layout_of(&run.join("report.html"), work.path());
    let ids: Vec<&str> = r["ids"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    for id in [
        "gait-graphs",
        "fig-gait_graphs",
        "consistency",
        "fig-consistency",
        "scores",
        "fig-map",
        "spatiotemporal",
        "overlay",
        "fig-skeleton",
        "files",
    ] {
        assert!(
            ids.contains(&id),
            "section {id} missing; the page has {ids:?}"
        );
    }
    assert_eq!(r["broken"], serde_json::json!([]), "broken images");
    assert_eq!(r["overlaps"], serde_json::json!([]), "overlapping boxes");

    // The check can fail: two boxes placed on top of each other are found.
    let bad = work.path().join("bad.html");
    std::fs::write(&bad, "<html><body><p style=\"position:absolute;top:0\">a</p><p style=\"position:absolute;top:0\">b</p><img style=\"position:absolute;top:300px\" src=\"missing.png\" alt=\"gone\"></body></html>").unwrap();
    let r = layout_of(&bad, work.path());
    assert_eq!(r["broken"], serde_json::json!(["gone"]));
    assert_eq!(r["overlaps"].as_array().unwrap().len(), 1, "{r}");
}

/// pdftotext of one page, with a header cell broken after an underscore joined again.
fn pdf_page(pdf: &Path, page: usize) -> String {
    let n = page.to_string();
    let pdf = pdf.to_str().unwrap();
    tool("pdftotext", &["-f", &n, "-l", &n, pdf, "-"]).replace("_\n", "_")
}

#[test]
fn pdf_pages_fit_every_table_column_and_end_with_a_short_provenance() {
    let run = sample_run();
    let pdf = run.join("report.pdf");
    let info = tool("pdfinfo", &[pdf.to_str().unwrap()]);
    let pages: usize = info
        .lines()
        .find_map(|l| l.strip_prefix("Pages:"))
        .and_then(|n| n.trim().parse().ok())
        .expect("pdfinfo gives the page count");
    // Kinematics, scores, parameters and tables of the sample run: 4 pages; the run.json
    // dump once made it 10.
    assert!((3..=5).contains(&pages), "{pages} pages");
    let texts: Vec<String> = (1..=pages).map(|p| pdf_page(&pdf, p)).collect();
    for (file, title) in [
        (
            "cycle_quality.csv",
            "Cycle quality: every cycle found, kept or rejected",
        ),
        ("bouts.csv", "Walking bouts"),
        ("events.csv", "Gait events"),
    ] {
        let csv = std::fs::read_to_string(run.join(file)).unwrap();
        let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
        let page = texts
            .iter()
            .position(|t| t.lines().any(|l| l.trim() == title))
            .unwrap_or_else(|| panic!("no page has the table {title}"));
        for column in header {
            // A name broken after an underscore may come out of the page interleaved with its
            // neighbour's (`stride_ stride_` / `s deviation`): then each part must be there.
            let whole = texts[page].contains(column);
            let parts = column.split('_').all(|p| texts[page].contains(p));
            assert!(
                whole || parts,
                "page {}: the column {column} of {title} is cut off:\n{}",
                page + 1,
                texts[page]
            );
        }
    }
    let all = texts.concat();
    assert!(
        !all.contains("keypoint_names"),
        "the manifest is not printed"
    );
    let last = &texts[pages - 1];
    let tool_version = format!("gait {}", env!("CARGO_PKG_VERSION"));
    for want in [
        "Provenance",
        &tool_version,
        "Config sha256",
        "Input sha256",
        "run.json",
    ] {
        assert!(last.contains(want), "{want} not on the last page:\n{last}");
    }
    let m = read_json(&run.join("run.json"));
    assert!(last.contains(m["input"]["sha256"].as_str().unwrap()));
}

#[test]
fn pdf_scores_and_exports_are_written() {
    let run = sample_run();
    let pdf = std::fs::read(run.join("report.pdf")).unwrap();
    assert!(pdf.starts_with(b"%PDF"), "report.pdf is a PDF");
    let text = String::from_utf8_lossy(&pdf);
    // A4 is 595 x 842 points.
    assert!(
        text.contains("/MediaBox [0 0 594.95996 841.91998]") || text.contains("/MediaBox [0 0 595"),
        "A4 pages"
    );
    let m = read_json(&run.join("run.json"));
    let gps = m["report"]["scores"]["gps"].as_array().unwrap();
    assert_eq!(
        gps.len(),
        3,
        "left, right and overall sagittal GPS: {gps:?}"
    );
    assert!(gps.iter().all(|g| g["value"].as_f64().unwrap() > 0.0));
    assert_eq!(m["report"]["normative"], "schwartz2008_free");
    assert!(
        std::fs::read_to_string(run.join("scores.csv"))
            .unwrap()
            .starts_with("score,side,joint,value,unit\n")
    );
    let frames = csv_frames(&run.join("keypoints_filtered.csv")).len();
    assert_eq!(
        std::fs::read_dir(run.join("openpose")).unwrap().count(),
        frames
    );
    for f in ["keypoints.trc", "angles.mot"] {
        assert!(run.join(f).is_file(), "{f}");
    }

    // `gait export` rewrites one format for the earlier run, and says what is wrong.
    std::fs::remove_file(run.join("keypoints.trc")).unwrap();
    run_ok(gait().args(["export"]).arg(run).args(["--format", "trc"]));
    assert!(run.join("keypoints.trc").is_file());
    fails_with(
        gait().args(["export"]).arg(run).args(["--format", "xlsx"]),
        &["xlsx", "c3d, trc, mot, openpose"],
    );
    let empty = tempfile::tempdir().unwrap();
    fails_with(gait().args(["export"]).arg(empty.path()), &["give --fps"]);
}

#[test]
fn an_ffmpeg_without_libx264_falls_back_to_mpeg4_with_a_warning() {
    let work = tempfile::tempdir().unwrap();
    // A real ffmpeg that hides libx264 from its encoder list, as a build without it would.
    let bin = work.path().join("bin");
    std::fs::create_dir(&bin).unwrap();
    let real = tool("bash", &["-c", "command -v ffmpeg"]);
    let shim = bin.join("ffmpeg");
    std::fs::write(
        &shim,
        format!(
            "#!/bin/sh\ncase \" $* \" in *\" -encoders \"*) {0} \"$@\" | grep -v libx264 ;; *) exec {0} \"$@\" ;; esac\n",
            real.trim()
        ),
    )
    .unwrap();
    tool("chmod", &["+x", shim.to_str().unwrap()]);
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap());
    let out = work.path().join("run");
    let res = run_ok(
        common::sample_run(&out, 100, 130)
            .env("PATH", path)
            .args(["--set", "report.overlay=true"]),
    );
    let err = String::from_utf8_lossy(&res.stderr);
    assert!(
        err.contains("warning:") && err.contains("mpeg4") && err.contains("libx264"),
        "{err}"
    );
    let codec = ffprobe(
        out.join("overlay.mp4").to_str().unwrap(),
        "stream=codec_name",
        "csv=p=0",
        false,
    );
    assert_eq!(codec.trim(), "mpeg4");
}

#[test]
fn zero_shot_overlay_side_by_side_shows_the_regenerated_frames() {
    let work = tempfile::tempdir().unwrap();
    let out = work.path().join("run");
    let mut cmd = common::sample_run(&out, 100, 109);
    for s in common::tiny_controlnet_sets() {
        cmd.args(["--set", &s]);
    }
    run_ok(cmd.args([
        "--set",
        "report.overlay=true",
        "--set",
        "report.overlay_layout=\"side_by_side\"",
    ]));
    let video = out.join("overlay.mp4");
    let probe = ffprobe(
        video.to_str().unwrap(),
        "stream=width,height,nb_read_frames",
        "default=nw=1",
        true,
    );
    assert!(probe.contains("nb_read_frames=10"), "{probe}");
    // Three panels of the 1768x994 input, each halved (the input is wider than 1280 px).
    assert!(
        probe.contains("width=2652") && probe.contains("height=498"),
        "{probe}"
    );
    // The middle panel is the regenerated image (the tiny random model draws noise), not the original.
    let png = work.path().join("f.png");
    tool(
        "ffmpeg",
        &[
            "-v",
            "error",
            "-i",
            video.to_str().unwrap(),
            "-vframes",
            "1",
            png.to_str().unwrap(),
        ],
    );
    let img = image::open(&png).unwrap().to_rgb8();
    let diff: u64 = (0..img.height())
        .step_by(4)
        .flat_map(|y| (0..884).step_by(4).map(move |x| (x, y)))
        .map(|(x, y)| {
            let (a, b) = (img.get_pixel(x, y).0, img.get_pixel(x + 884, y).0);
            a.iter()
                .zip(b)
                .map(|(p, q)| u64::from(p.abs_diff(q)))
                .sum::<u64>()
        })
        .sum();
    let n = u64::from(img.height() / 4) * 221 * 3;
    assert!(
        diff / n > 20,
        "mean difference original vs regenerated panel {}",
        diff / n
    );
}
