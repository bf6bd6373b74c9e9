//! Encode speed of the overlay against a plain ffmpeg transcode.
//!
//! Decodes the first N frames of a video to raw RGB with ffmpeg, draws the
//! overlay (marks of a run folder, or a synthetic walker) and encodes it,
//! then transcodes the same frames with plain ffmpeg at the same preset.
//! Both include decoding, so the ratio is the cost of drawing and piping.
//!
//! ```text
//! cargo run --release -p gait-overlay --example overlay_bench -- \
//!     --input data/sample/sports2d-demo.mp4 [--frames 230] [--size 1920x1080] \
//!     [--run runs/sample] [--layout skeleton|side-by-side] [--preset veryfast] [--out DIR]
//! ```

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use gait_core::{Keypoint, Pose};
use gait_overlay::{
    Backdrop, EventKind, EventMark, FrameMarks, Layout, OverlayOptions, OverlayWriter, Side,
    marks_from_run_dir,
};
use image::RgbImage;

struct Args {
    input: PathBuf,
    frames: usize,
    size: Option<(u32, u32)>,
    run: Option<PathBuf>,
    layout: Layout,
    preset: String,
    out: PathBuf,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        input: PathBuf::new(),
        frames: 230,
        size: None,
        run: None,
        layout: Layout::Skeleton,
        preset: "veryfast".into(),
        out: std::env::temp_dir(),
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut val = || it.next().ok_or(format!("{flag} needs a value"));
        match flag.as_str() {
            "--input" => a.input = val()?.into(),
            "--frames" => a.frames = val()?.parse().map_err(|_| "--frames: a number")?,
            "--size" => {
                let v = val()?;
                let (w, h) = v.split_once('x').ok_or("--size: WxH")?;
                a.size = Some((
                    w.parse().map_err(|_| "--size: WxH")?,
                    h.parse().map_err(|_| "--size: WxH")?,
                ));
            }
            "--run" => a.run = Some(val()?.into()),
            "--layout" => {
                a.layout = match val()?.as_str() {
                    "skeleton" => Layout::Skeleton,
                    "side-by-side" => Layout::SideBySide {
                        backdrop: Backdrop::Dark,
                    },
                    other => {
                        return Err(format!("--layout: skeleton or side-by-side, not {other}"));
                    }
                }
            }
            "--preset" => a.preset = val()?,
            "--out" => a.out = val()?.into(),
            other => return Err(format!("unknown argument {other}")),
        }
    }
    if a.input.as_os_str().is_empty() {
        return Err("--input VIDEO is required".into());
    }
    Ok(a)
}

/// Width, height and frame rate of the first video stream.
fn probe(input: &Path) -> Result<(u32, u32, f64), String> {
    let out = Command::new("ffprobe")
        .args(["-v", "error", "-select_streams", "v:0", "-show_entries"])
        .args(["stream=width,height,r_frame_rate", "-of", "csv=p=0"])
        .arg(input)
        .output()
        .map_err(|e| format!("ffprobe: {e}"))?;
    let text = String::from_utf8_lossy(&out.stdout);
    let f: Vec<&str> = text.trim().split(',').collect();
    let [w, h, r] = f.as_slice() else {
        return Err(format!("ffprobe: unexpected output `{text}`"));
    };
    let (n, d) = r.split_once('/').unwrap_or((r, "1"));
    let rate = n.parse::<f64>().unwrap_or(30.0) / d.parse::<f64>().unwrap_or(1.0);
    Ok((
        w.parse().map_err(|_| "width")?,
        h.parse().map_err(|_| "height")?,
        rate,
    ))
}

/// `-vf scale=W:H` when a size was asked for.
fn scale_args(size: Option<(u32, u32)>) -> Vec<String> {
    size.map(|(w, h)| vec!["-vf".into(), format!("scale={w}:{h}")])
        .unwrap_or_default()
}

