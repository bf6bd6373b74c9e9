//! `overlay.mp4`: the input video with the tracked skeleton drawn over it,
//! so a clinician can see what the analysis saw.
//!
//! Each frame shows the skeleton in side colours (left red, right blue), the
//! frame number and time, heel strikes and toe-offs as they happen, and is
//! dimmed (with the reason) outside walking bouts and in rejected cycles.
//! [`Layout::SideBySide`] shows original | regenerated | keypoints, as in
//! the paper's Figure 1.
//!
//! ```no_run
//! # fn frames() -> Vec<image::RgbImage> { vec![] }
//! use gait_overlay::{OverlayOptions, OverlayWriter, marks_from_run_dir};
//! let run = marks_from_run_dir("runs/sample".as_ref())?;
//! let opts = OverlayOptions::default();
//! let (mut w, warnings) =
//!     OverlayWriter::start("runs/sample/overlay.mp4".as_ref(), 1768, 994, run.fps, &run.names, &opts)?;
//! // frames(): the input frames run.marks[i].frame, decoded by the caller.
//! for (img, m) in frames().iter().zip(&run.marks) {
//!     w.push(img, None, m)?;
//! }
//! w.finish()?;
//! # Ok::<(), gait_overlay::OverlayError>(())
//! ```
//!
//! Frames are drawn into RGB24 buffers and piped to an `ffmpeg` process
//! (libx264, or mpeg4 when the ffmpeg lacks it). The file is written under a
//! temporary name and renamed on [`OverlayWriter::finish`], so an interrupted
//! run never leaves a broken `overlay.mp4`.

mod canvas;
mod draw;
mod encode;
mod error;
mod layout;
mod marks;
mod text;

use std::path::{Path, PathBuf};

use gait_core::Pose;
use image::RgbImage;

pub use draw::{CENTRE_COLOUR, LEFT_COLOUR, RIGHT_COLOUR, side_colour};
pub use error::OverlayError;
pub use layout::DIM_FACTOR;
pub use marks::{CycleSpan, EventAt, LABEL_SECONDS, RunMarks, marks_from_run_dir, plan_marks};

/// A body side.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Side {
    Left,
    Right,
}

impl Side {
    /// `left` or `right`, as the run's CSV files spell it.
    pub fn name(self) -> &'static str {
        match self {
            Side::Left => "left",
            Side::Right => "right",
        }
    }

    /// `L` or `R`, for labels.
    pub fn letter(self) -> char {
        match self {
            Side::Left => 'L',
            Side::Right => 'R',
        }
    }
}

/// A gait event.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EventKind {
    HeelStrike,
    ToeOff,
}

/// An event whose label is showing in a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EventMark {
    pub side: Side,
    pub kind: EventKind,
    /// Frames since the event (0 on the event's own frame).
    pub age_frames: usize,
}

/// What one frame shows besides the video.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FrameMarks {
    /// Index of the frame in the input.
    pub frame: usize,
    pub time_s: f64,
    /// The pose to draw (keypoints in input pixels); `None`: nobody found.
    pub pose: Option<Pose>,
    /// Events whose label is showing in this frame.
    pub events: Vec<EventMark>,
    /// `Some(reason)`: the frame is dimmed and captioned with the reason.
    pub dim: Option<String>,
}

/// What the keypoints panel of [`Layout::SideBySide`] is drawn on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Backdrop {
    /// A near-black background: the skeleton alone.
    #[default]
    Dark,
    /// The original frame.
    Original,
}

/// How frames are laid out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Layout {
    /// The input frame with the skeleton over it, at the input's size.
    #[default]
    Skeleton,
    /// Original | regenerated | keypoints side by side (zero-shot runs);
    /// panels are halved when the input is wider than 1280 pixels.
    SideBySide { backdrop: Backdrop },
}

/// Which video encoder to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Encoder {
    /// libx264 when the ffmpeg has it, else mpeg4 with a warning.
    #[default]
    Auto,
    /// libx264 or an error.
    Libx264,
    /// mpeg4 (MPEG-4 Part 2, `-q:v 3`), e.g. to test the fallback.
    Mpeg4,
}

/// Settings of [`OverlayWriter::start`].
#[derive(Debug, Clone, PartialEq)]
pub struct OverlayOptions {
    pub layout: Layout,
    pub encoder: Encoder,
    /// libx264 preset; `veryfast` keeps 1080p at 30 fps or better on two cores.
    pub preset: String,
    /// The ffmpeg program (default `ffmpeg`, found on PATH).
    pub ffmpeg: PathBuf,
    /// Taller frames are encoded scaled down to this height (the report shows the
    /// video 960 px wide; encoding a 1080p frame costs twice a 720p one).
    pub max_height: Option<u32>,
}

