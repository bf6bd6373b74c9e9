//! Inputs: a video file (decoded by the `ffmpeg` command line tool), a folder
//! of images, or a single image, read as a stream of RGB frames.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use sha2::{Digest, Sha256};

use crate::PipelineError;
pub use crate::frame_reader::{FrameReader, READ_AHEAD};
use crate::frame_reader::{Source, read_ahead};
use crate::frame_timing::FrameTiming;
use crate::still;
pub use crate::video_decoder::DecoderRecording;
use crate::video_decoder::{Request, VideoDecoder};

/// What ffmpeg reads and clinics film with: phones (mp4, mov, 3gp), camcorders (AVCHD's mts and
/// m2ts, mpg), screen and browser recordings (webm, mkv, wmv).
const VIDEO_EXTENSIONS: [&str; 13] = [
    "mp4", "avi", "mov", "webm", "mkv", "m4v", "mts", "m2ts", "ts", "3gp", "mpg", "mpeg", "wmv",
];
const IMAGE_EXTENSIONS: [&str; 5] = ["png", "jpg", "jpeg", "bmp", "tif"];

/// Names the way video frames are decoded (video_decoder.rs) in the cache keys: change it
/// when a change to the decoding can change a video's frames.
const VIDEO_DECODING: &str = "ffmpeg: largest video stream, frames as they come (passthrough)";

/// Frame rate assumed for image folders and single images.
pub const DEFAULT_IMAGE_FPS: f64 = 30.0;

/// What the input is and what is known about it before decoding.
#[derive(Debug, Clone, PartialEq)]
pub struct InputInfo {
    pub path: PathBuf,
    pub width: u32,
    pub height: u32,
    pub fps: f64,
    /// Number of frames, when the container says.
    pub frames: Option<usize>,
    /// How a video's frames are spaced in time, when its timestamps tell.
    pub timing: Option<FrameTiming>,
    /// The index of the video's stream that is analysed (`None`: the first video stream).
    pub stream: Option<usize>,
    /// An HDR video's transfer (ffprobe's `color_transfer`: "arib-std-b67" is HLG,
    /// "smpte2084" PQ): its frames are converted to standard range (picture.rs).
    pub hdr_transfer: Option<String>,
    /// An interlaced video's field order ("tt", "bb", "tb", "bt"): its frames are
    /// deinterlaced (picture.rs).
    pub interlaced: Option<String>,
    /// Still images: how many have each EXIF orientation (1-8), applied when decoded.
    pub orientations: std::collections::BTreeMap<u16, usize>,
    pub(crate) kind: Kind,
    /// What the decoder had to say about damaged but readable stills (shared by the readers).
    pub(crate) decode_warnings: DecodeWarnings,
    /// Time the readers waited for decoded frames (shared by the readers).
    pub(crate) reading: ReadClock,
}

/// Nanoseconds spent in [`FrameReader::next_frame`], over every reader of one input.
#[derive(Debug, Clone, Default)]
pub(crate) struct ReadClock(pub(crate) std::sync::Arc<std::sync::atomic::AtomicU64>);