/// A walker in the middle of the frame, for runs without a run folder.
fn synthetic(i: usize, fps: f64, w: f64, h: f64) -> (Vec<String>, FrameMarks) {
    let names: Vec<String> = gait_core::CANONICAL.iter().map(|s| s.to_string()).collect();
    let mut pose = Pose::empty(names.len());
    let swing = (i as f64 * 0.2).sin() * 0.05;
    for (k, name) in names.iter().enumerate() {
        let side = if name.starts_with("left") {
            1.0
        } else if name.starts_with("right") {
            -1.0
        } else {
            0.0
        };
        let y = match name.split('_').next_back().unwrap_or("") {
            "nose" => 0.15,
            "neck" | "shoulder" => 0.25,
            "hip" => 0.5,
            "knee" => 0.68,
            "ankle" => 0.85,
            _ => 0.9,
        };
        let x = 0.5 + side * (0.03 + if y > 0.6 { swing } else { 0.0 });
        pose.keypoints[k] = Keypoint::new(x * w, y * h, 0.9);
    }
    let marks = FrameMarks {
        frame: i,
        time_s: i as f64 / fps,
        pose: Some(pose),
        events: (i % 15 < 9)
            .then_some(EventMark {
                side: Side::Left,
                kind: EventKind::HeelStrike,
                age_frames: i % 15,
            })
            .into_iter()
            .collect(),
        dim: (i % 60 < 10).then(|| "outside walking bout".into()),
    };
    (names, marks)
}

fn main() {
    if let Err(e) = run() {
        eprintln!("overlay_bench: {e}");
        std::process::exit(1);
    }
}

/// CPU seconds so far of this process (all threads) and of its waited-for
/// children (the ffmpeg processes), from /proc/self/stat (Linux; 0 elsewhere).
fn cpu_s() -> (f64, f64) {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the parenthesised command name; utime is field 14.
    let rest = stat.rsplit_once(')').map(|(_, r)| r).unwrap_or("");
    let f: Vec<f64> = rest
        .split_whitespace()
        .map(|v| v.parse().unwrap_or(0.0))
        .collect();
    let tick = 100.0; // USER_HZ on Linux
    let get = |i: usize| f.get(i).copied().unwrap_or(0.0) / tick;
    // rest[0] is field 3 (state), so field n is rest[n - 3].
    (get(11) + get(12), get(13) + get(14))
}

