//! The two networks behind one small interface, on either backend.

use std::path::{Path, PathBuf};

use gait_core::{Backend, StageError};

use gait_tflite::{CandleGraph, Graph};

pub const DETECTOR_FILE: &str = "pose_detection.tflite";
pub const LANDMARK_FILE: &str = "pose_landmark_full.tflite";

/// A network taking one NHWC float image and returning its outputs, flattened.
pub(crate) trait Net: Send {
    fn run(&mut self, input: &[f32]) -> Result<Vec<Vec<f32>>, StageError>;
}

struct CandleNet {
    graph: CandleGraph,
}

impl Net for CandleNet {
    fn run(&mut self, input: &[f32]) -> Result<Vec<Vec<f32>>, StageError> {
        self.graph
            .run(input)
            .map_err(|e| StageError::backend("candle", e))
    }
}

fn missing(path: &Path) -> StageError {
    StageError::MissingModel {
        path: path.to_path_buf(),
        hint: "run `gait models fetch blazepose` or set model_dir to a folder holding it".into(),
    }
}

/// Loads the `.tflite` file at `path` for `backend`. ONNX Runtime runs it on
/// `device`; candle always on the CPU (gait-tflite's kernels are CPU code,
/// and the two small networks are not worth a GPU round trip per frame).
pub(crate) fn load(
    path: &Path,
    backend: Backend,
    device: gait_core::Device,
) -> Result<Box<dyn Net>, StageError> {
    if !path.is_file() {
        return Err(missing(path));
    }
    let graph = load_graph(path).map_err(|e| StageError::bad_model(path, e))?;
    match backend {
        Backend::Candle | Backend::Auto => {
            let graph = CandleGraph::new(&graph).map_err(|e| StageError::bad_model(path, e))?;
            Ok(Box::new(CandleNet { graph }))
        }
        Backend::Ort => super::ort_net::load(path, &graph, device),
    }
}

/// Element counts of the landmark model's outputs that the estimator never
/// reads: the 256x256 segmentation mask and the 33 world landmarks. Dropping
/// them halves the landmark model's work on both backends.
const UNUSED_OUTPUTS: [usize; 2] = [256 * 256, 39 * 3];

/// Parses a `.tflite` file, keeping only the outputs the estimator reads.
pub(crate) fn load_graph(path: &Path) -> Result<Graph, gait_tflite::TfliteError> {
    let mut graph = Graph::load(path)?;
    graph.keep_outputs(|t| !UNUSED_OUTPUTS.contains(&t.shape.iter().product()));
    Ok(graph)
}

/// Path of the ONNX export next to a `.tflite` file.
pub(crate) fn onnx_path(tflite: &Path) -> PathBuf {
    tflite.with_extension("onnx")
}