impl PartialEq for ReadClock {
    /// Time spent reading does not make two inputs different.
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// Warnings of every reader of one input, e.g. a JPEG cut short ("Premature end of JPEG file").
#[derive(Debug, Clone, Default)]
pub(crate) struct DecodeWarnings(std::sync::Arc<std::sync::Mutex<Vec<String>>>);

impl PartialEq for DecodeWarnings {
    /// What was decoded so far does not make two inputs different.
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl DecodeWarnings {
    pub(crate) fn add(&self, warning: String) {
        let mut w = self.0.lock().unwrap_or_else(|e| e.into_inner());
        if !w.contains(&warning) {
            w.push(warning);
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Kind {
    Video,
    Images(Vec<PathBuf>),
}

impl InputInfo {
    /// Why a frame range gave no frame: the range and, where the container says, the
    /// frames the input has.
    pub fn no_frames_in(&self, first: usize, last: Option<usize>) -> String {
        let range = match last {
            Some(l) => format!("first_frame = {first}, last_frame = {l}"),
            None => format!("first_frame = {first}"),
        };
        match self.frames {
            Some(0) => {
                format!("no frames in the selected range ({range}): the input has no frames")
            }
            Some(n) => format!(
                "no frames in the selected range ({range}): the input has {n} frames (0 to {}); set input.first_frame below {n}",
                n - 1
            ),
            None => format!(
                "no frames in the selected range ({range}): the input ends before frame {first}"
            ),
        }
    }

    /// Inspects `path` without decoding it whole.
    pub fn open(path: &Path) -> Result<Self, PipelineError> {
        if !path.exists() {
            return Err(PipelineError::input(
                path,
                "no such file or folder; check the --input path",
            ));
        }
        if path.is_dir() {
            return Self::folder(path);
        }
        let ext = extension(path);
        if IMAGE_EXTENSIONS.contains(&ext.as_str()) {
            return Self::images(path, vec![path.to_path_buf()]);
        }
        if VIDEO_EXTENSIONS.contains(&ext.as_str()) {
            return probe_video(path);
        }
        Err(PipelineError::input(
            path,
            format!(
                "unsupported file type `.{ext}`; give a video ({}), an image ({}) or a folder of images",
                VIDEO_EXTENSIONS.join(", "),
                IMAGE_EXTENSIONS.join(", ")
            ),
        ))
    }

    fn folder(dir: &Path) -> Result<Self, PipelineError> {
        let entries = std::fs::read_dir(dir)
            .map_err(|e| PipelineError::input(dir, format!("cannot list the folder ({e})")))?;
        let mut files: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && IMAGE_EXTENSIONS.contains(&extension(p).as_str()))
            .collect();
        if files.is_empty() {
            return Err(PipelineError::input(
                dir,
                format!(
                    "the folder has no images ({}); put the frames there or give a video",
                    IMAGE_EXTENSIONS.join(", ")
                ),
            ));
        }
        // Natural order, so frame_2 comes before frame_10.
        files.sort_by_key(|f| natural_key(f));
        Self::images(dir, files)
    }

    fn images(path: &Path, files: Vec<PathBuf>) -> Result<Self, PipelineError> {
        let mut orientations = std::collections::BTreeMap::new();
        let mut size = None;
        for f in &files {
            let (dims, o) = still::dimensions(f).map_err(|e| PipelineError::input(f, e))?;
            size.get_or_insert(dims);
            *orientations.entry(o).or_insert(0) += 1;
        }
        let (width, height) = size.unwrap_or_default();
        Ok(Self {
            path: path.to_path_buf(),
            width,
            height,
            fps: DEFAULT_IMAGE_FPS,
            frames: Some(files.len()),
            timing: None,
            stream: None,
            hdr_transfer: None,
            interlaced: None,
            orientations,
            kind: Kind::Images(files),
            decode_warnings: DecodeWarnings::default(),
            reading: ReadClock::default(),
        })
    }

    /// Seconds every reader of this input has waited for decoded frames so far.
    pub fn seconds_reading(&self) -> f64 {
        self.reading.0.load(std::sync::atomic::Ordering::Relaxed) as f64 * 1e-9
    }

    /// The decoder's warnings so far (damaged but readable stills), one per file.
    pub fn decode_warnings(&self) -> Vec<String> {
        self.decode_warnings
            .0
            .lock()
            .map(|w| w.clone())
            .unwrap_or_default()
    }

    /// A content hash of the input as decoded, so cached results of another input (or
    /// of an edited file with the same name) are never reused.
    pub fn fingerprint(&self) -> Result<String, PipelineError> {
        let mut hasher = Sha256::new();
        let files = match &self.kind {
            Kind::Video => vec![self.path.clone()],
            Kind::Images(files) => files.clone(),
        };
        for f in &files {
            let mut file = std::fs::File::open(f).map_err(|e| PipelineError::input(f, e))?;
            hasher.update(
                f.file_name()
                    .map(|n| n.as_encoded_bytes())
                    .unwrap_or_default(),
            );
            let mut buf = vec![0u8; 1 << 20];
            loop {
                let n = file
                    .read(&mut buf)
                    .map_err(|e| PipelineError::input(f, e))?;
                if n == 0 {
                    break;
                }
                hasher.update(&buf[..n]);
            }
        }
        // How a video is decoded is part of what its frames are: cached results of another
        // decoding (before 2026-12-06 ffmpeg could repeat a first frame, and resampled frames
        // are not the file's own) must not be taken for them.
        if self.kind == Kind::Video {
            hasher.update(VIDEO_DECODING.as_bytes());
        }
        if let Some(fps) = self.resampled_fps() {
            hasher.update(format!("resampled to {fps} fps").as_bytes());
        }
        if let Some(t) = &self.hdr_transfer {
            hasher.update(format!("converted from {t} to standard range").as_bytes());
        }
        if let Some(o) = &self.interlaced {
            hasher.update(format!("deinterlaced from field order {o}").as_bytes());
        }
        Ok(hex(&hasher.finalize()))
    }

    /// Decodes the frames in order; a video's on a thread of its own that
    /// stays [`READ_AHEAD`] frames ahead, so ffmpeg decodes the next frames
    /// while the caller works on this one (through a 64 KiB pipe it could
    /// not get ahead by even one frame).
    pub fn frames(&self) -> Result<FrameReader, PipelineError> {
        self.frames_at(None)
    }

    /// As [`Self::frames`], a video's frames scaled by ffmpeg to `size` (a
    /// picture that will be shown smaller: decoding straight to that size
    /// saves copying and drawing full frames). Images are read as they are.
    pub fn frames_at(&self, size: Option<(u32, u32)>) -> Result<FrameReader, PipelineError> {
        self.frames_as(Request {
            size,
            from: 0,
            resample: self.resampled_fps(),
            stream: self.stream,
            standard_range: self
                .hdr_transfer
                .as_deref()
                .and_then(crate::picture::to_standard_range),
            deinterlace: self
                .interlaced
                .as_deref()
                .and_then(crate::picture::deinterlace),
        })
    }

    /// As [`Self::frames`], from frame `from` on: the frames before it are
    /// not read (a video's are decoded but not converted or sent).
    pub fn frames_from(&self, from: usize) -> Result<FrameReader, PipelineError> {
        self.frames_as(Request {
            size: None,
            from,
            resample: self.resampled_fps(),
            stream: self.stream,
            standard_range: self
                .hdr_transfer
                .as_deref()
                .and_then(crate::picture::to_standard_range),
            deinterlace: self
                .interlaced
                .as_deref()
                .and_then(crate::picture::deinterlace),
        })
    }

    fn resampled_fps(&self) -> Option<f64> {
        self.timing.as_ref().and_then(|t| t.resampled_fps)
    }

    fn frames_as(&self, req: Request) -> Result<FrameReader, PipelineError> {
        let source = match &self.kind {
            Kind::Images(files) => Source::Images(files.clone()),
            Kind::Video => {
                let mut info = self.clone();
                if let Some((w, h)) = req.size {
                    (info.width, info.height) = (w, h);
                }
                let inner = FrameReader {
                    source: Source::Video(VideoDecoder::spawn(&self.path, req)?),
                    info,
                    next: req.from,
                };
                Source::Ahead(read_ahead(inner))
            }
        };
        Ok(FrameReader {
            info: self.clone(),
            source,
            next: req.from,
        })
    }

    /// Reads the frames of a recorded ffmpeg run as if ffmpeg decoded this video now (for the
    /// fuzzer and tests, which drive the reader without a process).
    pub fn replay(&self, recording: DecoderRecording) -> FrameReader {
        FrameReader {
            info: self.clone(),
            source: Source::Video(VideoDecoder::replay(&self.path, recording)),
            next: 0,
        }
    }
}

pub(crate) fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

fn natural_key(path: &Path) -> (String, u64, String) {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let stem = name.rsplit_once('.').map_or(name.as_str(), |(s, _)| s);
    let digits: String = stem
        .chars()
        .rev()
        .take_while(char::is_ascii_digit)
        .collect::<Vec<_>>()
        .into_iter()
        .rev()
        .collect();
    let prefix = stem[..stem.len() - digits.len()].to_string();
    (prefix, digits.parse().unwrap_or(0), name)
}

pub(crate) fn ffmpeg_missing(path: &Path, e: std::io::Error) -> PipelineError {
    PipelineError::input(
        path,
        format!(
            "cannot run ffmpeg ({e}); install it (Debian: apt-get install ffmpeg) or give a folder of images"
        ),
    )
}

/// The ffprobe command that describes `path` in the JSON [`parse_ffprobe`] reads: every video
/// stream that is not a cover picture (`V`; the video is chosen among them) and their packets'
/// times (frame_timing.rs), one packet a line.
pub fn ffprobe_command(path: &Path) -> Command {
    let mut cmd = Command::new("ffprobe");
    cmd.args(["-v", "error", "-select_streams", "V", "-show_entries"])
        .arg(concat!(
            "stream=index,codec_type,width,height,r_frame_rate,nb_frames,color_transfer,field_order",
            ":stream_disposition=attached_pic:stream_side_data=rotation",
            ":packet=stream_index,pts_time"
        ))
        .args(["-of", "json=compact=1"])
        .arg(path);
    cmd
}

/// The stream analysed: the video stream with the most pixels that is not a cover picture (the
/// one ffmpeg itself would take; a camera's small preview stream may come first). A stream
/// without a `codec_type` counts as video (older recordings of ffprobe's output).
fn video_stream(streams: &serde_json::Value) -> Option<&serde_json::Value> {
    let pixels = |s: &serde_json::Value| {
        // Saturating: a hostile description may declare any width; the size check follows.
        (s["width"].as_u64().unwrap_or(0)).saturating_mul(s["height"].as_u64().unwrap_or(0))
    };
    streams
        .as_array()?
        .iter()
        .filter(|s| s["codec_type"].as_str().is_none_or(|t| t == "video"))
        .filter(|s| s["disposition"]["attached_pic"].as_u64() != Some(1))
        .rev()
        .max_by_key(|s| pixels(s))
}

fn probe_video(path: &Path) -> Result<InputInfo, PipelineError> {
    let out = ffprobe_command(path)
        .stdin(Stdio::null())
        .output()
        .map_err(|e| ffmpeg_missing(path, e))?;
    if !out.status.success() {
        let msg = String::from_utf8_lossy(&out.stderr);
        let why = msg.lines().next().unwrap_or("ffprobe failed").trim();
        return Err(not_a_video(path, why));
    }
    parse_ffprobe(path, &out.stdout)
}

fn not_a_video(path: &Path, why: &str) -> PipelineError {
    PipelineError::input(
        path,
        format!("not a readable video ({why}); check the file or re-encode it"),
    )
}

/// The largest frame a video may declare: 8192 x 8192 pixels (8K video is 7680 x 4320), so
/// a hostile container cannot make each frame's buffer gigabytes.
pub const MAX_FRAME_PIXELS: u64 = 8192 * 8192;

/// The video's size, rate and frame count from ffprobe's JSON output for `path` (public
/// for the fuzzer, which feeds it arbitrary bytes).
pub fn parse_ffprobe(path: &Path, stdout: &[u8]) -> Result<InputInfo, PipelineError> {
    let bad = |why: &str| not_a_video(path, why);
    let json: serde_json::Value =
        serde_json::from_slice(stdout).map_err(|_| bad("ffprobe output unreadable"))?;
    let stream = video_stream(&json["streams"]).ok_or_else(|| bad("no video stream"))?;
    let index = stream["index"].as_u64();
    let dim = |k: &str| {
        stream[k]
            .as_u64()
            .filter(|v| *v > 0)
            .and_then(|v| u32::try_from(v).ok())
    };
    let (mut width, mut height) = match (dim("width"), dim("height")) {
        (Some(w), Some(h)) => (w, h),
        _ => return Err(bad("no frame size")),
    };
    if width as u64 * height as u64 > MAX_FRAME_PIXELS {
        return Err(bad(&format!(
            "frames of {width}x{height} pixels; at most 8192x8192 are read"
        )));
    }
    let rotation = stream["side_data_list"]
        .as_array()
        .and_then(|l| l.iter().find_map(|d| d["rotation"].as_i64()))
        .unwrap_or(0);
    // ffmpeg applies the rotation when decoding, so the frames are turned.
    if rotation.rem_euclid(180) == 90 {
        std::mem::swap(&mut width, &mut height);
    }
    let fps = stream["r_frame_rate"]
        .as_str()
        .and_then(|r| {
            let (n, d) = r.split_once('/')?;
            let (n, d): (f64, f64) = (n.parse().ok()?, d.parse().ok()?);
            // "inf/1" parses too; a camera rate is finite and below 10^5 frames per second.
            let fps = n / d;
            (d > 0.0 && n > 0.0 && fps.is_finite() && fps <= 1e5).then_some(fps)
        })
        .ok_or_else(|| bad("no frame rate"))?;
    let mut frames = stream["nb_frames"].as_str().and_then(|n| n.parse().ok());
    let times: Vec<f64> = json["packets"]
        .as_array()
        .into_iter()
        .flatten()
        .filter(|p| p["stream_index"].as_u64() == index)
        .filter_map(|p| p["pts_time"].as_str()?.parse().ok())
        .collect();
    let timing = FrameTiming::measure(fps, &times);
    let decode_warnings = DecodeWarnings::default();
    let hdr_transfer = stream["color_transfer"]
        .as_str()
        .filter(|t| crate::picture::to_standard_range(t).is_some())
        .map(str::to_string);
    if let Some(w) = hdr_transfer.as_deref().and_then(crate::picture::warning) {
        decode_warnings.add(w);
    }
    let interlaced = stream["field_order"]
        .as_str()
        .filter(|o| crate::picture::deinterlace(o).is_some())
        .map(str::to_string);
    if let Some(o) = &interlaced {
        decode_warnings.add(format!(
            "the video is interlaced (field order {o}): its frames were deinterlaced (bwdif, a frame for a frame)"
        ));
    }
    if let Some(t) = &timing {
        if t.resampled_fps.is_some() {
            frames = Some(t.frames(times.len()));
        }
        if let Some(w) = t.warning() {
            decode_warnings.add(w);
        }
    }
    Ok(InputInfo {
        path: path.to_path_buf(),
        width,
        height,
        fps: timing.as_ref().map_or(fps, FrameTiming::fps),
        frames,
        timing,
        stream: index.and_then(|i| usize::try_from(i).ok()),
        hdr_transfer,
        interlaced,
        orientations: Default::default(),
        kind: Kind::Video,
        decode_warnings,
        reading: ReadClock::default(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folders_are_read_in_natural_order() {
        let dir = tempfile::tempdir().unwrap();
        for (i, name) in ["f10.png", "f2.png", "f1.png"].iter().enumerate() {
            let img = image::RgbImage::from_pixel(4, 3, image::Rgb([i as u8, 0, 0]));
            img.save(dir.path().join(name)).unwrap();
        }
        std::fs::write(dir.path().join("notes.txt"), "not a frame").unwrap();
        let info = InputInfo::open(dir.path()).unwrap();
        assert_eq!((info.width, info.height, info.frames), (4, 3, Some(3)));
        let mut r = info.frames().unwrap();
        let reds: Vec<u8> = std::iter::from_fn(|| r.next_frame().unwrap())
            .map(|f| f.image.get_pixel(0, 0)[0])
            .collect();
        assert_eq!(reds, vec![2, 1, 0]);
    }

    /// Frames read from frame 7 on are the full decode's, bit for bit, under their own numbers.
    #[test]
    fn a_video_read_from_a_frame_on_gives_the_same_frames() {
        let dir = tempfile::tempdir().unwrap();
        let video = dir.path().join("clip.mp4");
        let status = std::process::Command::new("ffmpeg")
            .args(["-v", "error", "-y", "-f", "lavfi", "-i"])
            .arg("testsrc=size=64x48:rate=30:duration=0.5")
            .args(["-c:v", "libx264", "-pix_fmt", "yuv420p"])
            .arg(&video)
            .status()
            .expect("ffmpeg (tools/setup.sh installs it)");
        assert!(status.success());
        let info = InputInfo::open(&video).unwrap();
        let all = |mut r: FrameReader| -> Vec<gait_core::Frame> {
            std::iter::from_fn(|| r.next_frame().unwrap()).collect()
        };
        let full = all(info.frames().unwrap());
        let late = all(info.frames_from(7).unwrap());
        assert_eq!(full.len(), 15);
        assert_eq!(late.len(), 8);
        for (a, b) in full[7..].iter().zip(&late) {
            assert_eq!(a.index, b.index);
            assert!(a.image == b.image, "frame {}", a.index);
        }
    }

    #[test]
    fn hostile_ffprobe_descriptions_are_refused() {
        let p = Path::new("clip.mp4");
        let probe = |w: u64, h: u64, rate: &str| {
            let json = format!(
                r#"{{"streams": [{{"width": {w}, "height": {h}, "r_frame_rate": "{rate}", "nb_frames": "1000000000"}}]}}"#
            );
            parse_ffprobe(p, json.as_bytes()).map_err(|e| e.to_string())
        };
        let ok = probe(1768, 994, "30/1").unwrap();
        assert_eq!((ok.width, ok.height, ok.fps), (1768, 994, 30.0));
        assert!(
            probe(100_000, 100_000, "30/1")
                .unwrap_err()
                .contains("at most 8192x8192")
        );
        // A width past u32 is no frame size, not a wrapped one.
        assert!(
            probe(1 << 33, 10, "30/1")
                .unwrap_err()
                .contains("no frame size")
        );
        for rate in ["inf/1", "NaN/1", "30/0", "1e300/1e-300"] {
            assert!(
                probe(64, 48, rate).unwrap_err().contains("no frame rate"),
                "{rate}"
            );
        }
    }

    fn ffmpeg(args: &[&str]) {
        let status = Command::new("ffmpeg")
            .args(["-v", "error", "-y"])
            .args(args)
            .status()
            .expect("ffmpeg (tools/setup.sh installs it)");
        assert!(status.success());
    }

    fn all_frames(info: &InputInfo) -> Vec<gait_core::Frame> {
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
        assert!(
            info.decode_warnings()
                .iter()
                .any(|w| w.contains("resampled"))
        );
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
        assert!(
            info.decode_warnings()
                .iter()
                .any(|w| w.contains("HDR (HLG)"))
        );
        let (a, b) = (
            all_frames(&info),
            all_frames(&InputInfo::open(&sdr).unwrap()),
        );
        assert_eq!(a.len(), b.len());
        let diff = |x: &gait_core::Frame, y: &gait_core::Frame| {
            let (p, q) = (x.image.as_raw(), y.image.as_raw());
            p.iter()
                .zip(q)
                .map(|(u, v)| u.abs_diff(*v) as f64)
                .sum::<f64>()
                / p.len() as f64
        };
        let d = diff(&a[0], &b[0]);
        assert!(d < 6.0, "mean difference {d:.1} grey levels");
        // Decoded as standard video, the same frames differ by four times as much (21 levels).
        let as_standard = InputInfo {
            hdr_transfer: None,
            ..info
        };
        let washed = diff(&all_frames(&as_standard)[0], &b[0]);
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
        assert!(
            info.decode_warnings()
                .iter()
                .any(|w| w.contains("interlaced"))
        );
        let woven = InputInfo {
            interlaced: None,
            ..info.clone()
        };
        let (a, b) = (all_frames(&info), all_frames(&woven));
        let truth = all_frames(&InputInfo::open(&top).unwrap());
        assert_eq!((a.len(), b.len()), (truth.len(), truth.len()));
        let diff = |x: &gait_core::Frame, y: &gait_core::Frame| {
            let (p, q) = (x.image.as_raw(), y.image.as_raw());
            p.iter()
                .zip(q)
                .map(|(u, v)| u.abs_diff(*v) as f64)
                .sum::<f64>()
                / p.len() as f64
        };
        let (after, before) = (diff(&a[10], &truth[10]), diff(&b[10], &truth[10]));
        assert!(
            after < 0.7 * before,
            "{before:.1} -> {after:.1} grey levels"
        );
    }

    #[test]
    fn every_accepted_image_extension_decodes() {
        let dir = tempfile::tempdir().unwrap();
        let img =
            image::RgbImage::from_fn(8, 6, |x, y| image::Rgb([x as u8 * 30, y as u8 * 40, 7]));
        for ext in IMAGE_EXTENSIONS {
            let p = dir.path().join(format!("frame.{ext}"));
            img.save(&p).unwrap();
            let info = InputInfo::open(&p).unwrap();
            assert_eq!((info.width, info.height), (8, 6), "{ext}");
            let frame = info.frames().unwrap().next_frame().unwrap().unwrap();
            assert_eq!(frame.width(), 8, "{ext}");
        }
    }

    #[test]
    fn bad_inputs_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let e = InputInfo::open(dir.path()).unwrap_err().to_string();
        assert!(e.contains("no images"), "{e}");
        let e = InputInfo::open(&dir.path().join("nope.mp4"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("no such file"), "{e}");
        let txt = dir.path().join("a.txt");
        std::fs::write(&txt, "x").unwrap();
        assert!(
            InputInfo::open(&txt)
                .unwrap_err()
                .to_string()
                .contains("unsupported")
        );
        let png = dir.path().join("a.png");
        std::fs::write(&png, "not a png").unwrap();
        assert!(
            InputInfo::open(&png)
                .unwrap_err()
                .to_string()
                .contains("unreadable image")
        );
    }
}
