//! Encodes synthetic frames through the real ffmpeg and checks the result
//! with ffprobe: frame count, codec, rate, and a clean full decode.

use std::path::Path;
use std::process::Command;

use gait_core::{Keypoint, Pose};
use gait_overlay::{
    Backdrop, Encoder, EventKind, EventMark, FrameMarks, Layout, OverlayOptions, OverlayWriter,
    Side,
};
use image::{Rgb, RgbImage};

const FRAMES: usize = 40;

fn names() -> Vec<String> {
    gait_core::CANONICAL.iter().map(|s| s.to_string()).collect()
}

/// A gradient that moves, so the encoder has something to do.
fn frame(w: u32, h: u32, i: usize) -> RgbImage {
    RgbImage::from_fn(w, h, |x, y| {
        Rgb([(x as usize + i * 3) as u8, (y as usize * 2) as u8, 128])
    })
}

/// Legs that swing a little; heel strikes and dimming on some frames.
fn marks(w: u32, h: u32, i: usize) -> FrameMarks {
    let n = names();
    let mut pose = Pose::empty(n.len());
    let (w, h) = (f64::from(w), f64::from(h));
    let swing = (i as f64 * 0.3).sin() * w * 0.05;
    for (name, x, y) in [
        ("mid_hip", 0.5, 0.4),
        ("left_hip", 0.45, 0.4),
        ("right_hip", 0.55, 0.4),
        ("left_knee", 0.45, 0.6),
        ("right_knee", 0.55, 0.6),
        ("left_ankle", 0.45, 0.8),
        ("right_ankle", 0.55, 0.8),
        ("left_heel", 0.44, 0.85),
        ("right_heel", 0.54, 0.85),
        ("left_toe", 0.48, 0.86),
        ("right_toe", 0.58, 0.86),
    ] {
        let k = n.iter().position(|m| m == name).unwrap();
        let dx = if name.starts_with("left") {
            swing
        } else {
            -swing
        };
        pose.keypoints[k] = Keypoint::new(x * w + dx, y * h, 0.9);
    }
    FrameMarks {
        frame: i,
        time_s: i as f64 / 30.0,
        pose: (i % 7 != 3).then_some(pose),
        events: (i % 10 < 4)
            .then_some(EventMark {
                side: if i % 20 < 10 { Side::Left } else { Side::Right },
                kind: EventKind::HeelStrike,
                age_frames: i % 10,
            })
            .into_iter()
            .collect(),
        dim: (i < 5).then(|| "outside walking bout".to_string()),
    }
}

fn encode(path: &Path, w: u32, h: u32, fps: f64, opts: &OverlayOptions) -> (u32, u32) {
    let (mut wr, warnings) = OverlayWriter::start(path, w, h, fps, &names(), opts).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    for i in 0..FRAMES {
        let img = frame(w, h, i);
        let regen = (i % 2 == 0).then(|| frame(w / 2, h / 2, i + 50));
        wr.push(&img, regen.as_ref(), &marks(w, h, i)).unwrap();
    }
    let size = wr.output_size();
    assert!(!path.exists(), "the final name appears only on finish");
    assert_eq!(wr.finish().unwrap(), path);
    size
}

/// (frames, codec, rate, width, height) as ffprobe reports them.
fn probe(path: &Path) -> (usize, String, String, u32, u32) {
    let out = Command::new("ffprobe")
        .args([
            "-v",
            "error",
            "-count_frames",
            "-select_streams",
            "v:0",
            "-show_entries",
            "stream=nb_read_frames,codec_name,r_frame_rate,width,height",
            "-of",
            "default=nw=1",
        ])
        .arg(path)
        .output()
        .expect("ffprobe must be installed for these tests");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let get = |k: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(&format!("{k}=")))
            .unwrap_or_else(|| panic!("no {k} in {text}"))
            .to_string()
    };
    (
        get("nb_read_frames").parse().unwrap(),
        get("codec_name"),
        get("r_frame_rate"),
        get("width").parse().unwrap(),
        get("height").parse().unwrap(),
    )
}

