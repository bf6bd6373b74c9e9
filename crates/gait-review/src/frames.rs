//! The frames the page shows: the input video decoded once, in the background, into JPEG
//! images held in memory; the regenerated frames read once from the run's cache.

use std::collections::HashMap;
use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;

use gait_core::Frame;
use gait_pipeline::input::InputInfo;
use jpeg_encoder::{ColorType, Encoder, SamplingFactor};

/// JPEG quality of the frames sent to the page: keypoints stay placeable to a pixel.
const JPEG_QUALITY: u8 = 85;

/// Decoded frames waiting for an encoder (bounds the memory of raw frames).
const QUEUE: usize = 4;

/// How long a request waits for the decoder to reach its frame.
const WAIT: Duration = Duration::from_secs(60);

#[derive(Default)]
struct Decoded {
    jpeg: HashMap<usize, Arc<Vec<u8>>>,
    finished: bool,
    error: Option<String>,
}

/// Original frames by input frame number, decoded once by a background thread.
#[derive(Clone)]
pub struct FrameStore {
    shared: Arc<(Mutex<Decoded>, Condvar)>,
    frames: RangeInclusive<usize>,
}

/// A frame could not be had; the message is for the page.
#[derive(Debug)]
pub struct NoFrame(pub String);

impl FrameStore {
    /// Starts decoding `frames` of `video` in the background.
    pub fn start(video: PathBuf, frames: RangeInclusive<usize>) -> Self {
        let store = FrameStore {
            shared: Arc::new((Mutex::new(Decoded::default()), Condvar::new())),
            frames,
        };
        let worker = store.clone();
        std::thread::spawn(move || {
            let result = worker.decode(&video);
            let (lock, cvar) = &*worker.shared;
            let mut d = lock.lock().unwrap_or_else(|p| p.into_inner());
            d.finished = true;
            d.error = result.err();
            cvar.notify_all();
        });
        store
    }

    /// Decodes in this thread (the pipeline's reader, so frame numbers are the run's) and
    /// encodes on the other cores.
    fn decode(&self, video: &Path) -> Result<(), String> {
        let info = InputInfo::open(video).map_err(|e| e.to_string())?;
        let mut reader = info.frames().map_err(|e| e.to_string())?;
        let (tx, rx) = std::sync::mpsc::sync_channel::<Frame>(QUEUE);
        let rx = Arc::new(Mutex::new(rx));
        let cores = std::thread::available_parallelism().map_or(2, |n| n.get());
        let encoders: Vec<_> = (0..cores.saturating_sub(1).max(1))
            .map(|_| {
                let (rx, store) = (rx.clone(), self.clone());
                std::thread::spawn(move || store.encode_from(&rx))
            })
            .collect();
        let mut result = Ok(());
        loop {
            match reader.next_frame() {
                Ok(Some(f)) if f.index > *self.frames.end() => break,
                Ok(Some(f)) if f.index < *self.frames.start() => continue,
                Ok(Some(f)) => {
                    if tx.send(f).is_err() {
                        break;
                    }
                }
                Ok(None) => break,
                Err(e) => {
                    result = Err(e.to_string());
                    break;
                }
            }
        }
        drop(tx);
        for e in encoders {
            match e.join() {
                Ok(Err(m)) => result = result.and(Err(m)),
                Err(_) => result = result.and(Err("a frame encoder stopped".into())),
                Ok(Ok(())) => {}
            }
        }
        result
    }

    fn encode_from(&self, rx: &Mutex<std::sync::mpsc::Receiver<Frame>>) -> Result<(), String> {
        loop {
            let next = rx.lock().unwrap_or_else(|p| p.into_inner()).recv();
            let Ok(frame) = next else {
                return Ok(());
            };
            let jpeg = encode(&frame).map_err(|e| format!("frame {}: {e}", frame.index))?;
            let (lock, cvar) = &*self.shared;
            let mut d = lock.lock().unwrap_or_else(|p| p.into_inner());
            d.jpeg.insert(frame.index, Arc::new(jpeg));
            cvar.notify_all();
        }
    }

    /// The JPEG of input frame `n`, waiting for the decoder to reach it.
    pub fn get(&self, n: usize) -> Result<Arc<Vec<u8>>, NoFrame> {
        if !self.frames.contains(&n) {
            return Err(NoFrame(format!(
                "frame {n} is outside the run (frames {}-{})",
                self.frames.start(),
                self.frames.end()
            )));
        }
        let (lock, cvar) = &*self.shared;
        let d = lock.lock().unwrap_or_else(|p| p.into_inner());
        let (d, _) = cvar
            .wait_timeout_while(d, WAIT, |d| !d.finished && !d.jpeg.contains_key(&n))
            .unwrap_or_else(|p| p.into_inner());
        if let Some(j) = d.jpeg.get(&n) {
            return Ok(j.clone());
        }
        Err(NoFrame(match (&d.error, d.finished) {
            (Some(e), _) => format!("the video could not be decoded: {e}"),
            (None, true) => format!("the video has no frame {n}"),
            (None, false) => format!("frame {n} is still being decoded; try again"),
        }))
    }
}

