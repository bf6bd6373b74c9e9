//! ffmpeg decoding a video to raw RGB frames on a pipe.
//!
//! ffmpeg's messages are read on their own thread while frames are read here: a damaged video
//! makes ffmpeg report an error per frame, and once a pipe's 64 KiB fill up, a reader that
//! left them unread waits on the frame pipe while ffmpeg waits on the message pipe, forever.
//!
//! What the reader does with ffmpeg's output is kept apart from the process ([`FrameSource`]),
//! so that a [`DecoderRecording`] of a run can replace it: the fuzzer and the tests drive the
//! reader with any bytes, exit status and messages, without spawning ffmpeg per input.

use std::io::{Cursor, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::thread::JoinHandle;

use crate::PipelineError;

/// ffmpeg's messages kept for the error (the first line is what the user sees).
const MAX_MESSAGES: usize = 64 * 1024;

/// How a decoder ended: whether it succeeded, and what it reported.
#[derive(Clone)]
struct Ending {
    success: bool,
    messages: String,
}

/// Where a video's decoded frames come from: ffmpeg, or a recording of it.
trait FrameSource: Send {
    /// The raw rgb24 frames, one after another.
    fn output(&mut self) -> Option<&mut dyn Read>;
    /// Waits for the decoder to end.
    fn end(&mut self) -> std::io::Result<Ending>;
}

/// What a pass asks the decoder for.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Request {
    /// Frames scaled to this size (only overlay.mp4 asks: a picture shown at most 720 px high).
    pub size: Option<(u32, u32)>,
    /// The first frame wanted: those before are decoded, as a video must be, but neither
    /// converted to RGB nor sent (the pose pass starts where the subject comes into view).
    pub from: usize,
    /// A variable-rate video's frames resampled to this constant rate (frame_timing.rs).
    pub resample: Option<f64>,
    /// The input's stream to decode (`None`: its first video stream).
    pub stream: Option<usize>,
    /// The filter that converts an HDR video to standard range first (picture.rs).
    pub standard_range: Option<&'static str>,
    /// The filter that deinterlaces an interlaced video first (picture.rs).
    pub deinterlace: Option<&'static str>,
}

/// The ffmpeg command that decodes `path` to rgb24 frames on its standard output, as `req`
/// asks. Fast bilinear scaling for the overlay costs 0.7 CPU s less than bicubic on the
/// sample (BENCHMARKS.md) and no measure is taken from those frames.
fn ffmpeg_command(path: &Path, req: Request) -> Command {
    let mut cmd = Command::new("ffmpeg");
    // One decoding thread: the passes wait on the model, not on ffmpeg, and frame threads cost
    // CPU to coordinate (the sample's VP9 decode: 1.5 CPU s on one thread, 1.75 on two, at
    // about the same wall time); the frames are the same bits.
    cmd.args(["-v", "error", "-nostdin", "-threads", "1", "-i"])
        .arg(path)
        // The stream ffprobe described (input.rs), so the frames have the size it said.
        .arg("-map")
        .arg(req.stream.map_or("0:V:0".to_string(), |i| format!("0:{i}")));
    let mut filters = Vec::new();
    // Fields are woven back into frames before anything else looks at the pictures.
    filters.extend(req.deinterlace.map(str::to_string));
    filters.extend(req.standard_range.map(str::to_string));
    // Before the selection, so frame numbers count the constant-rate frames.
    if let Some(fps) = req.resample {
        filters.push(format!("fps={fps}"));
    }
    if req.from > 0 {
        filters.push(format!("select=gte(n\\,{})", req.from));
    }
    if let Some((w, h)) = req.size {
        filters.push(format!("scale={w}:{h}:flags=fast_bilinear"));
    }
    if !filters.is_empty() {
        cmd.arg("-vf").arg(filters.join(","));
    }
    // The frames as they come (or as the fps filter made them), in every pass alike: left to
    // itself, ffmpeg repeats frames to fill time to a raw output, e.g. a first frame for the
    // 23 ms a .mkv's audio starts before its video, and a pass that starts later (`from`)
    // would then number the same frame one lower.
    cmd.args(["-fps_mode", "passthrough"]);
    cmd.args(["-f", "rawvideo", "-pix_fmt", "rgb24", "-"]);
    cmd
}