fn decodes_cleanly(path: &Path) {
    let out = Command::new("ffmpeg")
        .args(["-v", "error", "-i"])
        .arg(path)
        .args(["-f", "null", "-"])
        .output()
        .unwrap();
    assert!(out.status.success());
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn check(w: u32, h: u32, fps: f64, rate: &str, opts: OverlayOptions, codec: &str) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("overlay.mp4");
    let (ow, oh) = encode(&path, w, h, fps, &opts);
    assert_eq!((ow % 2, oh % 2), (0, 0));
    let (n, c, r, pw, ph) = probe(&path);
    assert_eq!(n, FRAMES, "{w}x{h} {opts:?}");
    assert_eq!(c, codec);
    assert_eq!(r, rate);
    assert_eq!((pw, ph), (ow, oh));
    decodes_cleanly(&path);
    // Nothing but the result is left in the folder.
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(left.len(), 1);
}

fn side_by_side(backdrop: Backdrop) -> OverlayOptions {
    OverlayOptions {
        layout: Layout::SideBySide { backdrop },
        ..OverlayOptions::default()
    }
}

#[test]
fn skeleton_layout_is_h264_at_the_input_rate() {
    check(320, 240, 30.0, "30/1", OverlayOptions::default(), "h264");
}

#[test]
fn odd_sizes_are_padded_to_even() {
    check(321, 241, 25.0, "25/1", OverlayOptions::default(), "h264");
    check(
        322,
        183,
        30000.0 / 1001.0,
        "30000/1001",
        OverlayOptions::default(),
        "h264",
    );
}

#[test]
fn side_by_side_layout_encodes() {
    check(320, 240, 30.0, "30/1", side_by_side(Backdrop::Dark), "h264");
    check(
        321,
        241,
        30.0,
        "30/1",
        side_by_side(Backdrop::Original),
        "h264",
    );
}

#[test]
fn mpeg4_can_be_forced() {
    let opts = OverlayOptions {
        encoder: Encoder::Mpeg4,
        ..OverlayOptions::default()
    };
    check(320, 240, 30.0, "30/1", opts, "mpeg4");
    let opts = OverlayOptions {
        encoder: Encoder::Mpeg4,
        ..side_by_side(Backdrop::Dark)
    };
    check(321, 241, 30.0, "30/1", opts, "mpeg4");
}

#[test]
fn an_unfinished_overlay_leaves_nothing_behind() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("overlay.mp4");
    let (mut wr, _) =
        OverlayWriter::start(&path, 64, 48, 30.0, &names(), &OverlayOptions::default()).unwrap();
    wr.push(&frame(64, 48, 0), None, &marks(64, 48, 0)).unwrap();
    // A frame of the wrong size is refused, and the writer stays usable.
    assert!(wr.push(&frame(32, 48, 1), None, &marks(64, 48, 1)).is_err());
    wr.push(&frame(64, 48, 1), None, &marks(64, 48, 1)).unwrap();
    drop(wr);
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn bad_settings_are_errors_not_panics() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("overlay.mp4");
    let opts = OverlayOptions::default();
    assert!(OverlayWriter::start(&path, 64, 48, 0.0, &names(), &opts).is_err());
    assert!(OverlayWriter::start(&path, 0, 48, 30.0, &names(), &opts).is_err());
    let nowhere = dir.path().join("no/such/folder/overlay.mp4");
    let e = OverlayWriter::start(&nowhere, 64, 48, 30.0, &names(), &opts)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("does not exist"), "{e}");
    let missing = OverlayOptions {
        ffmpeg: "/nonexistent/ffmpeg".into(),
        ..OverlayOptions::default()
    };
    let e = OverlayWriter::start(&path, 64, 48, 30.0, &names(), &missing)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("cannot run ffmpeg"), "{e}");
    let bad_preset = OverlayOptions {
        preset: "no-such-preset".into(),
        ..OverlayOptions::default()
    };
    // ffmpeg refuses the preset: start, push or finish reports it in one line.
    let r =
        OverlayWriter::start(&path, 64, 48, 30.0, &names(), &bad_preset).and_then(|(mut w, _)| {
            for i in 0..30 {
                w.push(&frame(64, 48, i), None, &marks(64, 48, i))?;
            }
            w.finish()
        });
    let e = r.err().unwrap().to_string();
    assert!(e.starts_with("ffmpeg: ") && !e.contains('\n'), "{e}");
    assert!(!path.exists());
    let (w, _) = OverlayWriter::start(&path, 64, 48, 30.0, &names(), &opts).unwrap();
    assert!(w.finish().is_err(), "no frames");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}
