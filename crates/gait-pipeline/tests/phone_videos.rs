//! Videos as phones and camcorders deliver them, made with ffmpeg and read as a run reads them:
//! a variable frame rate, several video streams, HDR, interlacing (frame_timing.rs, picture.rs).

use std::path::Path;
use std::process::Command;

use gait_core::Frame;
use gait_pipeline::input::InputInfo;

fn ffmpeg(args: &[&str]) {
    let status = Command::new("ffmpeg")
        .args(["-v", "error", "-y"])
        .args(args)
        .status()
        .expect("ffmpeg (tools/setup.sh installs it)");
    assert!(status.success());
}

fn all_frames(info: &InputInfo) -> Vec<Frame> {
    let mut r = info.frames().unwrap();
    std::iter::from_fn(|| r.next_frame().unwrap()).collect()
}

/// Audio first, then a small preview stream, then the walk: the walk is analysed, and its
/// frames are decoded at the size the probe said.
#[test]
fn the_largest_video_stream_is_analysed() {
    let dir = tempfile::tempdir().unwrap();
    let clip = dir.path().join("clip.mkv");
    let clip = clip.to_str().unwrap();
    ffmpeg(&[
        "-f",
        "lavfi",
        "-i",
        "sine=d=1",
        "-f",
        "lavfi",
        "-i",
        "testsrc=size=32x24:rate=30:d=1",
        "-f",
        "lavfi",
        "-i",
        "testsrc=size=64x48:rate=30:d=1",
        "-map",
        "0",
        "-map",
        "1",
        "-map",
        "2",
        "-c:v",
        "mjpeg",
        clip,
    ]);
    let info = InputInfo::open(Path::new(clip)).unwrap();
    assert_eq!((info.width, info.height, info.stream), (64, 48, Some(2)));
    let frames = all_frames(&info);
    assert_eq!(frames.len(), 30);
    assert!(frames.iter().all(|f| (f.width(), f.height()) == (64, 48)));
}

/// Frames 20-39 of a 30 fps clip with every other one missing: resampled to 30 fps, the
/// missing frames' slots repeat the frame before, and the clip keeps its 60 frames' time.
#[test]
fn a_variable_frame_rate_is_decoded_at_the_camera_rate() {
    let dir = tempfile::tempdir().unwrap();
    let clip = dir.path().join("clip.mkv");
    let clip = clip.to_str().unwrap();
    ffmpeg(&[
        "-f",
        "lavfi",
        "-i",
        "testsrc=size=64x48:rate=30:d=2",
        "-vf",
        "select='not(between(n,20,39))+not(mod(n,2))'",
        "-fps_mode",
        "passthrough",
        "-c:v",
        "ffv1",
        clip,
    ]);
    let info = InputInfo::open(Path::new(clip)).unwrap();
    let timing = info.timing.clone().unwrap();
    assert_eq!((timing.resampled_fps, info.fps), (Some(30.0), 30.0));
    let frames = all_frames(&info);
    assert!((59..=60).contains(&frames.len()), "{}", frames.len());
    assert!(frames[21].image == frames[20].image);
    assert!(frames[20].image != frames[19].image && frames[22].image != frames[21].image);
    assert!(warns(&info, "resampled"));
}

