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
use std::sync::{Arc, OnceLock};
use std::thread::JoinHandle;

use crate::PipelineError;
use crate::frame_spool::SpoolWriter;
use crate::yuv::Yuv420;

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
    /// Frames sent as yuv420p and converted here (yuv.rs), not as rgb24.
    pub yuv: Option<Yuv420>,
    /// With `yuv`: the first frame checked against ffmpeg's rgb24 of it (decoded by another
    /// ffmpeg at the same time).
    pub check: bool,
    /// Only this many frames (that other ffmpeg's one).
    pub frames: Option<usize>,
}

/// Whether ffmpeg converts one input's frames as yuv.rs does, once its first frame was
/// compared; shared by the input's readers.
#[derive(Debug, Clone, Default)]
pub(crate) struct YuvVerdict(Arc<OnceLock<bool>>);

impl PartialEq for YuvVerdict {
    /// Whether the check has run does not make two inputs different.
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl YuvVerdict {
    /// `req` with its yuv420p frames checked (not known yet), kept (they agreed) or dropped.
    pub(crate) fn settle(&self, req: Request) -> Request {
        match self.0.get() {
            None => Request { check: true, ..req },
            Some(true) => req,
            Some(false) => Request { yuv: None, ..req },
        }
    }

    pub(crate) fn record(&self, agrees: bool) {
        let _ = self.0.set(agrees);
    }

    /// The outcome of the check, when it has run.
    #[cfg(test)]
    pub(crate) fn agreed(&self) -> Option<bool> {
        self.0.get().copied()
    }
}

/// The ffmpeg command that decodes `path` to raw frames on its standard output (rgb24, or
/// yuv420p where `req.yuv` says), as `req` asks. Fast bilinear scaling for the overlay costs
/// 0.7 CPU s less than bicubic on the sample (BENCHMARKS.md) and no measure is taken from
/// those frames.
fn ffmpeg_command(path: &Path, req: Request) -> Command {
    let mut cmd = Command::new("ffmpeg");
    // One decoding thread: the passes wait on the model, not on ffmpeg, and frame threads cost
    // CPU to coordinate (the sample's VP9 decode: 1.5 CPU s on one thread, 1.75 on two, at
    // about the same wall time); the frames are the same bits.
    cmd.args(["-v", "error", "-nostdin", "-threads", "1", "-i"])
        .arg(path);
    // The stream ffprobe described (input.rs), so the frames have the size it said.
    cmd.arg("-map")
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
    if let Some(n) = req.frames {
        cmd.arg("-frames:v").arg(n.to_string());
    }
    let pix_fmt = if req.yuv.is_some() {
        "yuv420p"
    } else {
        "rgb24"
    };
    cmd.args(["-f", "rawvideo", "-pix_fmt", pix_fmt, "-"]);
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
    /// What ffmpeg was asked for (asked again as rgb24 when the check fails).
    req: Request,
    /// The ffmpeg decoding the first frame as rgb24 for the check, while it is pending.
    check: Option<Child>,
    /// Where the check's outcome is kept for the input's other readers.
    verdict: YuvVerdict,
    /// A yuv420p frame's buffer, reused.
    planes: Vec<u8>,
    /// Where the frames read are kept for later readers (frame_spool.rs).
    keep: Option<SpoolWriter>,
}

impl VideoDecoder {
    /// Decodes `path` as `req` asks; the outcome of a yuv check goes to `verdict`.
    pub(crate) fn spawn(
        path: &Path,
        req: Request,
        verdict: YuvVerdict,
    ) -> Result<Self, PipelineError> {
        let source = Box::new(Ffmpeg::spawn(path, req)?);
        let check = (req.check && req.yuv.is_some()).then(|| {
            let first = Request {
                yuv: None,
                frames: Some(1),
                ..req
            };
            ffmpeg_command(path, first)
                .stdin(Stdio::null())
                .stdout(Stdio::piped())
                .stderr(Stdio::null())
                .spawn()
        });
        Ok(VideoDecoder {
            path: path.to_path_buf(),
            source,
            req,
            // A check that cannot start fails, and the frames come as rgb24.
            check: check.and_then(Result::ok),
            verdict,
            planes: Vec::new(),
            keep: None,
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
            req: Request::default(),
            check: None,
            verdict: YuvVerdict::default(),
            planes: Vec::new(),
            keep: None,
        }
    }

    /// Keeps the yuv420p frames read from now on for later readers (the first frame's reader
    /// only: the writer numbers them from 0).
    pub(crate) fn keep_frames(&mut self, writer: SpoolWriter) {
        self.keep = Some(writer);
    }

    /// Appends the next `width` x `height` frame to `buf` as rgb24: the bytes read (0 at the
    /// end of the output; fewer than a frame's when it was cut short).
    pub(crate) fn read_frame(
        &mut self,
        buf: &mut Vec<u8>,
        size: (usize, usize),
    ) -> Result<usize, PipelineError> {
        match self.req.yuv {
            None => {
                // ffmpeg's rgb24 frames are not what the kept frames' readers convert.
                if let Some(keep) = &mut self.keep {
                    keep.abandon();
                }
                self.read_bytes(buf, size.0 * size.1 * 3)
            }
            Some(_) if self.req.check => self.read_checked(buf, size),
            Some(yuv) => self.read_yuv(yuv, buf, size),
        }
    }

    /// The first frame converted here, kept when it is the other ffmpeg's rgb24 of it; else
    /// ffmpeg's, from a decoder started again without the yuv420p frames.
    fn read_checked(
        &mut self,
        buf: &mut Vec<u8>,
        size: (usize, usize),
    ) -> Result<usize, PipelineError> {
        self.req.check = false;
        let start = buf.len();
        let read = match self.req.yuv {
            Some(yuv) => self.read_yuv(yuv, buf, size)?,
            None => 0,
        };
        let theirs = self
            .check
            .take()
            .and_then(|c| c.wait_with_output().ok())
            .filter(|out| out.status.success())
            .map(|out| out.stdout);
        if read == 0 && theirs.as_ref().is_none_or(Vec::is_empty) {
            // No frame either way: the end (or the decoder's error) comes from `finish`.
            return Ok(0);
        }
        let agrees = read == size.0 * size.1 * 3 && theirs.as_deref() == Some(&buf[start..]);
        self.verdict.record(agrees);
        if agrees {
            return Ok(read);
        }
        buf.truncate(start);
        self.req.yuv = None;
        if let Some(keep) = &mut self.keep {
            keep.abandon();
        }
        self.source = Box::new(Ffmpeg::spawn(&self.path, self.req)?);
        self.read_bytes(buf, size.0 * size.1 * 3)
    }

    /// A yuv420p frame converted to rgb24 into `buf`: as [`Self::read_frame`].
    fn read_yuv(
        &mut self,
        yuv: Yuv420,
        buf: &mut Vec<u8>,
        (width, height): (usize, usize),
    ) -> Result<usize, PipelineError> {
        let mut planes = std::mem::take(&mut self.planes);
        planes.clear();
        let len = Yuv420::frame_len(width, height);
        let read = self.read_bytes(&mut planes, len);
        if matches!(read, Ok(n) if n == len) {
            yuv.convert(&planes, width, height, buf);
            if let Some(keep) = &mut self.keep {
                keep.push(&planes);
            }
        }
        self.planes = planes;
        let n = read?;
        Ok(if n == len { width * height * 3 } else { n })
    }

    /// Appends `len` bytes of ffmpeg's output to `buf`: the bytes read. Read into the vector's
    /// spare capacity, so a frame buffer is not zeroed first only to be overwritten (a full-HD
    /// frame is 6 MB, 230 of them a memset of 1.4 GB).
    fn read_bytes(&mut self, buf: &mut Vec<u8>, len: usize) -> Result<usize, PipelineError> {
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
        if let Some(keep) = &mut self.keep {
            keep.end();
        }
        Ok(())
    }
}

impl Drop for VideoDecoder {
    /// A check left pending (the reader stopped at an error) is not left running.
    fn drop(&mut self) {
        if let Some(mut check) = self.check.take() {
            let _ = check.kill();
            let _ = check.wait();
        }
    }
}

#[cfg(test)]
mod tests;
