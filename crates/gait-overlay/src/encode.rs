//! The ffmpeg process: codec choice, arguments, and a writer thread that
//! feeds it raw RGB24 frames through a pipe.
//!
//! The writer thread lets the next frame be drawn while ffmpeg is still
//! reading the previous one; a 64 KiB pipe would otherwise serialise the two.
//! ffmpeg's stderr is drained by a second thread (a full pipe would stall
//! ffmpeg) and kept to explain a failure in one line.

use std::ffi::OsString;
use std::io::{Read, Write};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{Receiver, SyncSender, channel, sync_channel};
use std::thread::JoinHandle;

use crate::{Encoder, OverlayError};

/// Frame buffers in flight: one being drawn, one queued, one being written.
const BUFFERS: usize = 3;

/// The codec actually used.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Codec {
    Libx264,
    Mpeg4,
}

/// Names of the video encoders in the output of `ffmpeg -encoders`.
///
/// The listing is a legend, a `------` rule, then one line per encoder:
/// six flag characters (the first `V` for video) and the name.
pub(crate) fn video_encoders(listing: &str) -> Vec<&str> {
    listing
        .lines()
        .skip_while(|l| !l.trim_start().starts_with("---"))
        .skip(1)
        .filter_map(|l| {
            let mut words = l.split_whitespace();
            let flags = words.next()?;
            let name = words.next()?;
            (flags.len() == 6 && flags.starts_with('V')).then_some(name)
        })
        .collect()
}

/// Picks the codec for `wanted` among the encoders `listing` names; the
/// warning says when libx264 was wanted but mpeg4 is used.
pub(crate) fn choose(
    listing: &str,
    wanted: Encoder,
) -> Result<(Codec, Option<String>), OverlayError> {
    let have = video_encoders(listing);
    let has = |n: &str| have.contains(&n);
    match wanted {
        Encoder::Libx264 if has("libx264") => Ok((Codec::Libx264, None)),
        Encoder::Libx264 => Err(OverlayError::Ffmpeg(format!(
            "this ffmpeg has no libx264 encoder; {LIBX264_HINT}"
        ))),
        Encoder::Mpeg4 if has("mpeg4") => Ok((Codec::Mpeg4, None)),
        Encoder::Auto if has("libx264") => Ok((Codec::Libx264, None)),
        Encoder::Auto if has("mpeg4") => Ok((
            Codec::Mpeg4,
            Some(format!(
                "ffmpeg has no libx264 encoder: the overlay is MPEG-4 Part 2 (mpeg4, -q:v 3), \
                 larger and not playable in every browser; {LIBX264_HINT}"
            )),
        )),
        Encoder::Mpeg4 | Encoder::Auto => Err(OverlayError::Ffmpeg(
            "this ffmpeg has neither the libx264 nor the mpeg4 encoder".into(),
        )),
    }
}

const LIBX264_HINT: &str = "for H.264 install an ffmpeg built with --enable-gpl --enable-libx264 \
(Debian/Ubuntu: apt-get install ffmpeg; or a static build from https://johnvansickle.com/ffmpeg/)";