/// A child ffmpeg decoding `frames` frames of `input` to raw RGB24 on its stdout.
fn decoder(a: &Args) -> Result<std::process::Child, String> {
    Command::new("ffmpeg")
        .args(["-v", "error", "-i"])
        .arg(&a.input)
        .args(["-frames:v", &a.frames.to_string()])
        .args(scale_args(a.size))
        .args(["-f", "rawvideo", "-pix_fmt", "rgb24", "pipe:1"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .spawn()
        .map_err(|e| format!("ffmpeg: {e}"))
}

/// Decoded frames, delivered by a reader thread (as a pipeline's reader
/// would) through a channel of two.
fn frames(
    a: &Args,
    w: u32,
    h: u32,
) -> Result<(std::process::Child, std::sync::mpsc::Receiver<RgbImage>), String> {
    let mut dec = decoder(a)?;
    let mut stdout = dec.stdout.take().ok_or("no decoder pipe")?;
    let (tx, rx) = std::sync::mpsc::sync_channel::<RgbImage>(2);
    let bytes = w as usize * h as usize * 3;
    std::thread::spawn(move || {
        loop {
            let mut buf = vec![0u8; bytes];
            if stdout.read_exact(&mut buf).is_err() {
                break;
            }
            let Some(img) = RgbImage::from_raw(w, h, buf) else {
                break;
            };
            if tx.send(img).is_err() {
                break;
            }
        }
    });
    Ok((dec, rx))
}

struct Marks {
    run: Option<gait_overlay::RunMarks>,
    names: Vec<String>,
    fps: f64,
    in_size: (f64, f64),
    scale: (f64, f64),
}

impl Marks {
    /// Frame `i`'s marks, keypoints scaled to the encoded size.
    fn get(&self, i: usize) -> FrameMarks {
        let mut m = match &self.run {
            Some(r) => r
                .marks
                .iter()
                .find(|m| m.frame == i)
                .cloned()
                .unwrap_or(FrameMarks {
                    frame: i,
                    time_s: i as f64 / self.fps,
                    ..FrameMarks::default()
                }),
            None => synthetic(i, self.fps, self.in_size.0, self.in_size.1).1,
        };
        if let Some(p) = &mut m.pose {
            for k in &mut p.keypoints {
                k.x = (k.x + 0.5) * self.scale.0 - 0.5;
                k.y = (k.y + 0.5) * self.scale.1 - 0.5;
            }
        }
        m
    }
}

/// Encodes `images` with their marks; returns frames and output size.
fn encode(
    a: &Args,
    out: &Path,
    (w, h): (u32, u32),
    marks: &Marks,
    images: impl Iterator<Item = RgbImage>,
) -> Result<(usize, (u32, u32)), String> {
    let opts = OverlayOptions {
        layout: a.layout,
        preset: a.preset.clone(),
        ..OverlayOptions::default()
    };
    let (mut wr, warnings) = OverlayWriter::start(out, w, h, marks.fps, &marks.names, &opts)
        .map_err(|e| e.to_string())?;
    for warn in warnings {
        eprintln!("warning: {warn}");
    }
    for (i, img) in images.enumerate() {
        wr.push(&img, None, &marks.get(i))
            .map_err(|e| e.to_string())?;
    }
    let n = wr.frames();
    let size = wr.output_size();
    wr.finish().map_err(|e| e.to_string())?;
    Ok((n, size))
}

fn run() -> Result<(), String> {
    let a = parse_args()?;
    let (in_w, in_h, fps) = probe(&a.input)?;
    let (w, h) = a.size.unwrap_or((in_w, in_h));
    let run = match &a.run {
        Some(dir) => Some(marks_from_run_dir(dir).map_err(|e| e.to_string())?),
        None => None,
    };
    let marks = Marks {
        names: match &run {
            Some(r) => r.names.clone(),
            None => synthetic(0, fps, 1.0, 1.0).0,
        },
        run,
        fps,
        in_size: (f64::from(in_w), f64::from(in_h)),
        scale: (
            f64::from(w) / f64::from(in_w),
            f64::from(h) / f64::from(in_h),
        ),
    };
    let out = a.out.join("overlay_bench.mp4");
    let plain = a.out.join("overlay_bench_plain.mp4");

    // 1. Encoding alone: frames decoded into memory first.
    let (mut dec, rx) = frames(&a, w, h)?;
    let images: Vec<RgbImage> = rx.iter().collect();
    let _ = dec.wait();
    let (c0, k0) = cpu_s();
    let t = Instant::now();
    let (n, (ow, oh)) = encode(&a, &out, (w, h), &marks, images.into_iter())?;
    let enc_s = t.elapsed().as_secs_f64();
    let (c1, k1) = cpu_s();

    // 2. Decoding, drawing and encoding at once, as `gait run` would.
    let t = Instant::now();
    let (mut dec, rx) = frames(&a, w, h)?;
    encode(&a, &out, (w, h), &marks, rx.into_iter())?;
    let _ = dec.wait();
    let both_s = t.elapsed().as_secs_f64();
    let (c2, k2) = cpu_s();

    // 3. The reference: a plain transcode of the same frames.
    let t = Instant::now();
    let status = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-i"])
        .arg(&a.input)
        .args(["-frames:v", &a.frames.to_string()])
        .args(scale_args(a.size))
        .args([
            "-an", "-c:v", "libx264", "-preset", &a.preset, "-pix_fmt", "yuv420p",
        ])
        .arg(&plain)
        .status()
        .map_err(|e| format!("ffmpeg: {e}"))?;
    let plain_s = t.elapsed().as_secs_f64();
    let (c3, k3) = cpu_s();
    if !status.success() {
        return Err("the plain transcode failed".into());
    }
    let fps_of = |s: f64| n as f64 / s;
    println!(
        "frames              {n} of {} ({w}x{h} in, {ow}x{oh} out, preset {})",
        a.input.display(),
        a.preset
    );
    println!(
        "overlay encode      {enc_s:6.2} s {:6.1} fps  cpu: drawing+pipe {:.2} s, ffmpeg {:.2} s (frames in memory)",
        fps_of(enc_s),
        c1 - c0,
        k1 - k0
    );
    println!(
        "overlay decode+enc  {both_s:6.2} s {:6.1} fps  cpu {:.2} s",
        fps_of(both_s),
        (c2 - c1) + (k2 - k1)
    );
    println!(
        "plain transcode     {plain_s:6.2} s {:6.1} fps  cpu {:.2} s",
        fps_of(plain_s),
        (c3 - c2) + (k3 - k2)
    );
    println!(
        "ratio               {:.2} wall, {:.2} cpu (overlay decode+encode / plain transcode)",
        both_s / plain_s,
        ((c2 - c1) + (k2 - k1)) / ((c3 - c2) + (k3 - k2)).max(1e-9)
    );
    Ok(())
}
