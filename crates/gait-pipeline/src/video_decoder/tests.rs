//! The decoder against ffmpeg: damaged videos, early readers, the yuv420p frames and their check.

use std::sync::mpsc;
use std::time::Duration;

use crate::input::InputInfo;

/// A 100 s MJPEG clip with every 128th byte after the header flipped: ffmpeg reports
/// about 150 KB of decoding errors, more than a pipe holds.
fn damaged_video(dir: &std::path::Path) -> std::path::PathBuf {
    let clean = dir.join("clean.avi");
    let status = std::process::Command::new("ffmpeg")
        .args([
            "-v",
            "error",
            "-y",
            "-f",
            "lavfi",
            "-i",
            "testsrc=size=64x48:rate=30",
        ])
        .args(["-t", "100", "-c:v", "mjpeg"])
        .arg(&clean)
        .status()
        .expect("ffmpeg (tools/setup.sh installs it)");
    assert!(status.success());
    let mut bytes = std::fs::read(&clean).unwrap();
    for b in bytes.iter_mut().skip(4096).step_by(128) {
        *b ^= 0xff;
    }
    let damaged = dir.join("damaged.avi");
    std::fs::write(&damaged, bytes).unwrap();
    damaged
}

/// The reader over a recorded run of a 4x2 video (24 bytes a frame).
fn replay(frames: Vec<u8>, success: bool, messages: &str) -> Vec<Result<usize, String>> {
    let probe = br#"{"streams": [{"width": 4, "height": 2, "r_frame_rate": "30/1"}]}"#;
    let info = crate::input::parse_ffprobe(std::path::Path::new("clip.mp4"), probe).unwrap();
    let mut reader = info.replay(super::DecoderRecording {
        frames,
        success,
        messages: messages.to_string(),
    });
    let mut seen = Vec::new();
    loop {
        match reader.next_frame() {
            Ok(Some(f)) => seen.push(Ok(f.index)),
            Ok(None) => return seen,
            Err(e) => {
                seen.push(Err(e.to_string()));
                return seen;
            }
        }
    }
}

#[test]
fn recorded_runs_end_as_ffmpeg_ended() {
    assert_eq!(replay(vec![7; 48], true, ""), vec![Ok(0), Ok(1)]);
    // Frames then a failure: the failure is reported with ffmpeg's first message line.
    let end = replay(vec![7; 24], false, "\n[h264] broken slice\nmore\n");
    assert_eq!(end[0], Ok(0));
    let err = end[1].clone().unwrap_err();
    assert!(
        err.contains("cannot decode the video: [h264] broken slice"),
        "{err}"
    );
    let err = replay(vec![7; 30], true, "")[1].clone().unwrap_err();
    assert!(err.contains("frame 1 is truncated"), "{err}");
    let err = replay(Vec::new(), true, "")[0].clone().unwrap_err();
    assert!(err.contains("the video has no frames"), "{err}");
    let err = replay(Vec::new(), true, "moov atom not found")[0]
        .clone()
        .unwrap_err();
    assert!(err.contains("moov atom not found"), "{err}");
}

/// A clean clip of `seconds` at 30 fps, 64 x 48 (H.264, 4:2:0).
fn clip(dir: &std::path::Path, seconds: u32) -> std::path::PathBuf {
    clip_as(dir, "clip.mp4", "64x48", "yuv420p", seconds)
}

#[test]
fn frames_over_the_socket_are_the_bytes_ffmpeg_writes() {
    let dir = tempfile::tempdir().unwrap();
    let path = clip(dir.path(), 2);
    // ffmpeg's standard output collected whole (a pipe), against the reader (a socket).
    let recorded = super::DecoderRecording::record(&path).unwrap();
    assert!(recorded.success && recorded.frames.len() == 60 * 64 * 48 * 3);
    assert!(read_all(&InputInfo::open(&path).unwrap()) == recorded.frames);
}

#[test]
fn a_reader_left_early_ends_its_decoder() {
    let dir = tempfile::tempdir().unwrap();
    let path = clip(dir.path(), 100);
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut frames = InputInfo::open(&path).unwrap().frames().unwrap();
        let first = frames.next_frame().unwrap().map(|f| f.index);
        drop(frames);
        let _ = tx.send(first);
    });
    // ffmpeg, with 3000 frames still to write, is stopped when the reader goes.
    let first = rx
        .recv_timeout(Duration::from_secs(600))
        .expect("leaving a decoder early hung");
    assert_eq!(first, Some(0));
}

#[test]
fn a_damaged_video_full_of_decoder_errors_ends() {
    let dir = tempfile::tempdir().unwrap();
    let path = damaged_video(dir.path());
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let info = InputInfo::open(&path).unwrap();
        let mut frames = info.frames().unwrap();
        let mut n = 0;
        let end = loop {
            match frames.next_frame() {
                Ok(Some(_)) => n += 1,
                other => break other.map(|_| n),
            }
        };
        let _ = tx.send(end);
    });
    // Not a speed check: before the messages were read on their own thread this never
    // returned (ffmpeg and gait each waiting on the other's pipe).
    let end = rx
        .recv_timeout(Duration::from_secs(600))
        .expect("decoding a damaged video hung");
    match end {
        Ok(n) => assert!(n > 0),
        Err(e) => assert!(e.to_string().contains("damaged.avi"), "{e}"),
    }
}

