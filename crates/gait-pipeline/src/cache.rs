//! The on-disk per-frame cache. Each stage's results live in a folder named
//! by the hash of the input and of every stage config up to that stage, so
//! changing only the pose stage reuses edges and regenerated images, and an
//! interrupted run resumes at the first frame it had not finished.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use gait_core::{Keypoint, Pose, Resize};
use serde::Serialize;
use serde::de::DeserializeOwned;
use sha2::{Digest, Sha256};

use crate::input::hex;
use crate::{PipelineError, atomic};

/// Chains stage configs into cache keys.
pub(crate) fn chain_key(previous: &str, stage: &str, config: &impl Serialize) -> String {
    let mut h = Sha256::new();
    h.update(previous.as_bytes());
    h.update(b"\0");
    h.update(stage.as_bytes());
    h.update(b"\0");
    h.update(serde_json::to_string(config).unwrap_or_default().as_bytes());
    hex(&h.finalize())
}

/// A stateful stage's saved state in the cache.
pub(crate) enum Saved {
    Ok(Vec<u8>),
    Missing,
    /// There, but truncated or altered (reported as a warning).
    Corrupt,
}

/// One stage's folder in the cache, or nothing when caching is off.
pub(crate) struct StageCache {
    dir: Option<PathBuf>,
    /// Entries found corrupt (and recomputed), for run.json's warnings.
    corrupt: Mutex<Vec<PathBuf>>,
}

/// What ends every entry: this tag and the first 8 bytes of the SHA-256 of
/// the bytes before it, in hex. A truncated or altered entry fails the check.
const SUM_TAG: &[u8] = b"\ngait-sha256:";
const SUM_LEN: usize = SUM_TAG.len() + 16 + 1;

fn with_sum(mut bytes: Vec<u8>) -> Vec<u8> {
    let sum = hex(&Sha256::digest(&bytes)[..8]);
    bytes.extend_from_slice(SUM_TAG);
    bytes.extend_from_slice(sum.as_bytes());
    bytes.push(b'\n');
    bytes
}

/// The verified bytes of the cache entry file at `path` (its checksum taken
/// off); `None` when it is absent, truncated or altered.
pub fn read_entry(path: &Path) -> Option<Vec<u8>> {
    checked(std::fs::read(path).ok()?)
}

/// What a cache entry file holds for `bytes`: them and their checksum.
pub fn entry_bytes(bytes: Vec<u8>) -> Vec<u8> {
    with_sum(bytes)
}

/// The folder of a stage's entries under the cache root, from its key (or
/// the key's first 16 digits, as run.json records it).
pub(crate) fn folder(root: &Path, stage: &str, key: &str) -> PathBuf {
    let short = key.get(..16).unwrap_or(key);
    // Entries carry checksums since this format: a folder name of its own,
    // so entries of the earlier format are not taken for corrupt ones.
    let format_key = hex(&Sha256::digest(
        format!("{short}:checked-entries").as_bytes(),
    ));
    root.join(format!("{stage}-{}", &format_key[..16]))
}

/// The bytes of an entry whose checksum holds.
fn checked(mut bytes: Vec<u8>) -> Option<Vec<u8>> {
    let body = bytes.len().checked_sub(SUM_LEN)?;
    let (data, footer) = bytes.split_at(body);
    let sum = footer.strip_prefix(SUM_TAG)?.strip_suffix(b"\n")?;
    if sum != hex(&Sha256::digest(data)[..8]).as_bytes() {
        return None;
    }
    bytes.truncate(body);
    Some(bytes)
}

impl StageCache {
    pub(crate) fn disabled() -> Self {
        Self {
            dir: None,
            corrupt: Mutex::new(Vec::new()),
        }
    }

    /// One warning per entry that failed its checksum since the last call.
    pub(crate) fn take_warnings(&self) -> Vec<String> {
        let mut corrupt = self.corrupt.lock().unwrap_or_else(|e| e.into_inner());
        corrupt
            .drain(..)
            .map(|p| {
                format!(
                    "cache entry {} failed its checksum (truncated or altered); it was recomputed",
                    p.display()
                )
            })
            .collect()
    }

    /// An entry's bytes: `None` when absent, or corrupt (then noted, to be recomputed).
    fn read(&self, index: usize, ext: &str) -> Option<Vec<u8>> {
        let path = self.file(index, ext)?;
        let bytes = std::fs::read(&path).ok()?;
        let data = checked(bytes);
        if data.is_none() {
            self.corrupt
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .push(path);
        }
        data
    }