/// Lists the encoders of the `ffmpeg` program.
pub(crate) fn probe_encoders(ffmpeg: &Path) -> Result<String, OverlayError> {
    let out = Command::new(ffmpeg)
        .args(["-hide_banner", "-encoders"])
        .stdin(Stdio::null())
        .output()
        .map_err(|e| OverlayError::FfmpegMissing(format!("{}: {e}", ffmpeg.display())))?;
    if !out.status.success() {
        return Err(OverlayError::Ffmpeg(format!(
            "`-encoders` failed: {}",
            one_line(&out.stderr, &out.status.to_string())
        )));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// `fps` as the rational ffmpeg expects: `30/1`, `30000/1001`, or thousandths.
pub(crate) fn rate(fps: f64) -> Result<String, OverlayError> {
    if !fps.is_finite() || fps <= 0.0 || fps > 1000.0 {
        return Err(OverlayError::BadInput(format!(
            "frame rate {fps} (must be above 0 and at most 1000)"
        )));
    }
    let n = fps.round();
    // NTSC rates (23.976, 29.97, 59.94) are n*1000/1001 exactly.
    let ntsc = (fps * 1.001).round();
    if (fps - n).abs() < 1e-6 {
        return Ok(format!("{}/1", n as u64));
    }
    if (fps - ntsc * 1000.0 / 1001.0).abs() < 1e-3 {
        return Ok(format!("{}/1001", ntsc as u64 * 1000));
    }
    let num = (fps * 1000.0).round() as u64;
    let g = gcd(num, 1000);
    Ok(format!("{}/{}", num / g, 1000 / g))
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 { a.max(1) } else { gcd(b, a % b) }
}

/// The encoded size of composed frames `(w, h)`: scaled to `max_height` when taller,
/// the aspect kept, both even (as yuv420p needs).
pub(crate) fn scaled((w, h): (usize, usize), max_height: Option<u32>) -> (usize, usize) {
    match max_height.map(|m| m as usize) {
        Some(m) if h > m && m >= 2 => {
            let even = |x: usize| (x / 2 * 2).max(2);
            let height = even(m);
            (even((w * height + h / 2) / h), height)
        }
        _ => (w, h),
    }
}

/// ffmpeg's arguments: raw RGB24 frames of `w` x `h` on stdin at `rate`,
/// encoded at `out_size` to an MP4 at `out`.
pub(crate) fn args(
    codec: Codec,
    preset: &str,
    (w, h): (usize, usize),
    out_size: (usize, usize),
    rate: &str,
    out: &Path,
) -> Vec<OsString> {
    let mut a: Vec<OsString> = [
        "-hide_banner",
        "-nostats",
        "-loglevel",
        "error",
        "-y",
        "-f",
        "rawvideo",
        "-pix_fmt",
        "rgb24",
        "-s",
        &format!("{w}x{h}"),
        "-framerate",
        rate,
        "-i",
        "pipe:0",
        "-an",
    ]
    .iter()
    .map(OsString::from)
    .collect();
    if out_size != (w, h) {
        a.push("-vf".into());
        a.push(format!("scale={}:{}:flags=bicubic", out_size.0, out_size.1).into());
    }
    let codec_args: &[&str] = match codec {
        // Sub-pixel motion estimation at its cheapest: on the sample's 960x540 overlay 0.35
        // CPU s less than veryfast's own (subme 2, 1.45 s), for a file 14 % larger at the
        // same quality setting (CRF 23).
        Codec::Libx264 => &[
            "-c:v",
            "libx264",
            "-preset",
            preset,
            "-x264-params",
            "subme=1",
        ],
        Codec::Mpeg4 => &["-c:v", "mpeg4", "-q:v", "3"],
    };
    a.extend(codec_args.iter().map(OsString::from));
    // faststart: the index goes first, so the report's <video> plays at once;
    // -f mp4 because the temporary name's extension says nothing.
    a.extend(
        [
            "-pix_fmt",
            "yuv420p",
            "-movflags",
            "+faststart",
            "-f",
            "mp4",
        ]
        .iter()
        .map(OsString::from),
    );
    a.push(out.as_os_str().to_owned());
    a
}

/// The last lines of ffmpeg's stderr joined into one, or `fallback`.
pub(crate) fn one_line(stderr: &[u8], fallback: &str) -> String {
    let text = String::from_utf8_lossy(stderr);
    let lines: Vec<&str> = text
        .lines()
        .map(str::trim)
        // ffmpeg's "Last message repeated N times" says nothing about the failure.
        .filter(|l| !l.is_empty() && !l.starts_with("Last message repeated"))
        .collect();
    let tail = lines[lines.len().saturating_sub(3)..].join(" | ");
    if tail.is_empty() {
        fallback.to_string()
    } else if tail.chars().count() > 400 {
        format!("{}...", tail.chars().take(400).collect::<String>())
    } else {
        tail
    }
}

/// ffmpeg can exit 0 after its output failed (a full disk while muxing): the file is cut
/// short. Its own messages say so.
fn failed_write(stderr: &[u8]) -> bool {
    let text = String::from_utf8_lossy(stderr);
    [
        "No space left on device",
        "Disk quota exceeded",
        "Error writing trailer",
        "Error closing file",
    ]
    .iter()
    .any(|m| text.contains(m))
}

/// A running ffmpeg that encodes the frames it is sent.
pub(crate) struct Ffmpeg {
    child: Child,
    frames: Option<SyncSender<Vec<u8>>>,
    spare: Receiver<Vec<u8>>,
    free: Vec<Vec<u8>>,
    allocated: usize,
    frame_bytes: usize,
    writer: Option<JoinHandle<std::io::Result<()>>>,
    stderr: Option<JoinHandle<Vec<u8>>>,
    done: bool,
}

impl Ffmpeg {
    /// Starts `ffmpeg` with `args`; frames are `frame_bytes` long.
    pub(crate) fn spawn(
        ffmpeg: &Path,
        args: &[OsString],
        frame_bytes: usize,
    ) -> Result<Self, OverlayError> {
        let mut child = Command::new(ffmpeg)
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| OverlayError::FfmpegMissing(format!("{}: {e}", ffmpeg.display())))?;
        let (Some(mut stdin), Some(mut err)) = (child.stdin.take(), child.stderr.take()) else {
            let _ = child.kill();
            let _ = child.wait();
            return Err(OverlayError::Ffmpeg(
                "no pipes to the ffmpeg process".into(),
            ));
        };
        let stderr = std::thread::spawn(move || {
            let mut buf = Vec::new();
            let _ = err.read_to_end(&mut buf);
            buf
        });
        let (tx, rx) = sync_channel::<Vec<u8>>(1);
        let (back, spare) = channel::<Vec<u8>>();
        let writer = std::thread::spawn(move || -> std::io::Result<()> {
            for buf in rx {
                stdin.write_all(&buf)?;
                // The main thread may have stopped listening; nothing to do then.
                let _ = back.send(buf);
            }
            stdin.flush()
            // Dropping stdin here closes the pipe: ffmpeg sees the end.
        });
        Ok(Self {
            child,
            frames: Some(tx),
            spare,
            free: Vec::new(),
            allocated: 0,
            frame_bytes,
            writer: Some(writer),
            stderr: Some(stderr),
            done: false,
        })
    }

    /// A frame buffer to draw into: a returned one, or a new zeroed one
    /// while fewer than [`BUFFERS`] exist; else waits for the writer.
    pub(crate) fn buffer(&mut self) -> Result<Vec<u8>, OverlayError> {
        if let Some(b) = self.free.pop() {
            return Ok(b);
        }
        if let Ok(b) = self.spare.try_recv() {
            return Ok(b);
        }
        if self.allocated < BUFFERS {
            self.allocated += 1;
            return Ok(vec![0; self.frame_bytes]);
        }
        match self.spare.recv() {
            Ok(b) => Ok(b),
            Err(_) => Err(self.failure()),
        }
    }

    /// Takes back a buffer that was not sent (drawing failed).
    pub(crate) fn recycle(&mut self, buf: Vec<u8>) {
        self.free.push(buf);
    }

    /// Queues a drawn frame for ffmpeg.
    pub(crate) fn send(&mut self, buf: Vec<u8>) -> Result<(), OverlayError> {
        let sent = match &self.frames {
            Some(tx) => tx.send(buf).is_ok(),
            None => false,
        };
        if sent { Ok(()) } else { Err(self.failure()) }
    }

    /// The error of a writer that stopped early: ffmpeg died, and says why.
    fn failure(&mut self) -> OverlayError {
        self.frames = None;
        let _ = self.child.kill();
        let status = self.child.wait();
        let _ = self.writer.take().map(JoinHandle::join);
        let err = self
            .stderr
            .take()
            .and_then(|h| h.join().ok())
            .unwrap_or_default();
        self.done = true;
        let fallback = match status {
            Ok(s) => format!("stopped reading frames ({s})"),
            Err(e) => format!("stopped reading frames ({e})"),
        };
        OverlayError::Ffmpeg(one_line(&err, &fallback))
    }

    /// Closes ffmpeg's input and waits for it to write the file.
    pub(crate) fn finish(mut self) -> Result<(), OverlayError> {
        self.frames = None;
        let written = self.writer.take().map(JoinHandle::join);
        let status = self.child.wait();
        let err = self
            .stderr
            .take()
            .and_then(|h| h.join().ok())
            .unwrap_or_default();
        self.done = true;
        let status = status.map_err(OverlayError::io("waiting for ffmpeg"))?;
        if !status.success() || failed_write(&err) {
            return Err(OverlayError::Ffmpeg(one_line(&err, &status.to_string())));
        }
        match written {
            Some(Ok(Ok(()))) => Ok(()),
            Some(Ok(Err(e))) => Err(OverlayError::Ffmpeg(one_line(
                &err,
                &format!("writing frames: {e}"),
            ))),
            _ => Err(OverlayError::Ffmpeg(
                "the frame writer thread failed".into(),
            )),
        }
    }
}

impl Drop for Ffmpeg {
    /// An encoder dropped unfinished is killed, not left writing.
    fn drop(&mut self) {
        if self.done {
            return;
        }
        self.frames = None;
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = self.writer.take().map(JoinHandle::join);
        let _ = self.stderr.take().map(JoinHandle::join);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tall_frames_are_scaled_to_the_height_cap_with_even_sides() {
        assert_eq!(scaled((1768, 994), Some(720)), (1280, 720));
        assert_eq!(scaled((3536, 994), Some(720)), (2560, 720));
        assert_eq!(scaled((3840, 2160), Some(720)), (1280, 720));
        assert_eq!(scaled((640, 480), Some(720)), (640, 480));
        assert_eq!(scaled((1768, 994), None), (1768, 994));
        assert_eq!(scaled((1001, 1000), Some(501)), (500, 500));
    }

    #[test]
    fn a_full_disk_is_a_failure_even_when_ffmpeg_exits_0() {
        let err = b"[mp4 @ 0x1] Error writing trailer of x.mp4: No space left on device\n";
        assert!(failed_write(err));
        assert!(!failed_write(b"frame=  8 fps=0.0 q=-1.0 Lsize=  135kB\n"));
    }

    /// The head and a few lines of Debian ffmpeg 5.1's `-encoders` output.
    const LISTING: &str = "Encoders:
 V..... = Video
 A..... = Audio
 S..... = Subtitle
 .F.... = Frame-level multithreading
 ------
 V....D a64multi             Multicolor charset for Commodore 64 (codec a64_multi)
 V....D libx264rgb           libx264 H.264 / AVC / MPEG-4 AVC / MPEG-4 part 10 RGB (codec h264)
 V....D libx264              libx264 H.264 / AVC / MPEG-4 AVC / MPEG-4 part 10 (codec h264)
 V.S... mpeg4                MPEG-4 part 2
 A....D aac                  AAC (Advanced Audio Coding)
";

    #[test]
    fn encoder_listing_is_parsed() {
        let v = video_encoders(LISTING);
        assert_eq!(v, ["a64multi", "libx264rgb", "libx264", "mpeg4"]);
        assert!(!v.contains(&"="), "the legend is skipped");
    }

    #[test]
    fn libx264_is_preferred_and_mpeg4_is_the_fallback() {
        assert_eq!(
            choose(LISTING, Encoder::Auto).unwrap(),
            (Codec::Libx264, None)
        );
        assert_eq!(
            choose(LISTING, Encoder::Mpeg4).unwrap(),
            (Codec::Mpeg4, None)
        );
        // libx264rgb alone is not libx264.
        let without = LISTING.replace(" V....D libx264              libx264 H.264", "");
        let (c, warn) = choose(&without, Encoder::Auto).unwrap();
        assert_eq!(c, Codec::Mpeg4);
        let warn = warn.unwrap();
        assert!(
            warn.contains("libx264") && warn.contains("apt-get install ffmpeg"),
            "{warn}"
        );
        assert!(choose(&without, Encoder::Libx264).is_err());
        assert!(choose("garbage", Encoder::Auto).is_err());
    }

    #[test]
    fn frame_rates_become_rationals() {
        assert_eq!(rate(30.0).unwrap(), "30/1");
        assert_eq!(rate(29.97).unwrap(), "30000/1001");
        assert_eq!(rate(30000.0 / 1001.0).unwrap(), "30000/1001");
        assert_eq!(rate(23.976).unwrap(), "24000/1001");
        assert_eq!(rate(12.5).unwrap(), "25/2");
        assert!(rate(0.0).is_err() && rate(f64::NAN).is_err() && rate(-5.0).is_err());
    }

    #[test]
    fn stderr_is_summarised_in_one_line() {
        assert_eq!(one_line(b"", "exit 1"), "exit 1");
        assert_eq!(one_line(b"a\n\nb\nc\nd\n", "x"), "b | c | d");
    }
}