/// A clip of `seconds` at 30 fps, `size`, in `pix_fmt` (H.264, BT.709 limited range).
fn clip_as(
    dir: &std::path::Path,
    name: &str,
    size: &str,
    pix_fmt: &str,
    seconds: u32,
) -> std::path::PathBuf {
    let path = dir.join(name);
    let status = std::process::Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-f", "lavfi", "-i"])
        .arg(format!("testsrc2=size={size}:rate=30:duration={seconds}"))
        .args([
            "-c:v",
            "libx264",
            "-pix_fmt",
            pix_fmt,
            "-colorspace",
            "bt709",
        ])
        .arg(&path)
        .status()
        .expect("ffmpeg (tools/setup.sh installs it)");
    assert!(status.success());
    path
}

/// Every frame's bytes, read through `info`'s reader, one after another.
fn read_all(info: &InputInfo) -> Vec<u8> {
    read_from(info, 0)
}

/// Every frame, read whole, against ffmpeg's rgb24 output of the whole video.
fn read_matches_ffmpeg(info: &InputInfo) -> bool {
    read_all(info) == super::DecoderRecording::record(&info.path).unwrap().frames
}

/// A 4:2:0 video (the sample's size: not a multiple of 16 wide) is taken as yuv420p, checked
/// and converted here; a 4:4:4 one as rgb24; either way the bytes are ffmpeg's rgb24.
#[test]
fn frames_taken_as_yuv_are_ffmpegs_rgb_bytes() {
    let dir = tempfile::tempdir().unwrap();
    for (name, size, pix_fmt) in [
        ("a.mp4", "1768x994", "yuv420p"),
        ("b.mp4", "66x48", "yuv444p"),
    ] {
        let path = clip_as(dir.path(), name, size, pix_fmt, 1);
        let info = InputInfo::open(&path).unwrap();
        assert_eq!(info.yuv.is_some(), pix_fmt == "yuv420p", "{name}");
        assert!(read_matches_ffmpeg(&info), "{name}: the frames differ");
        #[cfg(target_arch = "x86_64")]
        assert_eq!(info.yuv_verdict.agreed(), info.yuv.map(|_| true), "{name}");
    }
}

/// A conversion that is not ffmpeg's (here: the wrong colour matrix) fails the check on the
/// first frame, and the frames come as ffmpeg's rgb24, from the first on.
#[test]
fn a_conversion_unlike_ffmpegs_falls_back_to_its_rgb() {
    let dir = tempfile::tempdir().unwrap();
    let path = clip_as(dir.path(), "c.mp4", "64x48", "yuv420p", 1);
    let mut info = InputInfo::open(&path).unwrap();
    info.yuv = crate::yuv::Yuv420::of_stream(Some("yuv420p"), Some("smpte240m"), None, (64, 48));
    assert!(read_matches_ffmpeg(&info));
    assert_eq!(info.yuv_verdict.agreed(), Some(false));
    // The input's later readers take rgb24 without checking again.
    assert!(read_matches_ffmpeg(&info));
}

/// Frames from `from` on, read through `info`'s reader.
fn read_from(info: &InputInfo, from: usize) -> Vec<u8> {
    let mut frames = info.frames_from(from).unwrap();
    let mut read = Vec::new();
    while let Some(f) = frames.next_frame().unwrap() {
        read.extend_from_slice(f.image.as_raw());
    }
    read
}

/// The frames the subject pass's reader keeps are read back by the pose pass's as ffmpeg's
/// rgb24 bytes, without ffmpeg: here the video is gone before the second read.
#[test]
fn kept_frames_are_read_back_as_ffmpeg_decodes_them() {
    let dir = tempfile::tempdir().unwrap();
    let path = clip_as(dir.path(), "k.mp4", "66x48", "yuv420p", 2);
    let info = InputInfo::open(&path).unwrap();
    let whole = super::DecoderRecording::record(&path).unwrap().frames;
    info.keep_frames();
    assert!(read_all(&info) == whole);
    std::fs::remove_file(&path).unwrap();
    let len = 66 * 48 * 3;
    assert!(read_from(&info, 10) == whole[10 * len..]);
    // Released, nothing is kept, and the frames must come from the (missing) video.
    info.release_kept_frames();
    assert!(info.frames_from(10).unwrap().next_frame().is_err());
}

/// A first reader stopped early keeps the frames it read; a later reader decodes the rest.
#[test]
fn frames_after_those_kept_are_decoded() {
    let dir = tempfile::tempdir().unwrap();
    let path = clip_as(dir.path(), "e.mp4", "64x48", "yuv420p", 2);
    let info = InputInfo::open(&path).unwrap();
    let whole = super::DecoderRecording::record(&path).unwrap().frames;
    info.keep_frames();
    let mut first = info.frames().unwrap();
    for _ in 0..20 {
        first.next_frame().unwrap();
    }
    drop(first);
    let len = 64 * 48 * 3;
    assert!(read_from(&info, 5) == whole[5 * len..]);
}

/// Frames that failed the conversion's check come as ffmpeg's rgb24 and are not kept.
#[test]
fn frames_unlike_ffmpegs_are_not_kept() {
    let dir = tempfile::tempdir().unwrap();
    let path = clip_as(dir.path(), "c.mp4", "64x48", "yuv420p", 1);
    let mut info = InputInfo::open(&path).unwrap();
    info.yuv = crate::yuv::Yuv420::of_stream(Some("yuv420p"), Some("smpte240m"), None, (64, 48));
    info.keep_frames();
    assert!(read_matches_ffmpeg(&info));
    assert!(info.spool.kept().is_none());
    assert!(read_matches_ffmpeg(&info));
}
