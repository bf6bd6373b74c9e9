//! Inputs: a video file (decoded by the `ffmpeg` command line tool), a folder
//! of images, or a single image, read as a stream of RGB frames.

use std::io::Read;
use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

use crate::PipelineError;
pub use crate::frame_reader::{FrameReader, READ_AHEAD};
use crate::frame_reader::{Source, read_ahead};
use crate::frame_timing::FrameTiming;
pub use crate::probe::{MAX_FRAME_PIXELS, ffprobe_command, parse_ffprobe};
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
    /// How a 4:2:0 video's frames become RGB here rather than in ffmpeg (yuv.rs), when they can.
    pub(crate) yuv: Option<crate::yuv::Yuv420>,
    /// Whether ffmpeg converts this input's frames as yuv.rs does (shared by the readers).
    pub(crate) yuv_verdict: crate::video_decoder::YuvVerdict,
    /// Frames the first reader keeps for the others (shared by the readers).
    pub(crate) spool: crate::frame_spool::FrameSpool,
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
            return crate::probe::probe_video(path);
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
            yuv: None,
            yuv_verdict: Default::default(),
            spool: Default::default(),
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
            ..self.request()
        })
    }

    /// As [`Self::frames`], from frame `from` on: the frames before it are
    /// not read (a video's are decoded but not converted or sent).
    pub fn frames_from(&self, from: usize) -> Result<FrameReader, PipelineError> {
        self.frames_as(Request {
            from,
            ..self.request()
        })
    }

    /// How every pass decodes this video: its stream, its frames resampled to a constant rate,
    /// converted to standard range and deinterlaced where it needs it; all frames, full size.
    pub(crate) fn request(&self) -> Request {
        let standard_range = self
            .hdr_transfer
            .as_deref()
            .and_then(crate::picture::to_standard_range);
        Request {
            size: None,
            from: 0,
            resample: self.resampled_fps(),
            stream: self.stream,
            standard_range,
            deinterlace: self
                .interlaced
                .as_deref()
                .and_then(crate::picture::deinterlace),
            // The tone mapping's output is not the file's 4:2:0.
            yuv: self.yuv.filter(|_| standard_range.is_none()),
            check: false,
            frames: None,
        }
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
                let kept = req.size.is_none().then(|| self.spool.kept()).flatten();
                let source = match kept {
                    Some(kept) => Source::Kept(kept, Vec::new()),
                    None => Source::Video(Box::new(self.decoder(req)?)),
                };
                let inner = FrameReader {
                    source,
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

    /// ffmpeg decoding this video as `req` asks. A reader of every frame at full size keeps
    /// them for the readers after it when [`Self::keep_frames`] asked for it.
    pub(crate) fn decoder(&self, req: Request) -> Result<VideoDecoder, PipelineError> {
        // Scaled frames come as ffmpeg scales them, in rgb24.
        let req = match req.size {
            Some(_) => Request { yuv: None, ..req },
            None => self.yuv_verdict.settle(req),
        };
        let mut decoder = VideoDecoder::spawn(&self.path, req, self.yuv_verdict.clone())?;
        if let (None, 0, Some(yuv)) = (req.size, req.from, req.yuv) {
            let len = crate::yuv::Yuv420::frame_len(self.width as usize, self.height as usize);
            if let Some(writer) = self.spool.writer(yuv, len, self.frames) {
                decoder.keep_frames(writer);
            }
        }
        Ok(decoder)
    }

    /// The next reader of every frame (the subject pass's) keeps them in a temporary file
    /// (frame_spool.rs), and the readers after it read them there instead of decoding again.
    pub(crate) fn keep_frames(&self) {
        if self.kind == Kind::Video {
            self.spool.arm();
        }
    }

    /// Frees the frames kept since [`Self::keep_frames`].
    pub(crate) fn release_kept_frames(&self) {
        self.spool.release();
    }

    /// Reads the frames of a recorded ffmpeg run as if ffmpeg decoded this video now (for the
    /// fuzzer and tests, which drive the reader without a process).
    pub fn replay(&self, recording: DecoderRecording) -> FrameReader {
        FrameReader {
            info: self.clone(),
            source: Source::Video(Box::new(VideoDecoder::replay(&self.path, recording))),
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
