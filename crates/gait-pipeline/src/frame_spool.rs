//! Decoded frames kept for a later pass. The subject pass reads every frame of a video and the
//! pose pass most of them again; decoding a 1768 x 994 H.264 frame costs ffmpeg about 4 ms of
//! CPU, reading it back from a file in the page cache a fraction of that. The first reader of
//! the whole video (the subject pass's) writes each yuv420p frame it gets from ffmpeg to an
//! anonymous temporary file (it has no name: the system removes it when the run ends, killed or
//! not); the readers after it read the frames there and convert them as the decoder's reader
//! does (yuv.rs), so they get the same bytes. Frames the file does not hold are decoded again.

use std::fs::File;
use std::io::Write;
use std::sync::{Arc, Condvar, Mutex, PoisonError};
use std::time::Duration;

use crate::yuv::Yuv420;

/// The most the kept frames may take: 2 GiB is about 690 frames of 1080p (23 s at 30 fps), so
/// a clinic's pass fits, and a long recording is decoded twice as before.
const MAX_BYTES: u64 = 2 << 30;

/// The share of the temporary folder's free space the kept frames may take (1 / this).
const FREE_SHARE: u64 = 4;

/// Frames stop being kept once the folder's free space falls under this share of what it was
/// when they started (1 / this): runs side by side (a batch) each see the same free space at
/// their start, and together they must not fill the disk the results are written to.
const FLOOR_SHARE: u64 = 2;

/// How long a later reader waits for the writer to hand over its frames (it only has to see
/// its receiver dropped and finish the frame it was decoding).
const HANDOVER_WAIT: Duration = Duration::from_secs(2);

/// Frames written by one reader, readable by the others.
pub(crate) struct KeptFrames {
    file: File,
    frame_len: usize,
    frames: usize,
    /// Whether the writer read the video to its end (else frames after these are decoded).
    ended: bool,
    yuv: Yuv420,
}

impl KeptFrames {
    /// Frame `index` converted to rgb24 into `out` (`planes` is scratch); false when the file
    /// does not hold it.
    pub(crate) fn read(
        &self,
        index: usize,
        (width, height): (usize, usize),
        planes: &mut Vec<u8>,
        out: &mut Vec<u8>,
    ) -> std::io::Result<bool> {
        if index >= self.frames {
            return Ok(false);
        }
        planes.resize(self.frame_len, 0);
        read_at(&self.file, planes, (index * self.frame_len) as u64)?;
        self.yuv.convert(planes, width, height, out);
        Ok(true)
    }

    /// Whether the video has no frames after those kept.
    pub(crate) fn ended(&self) -> bool {
        self.ended
    }
}

#[cfg(unix)]
fn read_at(file: &File, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
    std::os::unix::fs::FileExt::read_exact_at(file, buf, offset)
}

#[cfg(not(unix))]
fn read_at(_: &File, _: &mut [u8], _: u64) -> std::io::Result<()> {
    Err(std::io::ErrorKind::Unsupported.into())
}

#[derive(Default)]
enum State {
    /// Frames are not kept.
    #[default]
    Off,
    /// The next reader of every frame keeps them.
    Armed,
    /// A reader is keeping them.
    Writing,
    Kept(Arc<KeptFrames>),
}

/// Where one input's kept frames are, shared by its readers.
#[derive(Clone, Default)]
pub(crate) struct FrameSpool(Arc<(Mutex<State>, Condvar)>);

impl std::fmt::Debug for FrameSpool {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("FrameSpool")
    }
}