/// A running ffmpeg.
struct Ffmpeg {
    child: Child,
    frames: Box<dyn Read + Send>,
    messages: Option<JoinHandle<String>>,
}

/// The channel ffmpeg writes its frames to: the child's end and ours.
///
/// On Unix a socket pair, not a pipe: a pipe's writer and reader take one lock per 32 KiB
/// written or read and spin on it while the other copies, and each 4 KiB of a pipe is a page
/// allocated and freed. The socket hands over whole buffers and each end locks only its own
/// side: on the sample, 230 frames of 1768 x 994 cost 1.8-1.9 CPU s through a socket against
/// 2.2-2.6 through a pipe, the same bytes (BENCHMARKS.md, issue 40).
fn frame_channel() -> std::io::Result<(Stdio, Option<Box<dyn Read + Send>>)> {
    #[cfg(unix)]
    {
        let (ours, theirs) = std::os::unix::net::UnixStream::pair()?;
        Ok((
            Stdio::from(std::os::fd::OwnedFd::from(theirs)),
            Some(Box::new(ours)),
        ))
    }
    #[cfg(not(unix))]
    {
        Ok((Stdio::piped(), None))
    }
}

impl Ffmpeg {
    fn spawn(path: &Path, req: Request) -> Result<Self, PipelineError> {
        let (stdout, ours) = frame_channel().map_err(|e| PipelineError::input(path, e))?;
        let mut cmd = ffmpeg_command(path, req);
        cmd.stdin(Stdio::null())
            .stdout(stdout)
            .stderr(Stdio::piped());
        let mut child = cmd
            .spawn()
            .map_err(|e| crate::input::ffmpeg_missing(path, e))?;
        // The child holds its end now; ours must be the only one left, or the reader would
        // never see the end of the output.
        drop(cmd);
        let frames = match (ours, child.stdout.take()) {
            (Some(frames), _) => frames,
            (None, Some(piped)) => Box::new(piped) as Box<dyn Read + Send>,
            (None, None) => {
                let _ = child.kill();
                return Err(PipelineError::input(path, "ffmpeg has no output"));
            }
        };
        let messages = child.stderr.take().map(|mut stderr| {
            std::thread::spawn(move || {
                let mut kept = Vec::new();
                let mut chunk = [0u8; 8192];
                while let Ok(n @ 1..) = stderr.read(&mut chunk) {
                    let room = MAX_MESSAGES.saturating_sub(kept.len());
                    kept.extend_from_slice(&chunk[..n.min(room)]);
                }
                String::from_utf8_lossy(&kept).into_owned()
            })
        });
        Ok(Ffmpeg {
            child,
            frames,
            messages,
        })
    }
}

impl FrameSource for Ffmpeg {
    fn output(&mut self) -> Option<&mut dyn Read> {
        Some(&mut *self.frames)
    }

    fn end(&mut self) -> std::io::Result<Ending> {
        let status = self.child.wait()?;
        let messages = self
            .messages
            .take()
            .and_then(|h| h.join().ok())
            .unwrap_or_default();
        Ok(Ending {
            success: status.success(),
            messages,
        })
    }
}

impl Drop for Ffmpeg {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// What one ffmpeg run wrote: its frame bytes, whether it exited with success, its messages.
#[derive(Debug, Clone, PartialEq)]
pub struct DecoderRecording {
    pub frames: Vec<u8>,
    pub success: bool,
    pub messages: String,
}

impl DecoderRecording {
    /// Runs [`ffmpeg_command`] on `path` to the end and keeps what it wrote.
    pub fn record(path: &Path) -> std::io::Result<Self> {
        let out = ffmpeg_command(path, Request::default())
            .stdin(Stdio::null())
            .output()?;
        Ok(DecoderRecording {
            frames: out.stdout,
            success: out.status.success(),
            messages: String::from_utf8_lossy(&out.stderr).into_owned(),
        })
    }
}

/// A recording played back as the decoder's output.
struct Playback {
    frames: Cursor<Vec<u8>>,
    ending: Ending,
}

impl FrameSource for Playback {
    fn output(&mut self) -> Option<&mut dyn Read> {
        Some(&mut self.frames)
    }