fn encode(frame: &Frame) -> Result<Vec<u8>, String> {
    let (w, h) = frame.image.dimensions();
    let (Ok(w16), Ok(h16)) = (u16::try_from(w), u16::try_from(h)) else {
        return Err(format!("{w}x{h} is larger than a JPEG can hold (65535)"));
    };
    let mut jpeg = Vec::new();
    let mut e = Encoder::new(&mut jpeg, JPEG_QUALITY);
    e.set_sampling_factor(SamplingFactor::F_2_2);
    e.encode(frame.image.as_raw(), w16, h16, ColorType::Rgb)
        .map_err(|e| e.to_string())?;
    Ok(jpeg)
}

/// Regenerated frames read from the run's cache folder once, then kept.
#[derive(Clone)]
pub struct RegeneratedStore {
    dir: PathBuf,
    cache: Arc<Mutex<HashMap<usize, Arc<Vec<u8>>>>>,
}

impl RegeneratedStore {
    pub fn new(dir: PathBuf) -> Self {
        RegeneratedStore {
            dir,
            cache: Arc::default(),
        }
    }

    /// The PNG of input frame `n`, when the regenerator made one (frames whose original pose was
    /// kept have none).
    pub fn get(&self, n: usize) -> Option<Arc<Vec<u8>>> {
        let mut cache = self.cache.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(b) = cache.get(&n) {
            return Some(b.clone());
        }
        // The name is built from a number only: no path from the request reaches the disk.
        let path = self.dir.join(format!("{n:06}.png"));
        let bytes = Arc::new(gait_pipeline::read_cache_entry(&path)?);
        cache.insert(n, bytes.clone());
        Some(bytes)
    }

    /// Frame numbers with a regenerated image.
    pub fn frames(&self) -> Vec<usize> {
        let Ok(entries) = std::fs::read_dir(&self.dir) else {
            return Vec::new();
        };
        let mut v: Vec<usize> = entries
            .filter_map(|e| {
                let name = e.ok()?.file_name().into_string().ok()?;
                name.strip_suffix(".png")?.parse().ok()
            })
            .collect();
        v.sort_unstable();
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three 40x30 PNG frames in a folder (an image-folder input), frame k grey level 60k.
    fn folder() -> tempfile::TempDir {
        let dir = tempfile::tempdir().unwrap();
        for k in 0..3u8 {
            let img = image::RgbImage::from_pixel(40, 30, image::Rgb([60 * k, 60 * k, 60 * k]));
            img.save(dir.path().join(format!("f{k}.png"))).unwrap();
        }
        dir
    }

    #[test]
    fn frames_are_jpegs_of_the_input_and_only_those_of_the_run() {
        let dir = folder();
        let store = FrameStore::start(dir.path().to_path_buf(), 1..=2);
        for k in 1..=2usize {
            let jpeg = store.get(k).unwrap();
            let back = image::load_from_memory(&jpeg).unwrap().to_rgb8();
            assert_eq!(back.dimensions(), (40, 30));
            let level = back.get_pixel(20, 15)[0] as i32;
            assert!((level - 60 * k as i32).abs() <= 2, "frame {k}: {level}");
        }
        let e = store.get(0).unwrap_err();
        assert!(e.0.contains("outside the run (frames 1-2)"), "{}", e.0);
        assert!(store.get(3).is_err());
    }

    #[test]
    fn a_video_shorter_than_the_run_says_so() {
        let dir = folder();
        let store = FrameStore::start(dir.path().to_path_buf(), 0..=5);
        let e = store.get(4).unwrap_err();
        assert!(e.0.contains("has no frame 4"), "{}", e.0);
    }

    #[test]
    fn regenerated_frames_are_found_by_number_only() {
        let dir = tempfile::tempdir().unwrap();
        for name in ["000007.png", "000012.png", "notes.txt", "x.png"] {
            let entry = gait_pipeline::cache_entry_bytes(name.as_bytes().to_vec());
            std::fs::write(dir.path().join(name), entry).unwrap();
        }
        // Without its checksum (cut short), an entry is not served.
        std::fs::write(dir.path().join("000009.png"), b"000009.png").unwrap();
        let store = RegeneratedStore::new(dir.path().to_path_buf());
        assert_eq!(store.frames(), vec![7, 9, 12]);
        assert_eq!(store.get(7).unwrap().as_slice(), b"000007.png");
        assert!(store.get(8).is_none());
        assert!(store.get(9).is_none());
        // Served from memory once read.
        std::fs::remove_file(dir.path().join("000007.png")).unwrap();
        assert!(store.get(7).is_some());
    }
}