impl Default for OverlayOptions {
    fn default() -> Self {
        Self {
            layout: Layout::default(),
            encoder: Encoder::default(),
            preset: "veryfast".into(),
            ffmpeg: PathBuf::from("ffmpeg"),
            max_height: Some(720),
        }
    }
}

/// The size a skeleton overlay of `width` x `height` frames is encoded at
/// (scaled down to `opts.max_height`); frames may be pushed at that size.
pub fn encoded_size(width: u32, height: u32, opts: &OverlayOptions) -> (u32, u32) {
    let (w, h) = encode::scaled((width as usize, height as usize), opts.max_height);
    (w as u32, h as u32)
}

/// Encodes frames with their marks into an MP4 file.
pub struct OverlayWriter {
    composer: layout::Composer,
    /// The encoded size (the composed frames scaled down, or as composed).
    size: (usize, usize),
    ffmpeg: Option<encode::Ffmpeg>,
    tmp: PathBuf,
    path: PathBuf,
    frames: usize,
}

impl OverlayWriter {
    /// Starts ffmpeg for frames of `width` x `height` at `fps`, whose poses
    /// have keypoints `names`; returns warnings (e.g. the mpeg4 fallback).
    pub fn start(
        path: &Path,
        width: u32,
        height: u32,
        fps: f64,
        names: &[String],
        opts: &OverlayOptions,
    ) -> Result<(Self, Vec<String>), OverlayError> {
        let rate = encode::rate(fps)?;
        let composer = layout::Composer::new(width, height, opts.layout, names)?;
        let Some(file_name) = path.file_name() else {
            return Err(OverlayError::BadInput(format!(
                "{} is not a file path",
                path.display()
            )));
        };
        // ffmpeg would only say so after the first frames: check up front.
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty())
            && !dir.is_dir()
        {
            return Err(OverlayError::BadInput(format!(
                "folder {} does not exist",
                dir.display()
            )));
        }
        let listing = encode::probe_encoders(&opts.ffmpeg)?;
        let (codec, warning) = encode::choose(&listing, opts.encoder)?;
        let tmp = path.with_file_name(format!(".{}.partial", file_name.to_string_lossy()));
        let (w, h) = composer.out_size();
        let size = encode::scaled((w, h), opts.max_height);
        let args = encode::args(codec, &opts.preset, (w, h), size, &rate, &tmp);
        let ffmpeg = encode::Ffmpeg::spawn(&opts.ffmpeg, &args, w * h * 3)?;
        Ok((
            Self {
                composer,
                size,
                ffmpeg: Some(ffmpeg),
                tmp,
                path: path.to_path_buf(),
                frames: 0,
            },
            warning.into_iter().collect(),
        ))
    }

    /// Size of the encoded frames (even; wider for side by side).
    pub fn output_size(&self) -> (u32, u32) {
        (self.size.0 as u32, self.size.1 as u32)
    }

    /// Frames pushed so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Draws and queues one frame. `original` must have the size given to
    /// `start`; `regenerated` (side by side only) may have any size.
    pub fn push(
        &mut self,
        original: &RgbImage,
        regenerated: Option<&RgbImage>,
        marks: &FrameMarks,
    ) -> Result<(), OverlayError> {
        let Some(ff) = self.ffmpeg.as_mut() else {
            return Err(OverlayError::Ffmpeg(
                "the encoder has already failed".into(),
            ));
        };
        let mut buf = ff.buffer()?;
        if let Err(e) = self.composer.render(&mut buf, original, regenerated, marks) {
            ff.recycle(buf);
            return Err(e);
        }
        let sent = ff.send(buf);
        if sent.is_err() {
            // ffmpeg is gone; the temporary file is removed on drop.
            self.ffmpeg = None;
        }
        sent?;
        self.frames += 1;
        Ok(())
    }

    /// Waits for ffmpeg to write the file, then renames it to its final
    /// path; returns that path.
    pub fn finish(mut self) -> Result<PathBuf, OverlayError> {
        if self.frames == 0 {
            return Err(OverlayError::BadInput("no frames were pushed".into()));
        }
        let Some(ff) = self.ffmpeg.take() else {
            return Err(OverlayError::Ffmpeg(
                "the encoder has already failed".into(),
            ));
        };
        ff.finish()?;
        std::fs::rename(&self.tmp, &self.path).map_err(OverlayError::io(format!(
            "renaming {} to {}",
            self.tmp.display(),
            self.path.display()
        )))?;
        Ok(self.path.clone())
    }
}

impl Drop for OverlayWriter {
    /// Unfinished or failed: ffmpeg is stopped and its partial file removed.
    fn drop(&mut self) {
        drop(self.ffmpeg.take());
        let _ = std::fs::remove_file(&self.tmp);
    }
}
