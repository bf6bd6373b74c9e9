//! The subject pass on scenes built from the sample video's real frames:
//! two people crossing, the subject leaving and coming back, someone else
//! entering while the subject is gone, a walk with a turn, a part standing
//! still. Each scene is composited here (time-reversed, repeated, mirrored,
//! scaled and overlaid copies of the sample's frames, at half size) and run
//! through `gait run` with the default pipeline.

mod common;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use common::{read_json, run_ok, run_on, sample_video};
use image::{RgbImage, imageops};

/// The sample's frames at half size (884x497), decoded once.
fn frames() -> &'static [RgbImage] {
    static FRAMES: OnceLock<Vec<RgbImage>> = OnceLock::new();
    FRAMES.get_or_init(|| {
        let info = gait_pipeline::input::InputInfo::open(&sample_video()).unwrap();
        let mut reader = info.frames().unwrap();
        let mut out = Vec::new();
        while let Some(f) = reader.next_frame().unwrap() {
            out.push(imageops::resize(
                &f.image,
                884,
                497,
                imageops::FilterType::Triangle,
            ));
        }
        out
    })
}

fn range(a: usize, b: usize) -> Vec<RgbImage> {
    frames()[a..=b].to_vec()
}

fn reversed(a: usize, b: usize) -> Vec<RgbImage> {
    range(a, b).into_iter().rev().collect()
}

/// `img` mirrored, scaled by `s` and pasted bottom-centred on the frame
/// `onto` (another person of another size, entering where the subject is not).
fn mirrored_small(img: &RgbImage, onto: &RgbImage, s: f32) -> RgbImage {
    let flipped = imageops::flip_horizontal(img);
    let (w, h) = (img.width(), img.height());
    let small = imageops::resize(
        &flipped,
        (w as f32 * s) as u32,
        (h as f32 * s) as u32,
        imageops::FilterType::Triangle,
    );
    let mut out = onto.clone();
    imageops::overlay(
        &mut out,
        &small,
        i64::from((w - small.width()) / 2),
        i64::from(h - small.height()),
    );
    out
}

/// `a + b - background`, pixel by pixel: both frames' people over the
/// shared background of a fixed camera.
fn overlaid(a: &RgbImage, b: &RgbImage, background: &RgbImage) -> RgbImage {
    RgbImage::from_fn(a.width(), a.height(), |x, y| {
        let (p, q, r) = (
            a.get_pixel(x, y).0,
            b.get_pixel(x, y).0,
            background.get_pixel(x, y).0,
        );
        image::Rgb(std::array::from_fn(|k| {
            (i32::from(p[k]) + i32::from(q[k]) - i32::from(r[k])).clamp(0, 255) as u8
        }))
    })
}

/// Writes `scene` as numbered PNGs and runs the default pipeline on them.
fn run_scene(name: &str, scene: &[RgbImage], root: &Path) -> (PathBuf, serde_json::Value) {
    let dir = root.join(name);
    std::fs::create_dir_all(&dir).unwrap();
    for (i, img) in scene.iter().enumerate() {
        img.save(dir.join(format!("{i:04}.png"))).unwrap();
    }
    let out = root.join(format!("{name}-run"));
    run_ok(run_on(&dir, &out).args(["--set", "input.fps=30"]));
    let run = read_json(&out.join("run.json"));
    (out, run)
}

/// The walker's mid-hip x in each frame of the sample video.
fn walker_x() -> Vec<Option<f64>> {
    mid_hip_x(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../tests/data/sample-subject/keypoints.csv"),
    )
}

/// The subject's mid-hip x per scene frame (`None`: not in view).
fn subject_x(out: &Path) -> Vec<Option<f64>> {
    mid_hip_x(&out.join("keypoints.csv"))
}

fn mid_hip_x(csv: &Path) -> Vec<Option<f64>> {
    let text = std::fs::read_to_string(csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let col = lines[1].split(',').position(|c| c == "mid_hip").unwrap();
    lines[3..]
        .iter()
        .map(|l| l.split(',').nth(col).and_then(|c| c.parse().ok()))
        .collect()
}

fn bouts(run: &serde_json::Value) -> Vec<(u64, u64, String)> {
    run["extra"]["kinematics"]["bouts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| {
            (
                b["first"].as_u64().unwrap(),
                b["last"].as_u64().unwrap(),
                b["direction"].as_str().unwrap().to_string(),
            )
        })
        .collect()
}

fn chosen_track(run: &serde_json::Value) -> serde_json::Value {
    let s = &run["subject"];
    let id = s["chosen"].as_u64().unwrap();
    s["tracks"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["id"].as_u64() == Some(id))
        .unwrap()
        .clone()
}

