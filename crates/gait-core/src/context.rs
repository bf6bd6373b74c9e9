use std::path::{Path, PathBuf};

use crate::Device;

/// What a stage needs to know about its surroundings when it is built.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StageContext {
    /// Folder where `gait models fetch` puts model files; relative model paths
    /// in stage configs are resolved against it.
    pub models_dir: PathBuf,
    /// Where model stages run (`[run] device`); [`StageContext::new`] picks the CPU.
    pub device: Device,
}

impl StageContext {
    pub fn new(models_dir: impl Into<PathBuf>) -> Self {
        Self {
            models_dir: models_dir.into(),
            device: Device::Cpu,
        }
    }

    /// The same context with model stages on `device`.
    pub fn on(mut self, device: Device) -> Self {
        self.device = device;
        self
    }

    /// Resolves a configured model path: absolute paths stay, relative ones
    /// are taken inside the models folder.
    pub fn model_path(&self, path: &Path) -> PathBuf {
        if path.is_absolute() {
            path.to_path_buf()
        } else {
            self.models_dir.join(path)
        }
    }
}
