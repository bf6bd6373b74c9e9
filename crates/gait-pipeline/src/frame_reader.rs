//! Reading an input's frames in order: a video's decoded ahead on a thread of
//! its own, stills read one by one (see [`crate::input::InputInfo::frames`]).

use std::path::PathBuf;

use gait_core::Frame;

use crate::frame_spool::KeptFrames;
use crate::input::InputInfo;
use crate::video_decoder::VideoDecoder;
use crate::{PipelineError, still};

pub(crate) enum Source {
    Video(Box<VideoDecoder>),
    Images(Vec<PathBuf>),
    /// Frames an earlier reader kept (frame_spool.rs), with a buffer for their planes; the
    /// frames after them are decoded.
    Kept(std::sync::Arc<KeptFrames>, Vec<u8>),
    /// Frames decoded ahead by another reader on its own thread.
    Ahead(std::sync::mpsc::Receiver<Result<Option<Frame>, PipelineError>>),
}

/// Frames decoded ahead of the caller (each a whole frame: 6 MB at 1080p).
pub const READ_AHEAD: usize = 1;

/// `inner`'s frames, read on a thread into a queue of [`READ_AHEAD`]. The
/// thread ends at the end of the video, at an error, or when the receiver is
/// dropped (the decoder with it).
pub(crate) fn read_ahead(
    mut inner: FrameReader,
) -> std::sync::mpsc::Receiver<Result<Option<Frame>, PipelineError>> {
    let (tx, rx) = std::sync::mpsc::sync_channel(READ_AHEAD);
    std::thread::spawn(move || {
        loop {
            let frame = inner.read_frame();
            let last = !matches!(frame, Ok(Some(_)));
            if tx.send(frame).is_err() || last {
                break;
            }
        }
    });
    rx
}

/// Yields frames in input order.
pub struct FrameReader {
    pub(crate) info: InputInfo,
    pub(crate) source: Source,
    pub(crate) next: usize,
}

impl FrameReader {
    /// The next frame, `Ok(None)` at the end.
    pub fn next_frame(&mut self) -> Result<Option<Frame>, PipelineError> {
        let t = std::time::Instant::now();
        let frame = self.read_frame();
        let nanos = t.elapsed().as_nanos() as u64;
        self.info
            .reading
            .0
            .fetch_add(nanos, std::sync::atomic::Ordering::Relaxed);
        frame
    }

    fn read_frame(&mut self) -> Result<Option<Frame>, PipelineError> {
        let index = self.next;
        let image = match &mut self.source {
            Source::Ahead(rx) => {
                // A closed queue: the thread ended after the last frame or an error it sent.
                return rx.recv().unwrap_or(Ok(None));
            }
            Source::Images(files) => {
                let Some(path) = files.get(index) else {
                    return Ok(None);
                };
                let still = still::read(path).map_err(|e| PipelineError::input(path, e))?;
                if let Some(w) = still.warning {
                    let name = path.file_name().unwrap_or_default().to_string_lossy();
                    self.info.decode_warnings.add(format!(
                        "{name}: damaged JPEG, decoded as OpenCV does ({w})"
                    ));
                }
                let img = still.image;
                if (img.width(), img.height()) != (self.info.width, self.info.height) {
                    return Err(PipelineError::input(
                        path,
                        format!(
                            "image is {}x{} but the first image is {}x{}; all frames must have one size",
                            img.width(),
                            img.height(),
                            self.info.width,
                            self.info.height
                        ),
                    ));
                }
                img
            }
            Source::Kept(kept, planes) => {
                let size = (self.info.width as usize, self.info.height as usize);
                let mut buf = Vec::with_capacity(size.0 * size.1 * 3);
                let read = kept
                    .read(index, size, planes, &mut buf)
                    .map_err(|e| PipelineError::input(&self.info.path, e))?;
                if !read {
                    if kept.ended() {
                        return Ok(None);
                    }
                    let from = crate::video_decoder::Request {
                        from: index,
                        ..self.info.request()
                    };
                    self.source = Source::Video(Box::new(self.info.decoder(from)?));
                    return self.read_frame();
                }
                image::RgbImage::from_raw(self.info.width, self.info.height, buf).ok_or_else(
                    || PipelineError::input(&self.info.path, "frame buffer size mismatch"),
                )?
            }
            Source::Video(decoder) => {
                let size = (self.info.width as usize, self.info.height as usize);
                let len = size.0 * size.1 * 3;
                let mut buf = Vec::with_capacity(len);
                match decoder.read_frame(&mut buf, size)? {
                    0 => {
                        decoder.finish(index)?;
                        return Ok(None);
                    }
                    n if n < len => {
                        return Err(PipelineError::input(
                            &self.info.path,
                            format!("frame {index} is truncated; the video is damaged"),
                        ));
                    }
                    _ => {}
                }
                image::RgbImage::from_raw(self.info.width, self.info.height, buf).ok_or_else(
                    || PipelineError::input(&self.info.path, "frame buffer size mismatch"),
                )?
            }
        };
        self.next += 1;
        Ok(Some(Frame::new(index, image)))
    }
}
