//! ffmpeg decoding a video to raw RGB frames on a pipe.
//!
//! ffmpeg's messages are read on their own thread while frames are read here: a damaged video
//! makes ffmpeg report an error per frame, and once a pipe's 64 KiB fill up, a reader that
//! left them unread waits on the frame pipe while ffmpeg waits on the message pipe, forever.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::thread::JoinHandle;

use crate::PipelineError;

/// ffmpeg's messages kept for the error (the first line is what the user sees).
const MAX_MESSAGES: usize = 64 * 1024;

/// A running ffmpeg decoding one video.
pub(crate) struct VideoDecoder {
    path: PathBuf,
    child: Child,
    messages: Option<JoinHandle<String>>,
}

impl VideoDecoder {
    pub(crate) fn spawn(path: &Path) -> Result<Self, PipelineError> {
        let mut child = Command::new("ffmpeg")
            .args(["-v", "error", "-nostdin", "-i"])
            .arg(path)
            .args(["-f", "rawvideo", "-pix_fmt", "rgb24", "-"])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| crate::input::ffmpeg_missing(path, e))?;
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
        Ok(VideoDecoder {
            path: path.to_path_buf(),
            child,
            messages,
        })
    }

    /// Fills `buf` with the next frame: the bytes read (0 at the end of the output).
    pub(crate) fn read_frame(&mut self, buf: &mut [u8]) -> Result<usize, PipelineError> {
        let stdout = self
            .child
            .stdout
            .as_mut()
            .ok_or_else(|| PipelineError::input(&self.path, "ffmpeg has no output"))?;
        let mut filled = 0;
        while filled < buf.len() {
            match stdout.read(&mut buf[filled..]) {
                Ok(0) => break,
                Ok(n) => filled += n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(PipelineError::input(&self.path, e)),
            }
        }
        Ok(filled)
    }

    /// At the end of ffmpeg's output after `frames` frames: a clean end, or the decoder's error.
    pub(crate) fn finish(&mut self, frames: usize) -> Result<(), PipelineError> {
        let status = self
            .child
            .wait()
            .map_err(|e| PipelineError::input(&self.path, e))?;
        let err = self
            .messages
            .take()
            .and_then(|h| h.join().ok())
            .unwrap_or_default();
        if !status.success() || (frames == 0 && !err.trim().is_empty()) {
            let first = err
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

impl Drop for VideoDecoder {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
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