impl PartialEq for FrameSpool {
    /// Whether frames are kept does not make two inputs different.
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl FrameSpool {
    fn state(&self) -> std::sync::MutexGuard<'_, State> {
        self.0.0.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// The next reader of every frame keeps them for the readers after it.
    pub(crate) fn arm(&self) {
        let mut state = self.state();
        if matches!(*state, State::Off) {
            *state = State::Armed;
        }
    }

    /// Frees the kept frames (the file goes when the last reader of it ends).
    pub(crate) fn release(&self) {
        *self.state() = State::Off;
        self.0.1.notify_all();
    }

    /// A writer for a reader of every frame, when armed and the frames fit.
    pub(crate) fn writer(
        &self,
        yuv: Yuv420,
        frame_len: usize,
        expected_frames: Option<usize>,
    ) -> Option<SpoolWriter> {
        let mut state = self.state();
        if !matches!(*state, State::Armed) {
            return None;
        }
        *state = State::Off;
        let dir = std::env::temp_dir();
        let free = free_bytes(&dir)?;
        let budget = MAX_BYTES.min(free / FREE_SHARE);
        if expected_frames.is_some_and(|n| (n * frame_len) as u64 > budget) {
            return None;
        }
        let file = tempfile::tempfile_in(&dir).ok()?;
        *state = State::Writing;
        Some(SpoolWriter {
            spool: self.clone(),
            file: Some(file),
            frame_len,
            frames: 0,
            budget,
            dir,
            floor: free / FLOOR_SHARE,
            ended: false,
            yuv,
        })
    }

    /// The kept frames, once their writer has handed them over.
    pub(crate) fn kept(&self) -> Option<Arc<KeptFrames>> {
        let state = self.state();
        let (state, _) = self
            .0
            .1
            .wait_timeout_while(state, HANDOVER_WAIT, |s| matches!(s, State::Writing))
            .unwrap_or_else(PoisonError::into_inner);
        match &*state {
            State::Kept(kept) => Some(kept.clone()),
            _ => None,
        }
    }
}

#[cfg(unix)]
fn free_bytes(dir: &std::path::Path) -> Option<u64> {
    let fs = rustix::fs::statvfs(dir).ok()?;
    Some(fs.f_bavail.saturating_mul(fs.f_frsize))
}

#[cfg(not(unix))]
fn free_bytes(_: &std::path::Path) -> Option<u64> {
    None
}

/// Keeps the frames one reader gets; hands them over when dropped.
pub(crate) struct SpoolWriter {
    spool: FrameSpool,
    /// `None` once abandoned (over budget, a write failed, the frames are not these).
    file: Option<File>,
    frame_len: usize,
    frames: usize,
    budget: u64,
    /// The folder, and the free space under which nothing more is written there.
    dir: std::path::PathBuf,
    floor: u64,
    ended: bool,
    yuv: Yuv420,
}

impl SpoolWriter {
    /// Keeps the next frame's yuv420p planes.
    pub(crate) fn push(&mut self, planes: &[u8]) {
        let room = free_bytes(&self.dir)
            .is_some_and(|f| f >= self.floor.saturating_add(planes.len() as u64));
        let fits = room && ((self.frames + 1) * self.frame_len) as u64 <= self.budget;
        let written = fits
            && planes.len() == self.frame_len
            && self
                .file
                .as_mut()
                .is_some_and(|f| f.write_all(planes).is_ok());
        if written {
            self.frames += 1;
        } else {
            self.file = None;
        }
    }

    /// The frames are not those the readers would decode: none is kept.
    pub(crate) fn abandon(&mut self) {
        self.file = None;
    }

    /// The video ended after the frames kept.
    pub(crate) fn end(&mut self) {
        self.ended = true;
    }
}

impl Drop for SpoolWriter {
    fn drop(&mut self) {
        let mut state = self.spool.state();
        if matches!(*state, State::Writing) {
            *state = match self.file.take() {
                Some(file) if self.frames > 0 => State::Kept(Arc::new(KeptFrames {
                    file,
                    frame_len: self.frame_len,
                    frames: self.frames,
                    ended: self.ended,
                    yuv: self.yuv,
                })),
                _ => State::Off,
            };
        }
        self.spool.0.1.notify_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn writer(spool: &FrameSpool) -> SpoolWriter {
        let yuv = Yuv420::of_stream(Some("yuv420p"), Some("bt709"), None, (4, 2)).unwrap();
        spool.arm();
        spool.writer(yuv, Yuv420::frame_len(4, 2), Some(2)).unwrap()
    }

    #[test]
    fn frames_are_kept_until_the_disk_s_free_space_falls_to_its_floor() {
        let spool = FrameSpool::default();
        let mut w = writer(&spool);
        w.push(&[16; 12]);
        w.end();
        drop(w);
        let kept = spool.kept().expect("kept");
        let (mut planes, mut out) = (Vec::new(), Vec::new());
        assert!(kept.read(0, (4, 2), &mut planes, &mut out).unwrap() && kept.ended());
        assert!(!kept.read(1, (4, 2), &mut planes, &mut out).unwrap());
        // Free space under the floor (another run filled the disk): nothing is kept.
        let spool = FrameSpool::default();
        let mut w = writer(&spool);
        w.floor = u64::MAX - 12;
        w.push(&[16; 12]);
        drop(w);
        assert!(spool.kept().is_none());
    }
}