    /// Writes an entry (atomically, with its checksum, which a read checks).
    fn write(&self, index: usize, ext: &str, bytes: Vec<u8>) -> Result<(), PipelineError> {
        let Some(path) = self.file(index, ext) else {
            return Ok(());
        };
        atomic::write_unsynced(&path, &with_sum(bytes)).map_err(|e| cache_err(&path, e))
    }

    /// Opens (creating) `<root>/<stage>-<key prefix>`, recording the stage's
    /// config beside the results for people browsing the cache.
    pub(crate) fn open(
        root: &Path,
        stage: &str,
        key: &str,
        config: &impl Serialize,
    ) -> Result<Self, PipelineError> {
        let dir = folder(root, stage, key);
        std::fs::create_dir_all(&dir).map_err(|e| cache_err(&dir, e))?;
        let about = dir.join("config.json");
        if !about.exists() {
            let json = serde_json::to_vec_pretty(config).unwrap_or_default();
            atomic::write(&about, &json).map_err(|e| cache_err(&about, e))?;
        }
        Ok(Self {
            dir: Some(dir),
            corrupt: Mutex::new(Vec::new()),
        })
    }

    fn file(&self, index: usize, ext: &str) -> Option<PathBuf> {
        self.dir
            .as_ref()
            .map(|d| d.join(format!("{index:06}.{ext}")))
    }

    pub(crate) fn load_rgb(&self, index: usize) -> Option<image::RgbImage> {
        let bytes = self.read(index, "png")?;
        image::load_from_memory(&bytes).ok().map(|i| i.to_rgb8())
    }

    pub(crate) fn store_rgb(
        &self,
        index: usize,
        img: &image::RgbImage,
    ) -> Result<(), PipelineError> {
        self.store_png(
            index,
            img.as_raw(),
            img.width(),
            img.height(),
            image::ExtendedColorType::Rgb8,
        )
    }

    /// An edge map and the resize it was made with.
    pub(crate) fn load_edge(&self, index: usize) -> Option<(image::GrayImage, Resize)> {
        let img = image::load_from_memory(&self.read(index, "png")?)
            .ok()?
            .to_luma8();
        let json = self.read(index, "json")?;
        Some((img, serde_json::from_slice(&json).ok()?))
    }

    pub(crate) fn store_edge(
        &self,
        index: usize,
        img: &image::GrayImage,
        resize: &Resize,
    ) -> Result<(), PipelineError> {
        self.write(
            index,
            "json",
            serde_json::to_vec(resize).unwrap_or_default(),
        )?;
        self.store_png(
            index,
            img.as_raw(),
            img.width(),
            img.height(),
            image::ExtendedColorType::L8,
        )
    }

    fn store_png(
        &self,
        index: usize,
        raw: &[u8],
        w: u32,
        h: u32,
        color: image::ExtendedColorType,
    ) -> Result<(), PipelineError> {
        let mut png = Vec::new();
        let encoded = image::ImageEncoder::write_image(
            image::codecs::png::PngEncoder::new(&mut png),
            raw,
            w,
            h,
            color,
        );
        if let Err(e) = encoded {
            let path = self.file(index, "png").unwrap_or_default();
            return Err(cache_err(&path, std::io::Error::other(e)));
        }
        self.write(index, "png", png)
    }

    /// A pose with `n` keypoints; a file of another length is ignored.
    pub(crate) fn load_pose(&self, index: usize, n: usize) -> Option<Pose> {
        let json = self.read(index, "json")?;
        let rows: Vec<Option<[f64; 3]>> = serde_json::from_slice(&json).ok()?;
        (rows.len() == n).then(|| Pose {
            keypoints: rows
                .into_iter()
                .map(|r| r.map_or_else(Keypoint::missing, |[x, y, l]| Keypoint::new(x, y, l)))
                .collect(),
        })
    }

    /// A stateful stage's state saved after frame `index`, telling a state never saved from one
    /// that failed its checksum.
    pub(crate) fn saved_state(&self, index: usize) -> Saved {
        match self.file(index, "state") {
            Some(path) if path.exists() => {
                self.read(index, "state").map_or(Saved::Corrupt, Saved::Ok)
            }
            _ => Saved::Missing,
        }
    }