/// Every scene in one test: the frames are decoded once, and the scenes run
/// one after the other (each is a full `gait run`).
#[test]
fn subject_and_bouts_on_scenes_made_of_real_frames() {
    // GAIT_SCENES_DIR keeps the scenes and their runs there, to look at.
    let temp = tempfile::tempdir().unwrap();
    let kept = std::env::var_os("GAIT_SCENES_DIR").map(PathBuf::from);
    let root = kept.as_deref().unwrap_or(temp.path());

    // Two people crossing: the walker (frames 60-190, walking left) and a
    // time-reversed copy of her (walking right, 90 frames) overlaid on the
    // same background; they cross mid-way. The subject (the longer walk)
    // keeps walking left: her hips never jump to the other one.
    let background = &frames()[10];
    let a = range(60, 190);
    let b = reversed(100, 190);
    let crossing: Vec<RgbImage> = a
        .iter()
        .enumerate()
        .map(|(i, f)| match b.get(i) {
            Some(g) => overlaid(f, g, background),
            None => f.clone(),
        })
        .collect();
    let (out, run) = run_scene("crossing", &crossing, root);
    // Where each walker's hips are, from the whole-video run of the sample
    // (tests/data/sample-subject), at half size.
    let known = walker_x();
    let at = |f: usize| known[f].map(|x| x / 2.0);
    let mut sides = (0, 0);
    for (i, x) in subject_x(&out).into_iter().enumerate() {
        let (Some(x), Some(xa), Some(xb)) = (x, at(60 + i), b.get(i).and(at(190 - i))) else {
            continue;
        };
        // Near the crossing the two bodies overlap (hips closer than about
        // a third of a body size) and cannot be told apart by position.
        if (xa - xb).abs() < 130.0 {
            continue;
        }
        if (x - xa).abs() < (x - xb).abs() {
            sides.0 += 1;
        } else {
            sides.1 += 1;
        }
    }
    // Followed apart from the crossing in at least 15 frames (18 with the linker of
    // 2026-12-04, 25 or more before: the walker is now taken up later after the crossing).
    assert!(sides.0 + sides.1 > 15, "{sides:?}");
    assert!(
        sides.0.min(sides.1) <= 2,
        "the subject changes between the two walkers: {sides:?}"
    );
    assert!(run["subject"]["tracks"].as_array().unwrap().len() >= 2);

    // Leaving and coming back: she walks out at the left edge (60-199), the
    // view without her (200-229: the man runs), then she walks back in from
    // the left (time-reversed 199-100). One track, taken up again by her.
    let mut scene = range(60, 199);
    scene.extend(range(200, 229));
    scene.extend(reversed(100, 199));
    let (out, run) = run_scene("comes-back", &scene, root);
    let xs = subject_x(&out);
    let track = chosen_track(&run);
    assert!(
        track["first_frame"].as_u64().unwrap() < 60 && track["last_frame"].as_u64().unwrap() > 200,
        "{track}"
    );
    assert!(
        xs[150..165].iter().all(Option::is_none),
        "nobody is followed while she is gone"
    );
    assert!(xs[60..100].iter().any(Option::is_some) && xs[200..240].iter().any(Option::is_some));

    // Someone else entering while the subject is gone: after she has left
    // (60-192), a smaller, mirrored person walks in. Not the subject.
    let mut scene = range(60, 192);
    let empty_view = &frames()[215];
    scene.extend((60..=140).map(|f| mirrored_small(&frames()[f], empty_view, 0.6)));
    let (out, run) = run_scene("someone-else", &scene, root);
    let xs = subject_x(&out);
    assert!(
        chosen_track(&run)["last_frame"].as_u64().unwrap() <= 133,
        "{}",
        chosen_track(&run)
    );
    assert!(
        xs[140..].iter().all(Option::is_none),
        "the other person is never the subject"
    );
    assert!(run["subject"]["tracks"].as_array().unwrap().len() >= 2);

    // A walk with a turn: left (100-170), then back to the right (the same
    // frames time-reversed). Two bouts, one each way, none across the turn.
    let mut scene = range(100, 170);
    scene.extend(reversed(100, 170));
    let (_, run) = run_scene("turn", &scene, root);
    let b = bouts(&run);
    assert!(
        b.iter().any(|x| x.2 == "left" && x.1 <= 72)
            && b.iter().any(|x| x.2 == "right" && x.0 >= 69),
        "{b:?}"
    );
    assert!(
        b.iter().all(|x| x.1 <= 72 || x.0 >= 69),
        "a bout across the turn: {b:?}"
    );

    // A part standing still: walking (100-140), 1.5 s on frame 140, walking
    // on (141-185). The standing part is in no bout.
    let mut scene = range(100, 140);
    scene.extend(std::iter::repeat_n(frames()[140].clone(), 45));
    scene.extend(range(141, 185));
    let (_, run) = run_scene("standing", &scene, root);
    let b = bouts(&run);
    assert!(!b.is_empty(), "{b:?}");
    assert!(
        b.iter().all(|x| x.1 <= 50 || x.0 >= 76),
        "a bout through the standing part: {b:?}"
    );
}