    fn end(&mut self) -> std::io::Result<Ending> {
        Ok(self.ending.clone())
    }
}

/// A video being decoded, frame by frame.
pub(crate) struct VideoDecoder {
    path: PathBuf,
    source: Box<dyn FrameSource>,
}

impl VideoDecoder {
    /// Decodes `path` as `req` asks.
    pub(crate) fn spawn(path: &Path, req: Request) -> Result<Self, PipelineError> {
        Ok(VideoDecoder {
            path: path.to_path_buf(),
            source: Box::new(Ffmpeg::spawn(path, req)?),
        })
    }

    /// A decoder that plays `recording` back as if ffmpeg decoded `path` now.
    pub(crate) fn replay(path: &Path, recording: DecoderRecording) -> Self {
        let playback = Playback {
            frames: Cursor::new(recording.frames),
            ending: Ending {
                success: recording.success,
                messages: recording.messages,
            },
        };
        VideoDecoder {
            path: path.to_path_buf(),
            source: Box::new(playback),
        }
    }

    /// Appends the next frame, `len` bytes, to `buf`: the bytes read (0 at the end of the
    /// output). Read into the vector's spare capacity, so a frame buffer is not zeroed first
    /// only to be overwritten (a full-HD frame is 6 MB, 230 of them a memset of 1.4 GB).
    pub(crate) fn read_frame(
        &mut self,
        buf: &mut Vec<u8>,
        len: usize,
    ) -> Result<usize, PipelineError> {
        let output = self
            .source
            .output()
            .ok_or_else(|| PipelineError::input(&self.path, "ffmpeg has no output"))?;
        Read::take(output, len as u64)
            .read_to_end(buf)
            .map_err(|e| PipelineError::input(&self.path, e))
    }

    /// At the end of ffmpeg's output after `frames` frames: a clean end, or the decoder's error.
    pub(crate) fn finish(&mut self, frames: usize) -> Result<(), PipelineError> {
        let Ending { success, messages } = self
            .source
            .end()
            .map_err(|e| PipelineError::input(&self.path, e))?;
        if !success || (frames == 0 && !messages.trim().is_empty()) {
            let first = messages
                .lines()
                .find(|l| !l.trim().is_empty())
                .unwrap_or("ffmpeg failed")
                .trim()
                .to_string();
            return Err(PipelineError::input(
                &self.path,
                format!("cannot decode the video: {first}"),
            ));
        }
        if frames == 0 {
            return Err(PipelineError::input(&self.path, "the video has no frames"));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
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

    /// A clean clip of `seconds` at 30 fps, 64 x 48 (H.264).
    fn clip(dir: &std::path::Path, seconds: u32) -> std::path::PathBuf {
        let path = dir.join("clip.mp4");
        let status = std::process::Command::new("ffmpeg")
            .args(["-v", "error", "-y", "-f", "lavfi", "-i"])
            .arg(format!("testsrc=size=64x48:rate=30:duration={seconds}"))
            .args(["-c:v", "libx264", "-pix_fmt", "yuv420p"])
            .arg(&path)
            .status()
            .expect("ffmpeg (tools/setup.sh installs it)");
        assert!(status.success());
        path
    }

    #[test]
    fn frames_over_the_socket_are_the_bytes_ffmpeg_writes() {
        let dir = tempfile::tempdir().unwrap();
        let path = clip(dir.path(), 2);
        // ffmpeg's standard output collected whole (a pipe), against the reader (a socket).
        let recorded = super::DecoderRecording::record(&path).unwrap();
        assert!(recorded.success && recorded.frames.len() == 60 * 64 * 48 * 3);
        let mut frames = InputInfo::open(&path).unwrap().frames().unwrap();
        let mut read = Vec::new();
        while let Some(f) = frames.next_frame().unwrap() {
            read.extend_from_slice(f.image.as_raw());
        }
        assert!(read == recorded.frames);
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
}