    pub(crate) fn store_state(&self, index: usize, state: &[u8]) -> Result<(), PipelineError> {
        self.write(index, "state", state.to_vec())
    }

    /// A JSON record of frame `index` (e.g. the people found in it).
    pub(crate) fn load_json<T: DeserializeOwned>(&self, index: usize) -> Option<T> {
        serde_json::from_slice(&self.read(index, "json")?).ok()
    }

    pub(crate) fn store_json(
        &self,
        index: usize,
        value: &impl Serialize,
    ) -> Result<(), PipelineError> {
        self.write(index, "json", serde_json::to_vec(value).unwrap_or_default())
    }

    pub(crate) fn store_pose(&self, index: usize, pose: &Pose) -> Result<(), PipelineError> {
        // JSON has no NaN: a missing keypoint is `null`.
        let rows: Vec<Option<[f64; 3]>> = pose
            .keypoints
            .iter()
            .map(|k| k.is_found().then_some([k.x, k.y, k.likelihood]))
            .collect();
        self.write(index, "json", serde_json::to_vec(&rows).unwrap_or_default())
    }
}

fn cache_err(path: &Path, e: std::io::Error) -> PipelineError {
    // A full disk gets its own advice where the error is shown (free space, rerun).
    let full = matches!(
        e.kind(),
        std::io::ErrorKind::StorageFull | std::io::ErrorKind::QuotaExceeded
    );
    PipelineError::Cache {
        path: path.to_path_buf(),
        message: if full {
            e.to_string()
        } else {
            format!("{e}; check the disk or set run.cache = false")
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_truncated_or_altered_entry_is_refused_and_reported() {
        let root = tempfile::tempdir().unwrap();
        let cache = StageCache::open(root.path(), "pose", &"ab".repeat(32), &1).unwrap();
        let pose = Pose {
            keypoints: vec![Keypoint::new(1.5, 2.5, 0.75), Keypoint::new(-3.0, 4.0, 0.0)],
        };
        for index in 0..3 {
            cache.store_pose(index, &pose).unwrap();
        }
        assert_eq!(cache.load_pose(0, 2), Some(pose.clone()));
        assert!(cache.take_warnings().is_empty());
        let file = |i: usize| cache.file(i, "json").unwrap();
        let mut flipped = std::fs::read(file(1)).unwrap();
        flipped[3] ^= 0x04;
        std::fs::write(file(1), flipped).unwrap();
        let whole = std::fs::read(file(2)).unwrap();
        std::fs::write(file(2), &whole[..whole.len() - 5]).unwrap();
        assert_eq!(cache.load_pose(1, 2), None);
        assert_eq!(cache.load_pose(2, 2), None);
        let warnings = cache.take_warnings();
        assert_eq!(warnings.len(), 2, "{warnings:?}");
        assert!(warnings[0].contains("000001.json") && warnings[0].contains("checksum"));
        // Stored again, it reads back.
        cache.store_pose(1, &pose).unwrap();
        assert_eq!(cache.load_pose(1, 2), Some(pose));
    }

    #[test]
    fn keys_change_with_any_upstream_config() {
        let a = chain_key(
            "input",
            "edge",
            &serde_json::json!({"kind": "canny", "low": 100}),
        );
        let b = chain_key(
            "input",
            "edge",
            &serde_json::json!({"kind": "canny", "low": 101}),
        );
        let c = chain_key(
            "other-input",
            "edge",
            &serde_json::json!({"kind": "canny", "low": 100}),
        );
        assert!(a != b && a != c && b != c);
        assert_eq!(
            a,
            chain_key(
                "input",
                "edge",
                &serde_json::json!({"kind": "canny", "low": 100})
            )
        );
    }

    #[test]
    fn poses_round_trip_with_missing_points() {
        let dir = tempfile::tempdir().unwrap();
        let c = StageCache::open(dir.path(), "pose", &"a".repeat(64), &"cfg").unwrap();
        let pose = Pose {
            keypoints: vec![Keypoint::new(1.0, 2.0, 0.5), Keypoint::missing()],
        };
        c.store_pose(7, &pose).unwrap();
        let back = c.load_pose(7, 2).unwrap();
        assert_eq!(back.keypoints[0], pose.keypoints[0]);
        assert!(!back.keypoints[1].is_found());
        assert!(c.load_pose(7, 3).is_none());
        assert!(c.load_pose(8, 2).is_none());
    }
}