/// An HLG clip (testsrc made HLG by zscale, losslessly stored) is decoded to the standard
/// range frames it was made from, not washed out.
#[test]
fn an_hdr_video_is_decoded_to_standard_range() {
    let dir = tempfile::tempdir().unwrap();
    let (sdr, hlg) = (dir.path().join("sdr.mkv"), dir.path().join("hlg.mkv"));
    // Colours kept inside BT.709's gamut, as a natural scene's mostly are.
    let src = "testsrc2=size=64x48:rate=30:d=0.2,hue=s=0.4";
    ffmpeg(&[
        "-f",
        "lavfi",
        "-i",
        src,
        "-c:v",
        "ffv1",
        "-pix_fmt",
        "yuv444p",
        sdr.to_str().unwrap(),
    ]);
    ffmpeg(&[
        "-f",
        "lavfi",
        "-i",
        src,
        "-vf",
        "zscale=tin=bt709:min=bt709:pin=bt709:t=arib-std-b67:m=bt2020nc:p=bt2020:r=tv,format=yuv444p10le",
        "-c:v",
        "ffv1",
        "-color_trc",
        "arib-std-b67",
        "-color_primaries",
        "bt2020",
        "-colorspace",
        "bt2020nc",
        hlg.to_str().unwrap(),
    ]);
    let info = InputInfo::open(&hlg).unwrap();
    assert_eq!(info.hdr_transfer.as_deref(), Some("arib-std-b67"));
    assert!(warns(&info, "HDR (HLG)"));
    let (a, b) = (
        all_frames(&info),
        all_frames(&InputInfo::open(&sdr).unwrap()),
    );
    assert_eq!(a.len(), b.len());
    let d = mean_difference(&a[0], &b[0]);
    assert!(d < 6.0, "mean difference {d:.1} grey levels");
    // Decoded as standard video, the same frames differ by four times as much (21 levels).
    let mut as_standard = info.clone();
    as_standard.hdr_transfer = None;
    let washed = mean_difference(&all_frames(&as_standard)[0], &b[0]);
    assert!(washed > 15.0, "{washed:.1}");
}

/// A camcorder's interlaced .mts (two fields 1/60 s apart woven into each frame of 30) is
/// deinterlaced a frame for a frame: nearer the top field's moment, taken from the 60 fps
/// source, than the woven frame with its combed edges.
#[test]
fn an_interlaced_video_is_deinterlaced() {
    let dir = tempfile::tempdir().unwrap();
    let (clip, top) = (dir.path().join("camcorder.mts"), dir.path().join("top.mkv"));
    // A white bar crossing a black frame at 400 px/s: 6.7 px between the two fields.
    let src = concat!(
        "color=c=black:s=128x96:r=60:d=0.5[bg];color=c=white:s=16x96:r=60[bar];",
        "[bg][bar]overlay=x='mod(t*400,112)':y=0:shortest=1[out0]"
    );
    ffmpeg(&[
        "-f",
        "lavfi",
        "-i",
        src,
        "-vf",
        "tinterlace=mode=interleave_top,setfield=tff",
        "-c:v",
        "libx264",
        "-crf",
        "10",
        "-flags",
        "+ildct+ilme",
        "-x264-params",
        "tff=1",
        "-field_order",
        "tt",
        clip.to_str().unwrap(),
    ]);
    ffmpeg(&[
        "-f",
        "lavfi",
        "-i",
        src,
        "-vf",
        "select='not(mod(n,2))'",
        "-fps_mode",
        "passthrough",
        "-c:v",
        "ffv1",
        top.to_str().unwrap(),
    ]);
    let info = InputInfo::open(&clip).unwrap();
    assert_eq!(info.interlaced.as_deref(), Some("tt"));
    assert!(warns(&info, "interlaced"));
    let mut woven = info.clone();
    woven.interlaced = None;
    let (a, b) = (all_frames(&info), all_frames(&woven));
    let truth = all_frames(&InputInfo::open(&top).unwrap());
    assert_eq!((a.len(), b.len()), (truth.len(), truth.len()));
    let (after, before) = (
        mean_difference(&a[10], &truth[10]),
        mean_difference(&b[10], &truth[10]),
    );
    assert!(
        after < 0.7 * before,
        "{before:.1} -> {after:.1} grey levels"
    );
}

/// Whether the reader of `info` warned with `text`.
fn warns(info: &InputInfo, text: &str) -> bool {
    info.decode_warnings().iter().any(|w| w.contains(text))
}

/// The mean absolute difference of two frames' RGB values, in grey levels.
fn mean_difference(x: &Frame, y: &Frame) -> f64 {
    let (p, q) = (x.image.as_raw(), y.image.as_raw());
    p.iter()
        .zip(q)
        .map(|(u, v)| u.abs_diff(*v) as f64)
        .sum::<f64>()
        / p.len() as f64
}
