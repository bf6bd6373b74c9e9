//! The on-disk per-frame cache. Each stage's results live in a folder named
//! by the hash of the input and of every stage config up to that stage, so
//! changing only the pose stage reuses edges and regenerated images, and an
//! interrupted run resumes at the first frame it had not finished.

use std::path::{Path, PathBuf};

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

/// One stage's folder in the cache, or nothing when caching is off.
pub(crate) struct StageCache {
    dir: Option<PathBuf>,
}

impl StageCache {
    pub(crate) fn disabled() -> Self {
        Self { dir: None }
    }

    /// Opens (creating) `<root>/<stage>-<key prefix>`, recording the stage's
    /// config beside the results for people browsing the cache.
    pub(crate) fn open(
        root: &Path,
        stage: &str,
        key: &str,
        config: &impl Serialize,
    ) -> Result<Self, PipelineError> {
        let dir = root.join(format!("{stage}-{}", &key[..16]));
        std::fs::create_dir_all(&dir).map_err(|e| cache_err(&dir, e))?;
        let about = dir.join("config.json");
        if !about.exists() {
            let json = serde_json::to_vec_pretty(config).unwrap_or_default();
            atomic::write(&about, &json).map_err(|e| cache_err(&about, e))?;
        }
        Ok(Self { dir: Some(dir) })
    }

    fn file(&self, index: usize, ext: &str) -> Option<PathBuf> {
        self.dir
            .as_ref()
            .map(|d| d.join(format!("{index:06}.{ext}")))
    }

    pub(crate) fn load_rgb(&self, index: usize) -> Option<image::RgbImage> {
        let path = self.file(index, "png")?;
        image::open(path).ok().map(|i| i.to_rgb8())
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
        let img = image::open(self.file(index, "png")?).ok()?.to_luma8();
        let text = std::fs::read_to_string(self.file(index, "json")?).ok()?;
        Some((img, serde_json::from_str(&text).ok()?))
    }

    pub(crate) fn store_edge(
        &self,
        index: usize,
        img: &image::GrayImage,
        resize: &Resize,
    ) -> Result<(), PipelineError> {
        let Some(path) = self.file(index, "json") else {
            return Ok(());
        };
        let json = serde_json::to_vec(resize).unwrap_or_default();
        atomic::write(&path, &json).map_err(|e| cache_err(&path, e))?;
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
        let Some(path) = self.file(index, "png") else {
            return Ok(());
        };
        atomic::write_with(&path, |out| {
            image::ImageEncoder::write_image(
                image::codecs::png::PngEncoder::new(out),
                raw,
                w,
                h,
                color,
            )
            .map_err(std::io::Error::other)
        })
        .map_err(|e| cache_err(&path, e))
    }

    /// A pose with `n` keypoints; a file of another length is ignored.
    pub(crate) fn load_pose(&self, index: usize, n: usize) -> Option<Pose> {
        let text = std::fs::read_to_string(self.file(index, "json")?).ok()?;
        let rows: Vec<Option<[f64; 3]>> = serde_json::from_str(&text).ok()?;
        (rows.len() == n).then(|| Pose {
            keypoints: rows
                .into_iter()
                .map(|r| r.map_or_else(Keypoint::missing, |[x, y, l]| Keypoint::new(x, y, l)))
                .collect(),
        })
    }

    /// A pose estimator's tracking state saved after frame `index`.
    pub(crate) fn load_state(&self, index: usize) -> Option<Vec<u8>> {
        std::fs::read(self.file(index, "state")?).ok()
    }

    pub(crate) fn store_state(&self, index: usize, state: &[u8]) -> Result<(), PipelineError> {
        let Some(path) = self.file(index, "state") else {
            return Ok(());
        };
        atomic::write(&path, state).map_err(|e| cache_err(&path, e))
    }

    /// A JSON record of frame `index` (e.g. the people found in it).
    pub(crate) fn load_json<T: DeserializeOwned>(&self, index: usize) -> Option<T> {
        let bytes = std::fs::read(self.file(index, "json")?).ok()?;
        serde_json::from_slice(&bytes).ok()
    }

    pub(crate) fn store_json(
        &self,
        index: usize,
        value: &impl Serialize,
    ) -> Result<(), PipelineError> {
        let Some(path) = self.file(index, "json") else {
            return Ok(());
        };
        let json = serde_json::to_vec(value).unwrap_or_default();
        atomic::write(&path, &json).map_err(|e| cache_err(&path, e))
    }

    pub(crate) fn store_pose(&self, index: usize, pose: &Pose) -> Result<(), PipelineError> {
        let Some(path) = self.file(index, "json") else {
            return Ok(());
        };
        // JSON has no NaN: a missing keypoint is `null`.
        let rows: Vec<Option<[f64; 3]>> = pose
            .keypoints
            .iter()
            .map(|k| k.is_found().then_some([k.x, k.y, k.likelihood]))
            .collect();
        let json = serde_json::to_vec(&rows).unwrap_or_default();
        atomic::write(&path, &json).map_err(|e| cache_err(&path, e))
    }
}

fn cache_err(path: &Path, e: std::io::Error) -> PipelineError {
    PipelineError::Cache {
        path: path.to_path_buf(),
        message: format!("{e}; check the disk or set run.cache = false"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
