//! Reading TensorFlow Lite model files (`.tflite` flatbuffers) into an owned
//! graph: tensors with their constant data (float32, float16, int32, sparse
//! tensors densified) and operators with their builtin options. Shared by the stages that run
//! MediaPipe models (BlazePose, selfie segmentation).

mod candle;
mod densify;
mod flatbuf;
mod kernels;
mod model;
mod onnx;
mod operator_io;
mod same;

pub use candle::CandleGraph;
pub use model::{
    Activation, DType, Graph, MAX_TENSOR_ELEMENTS, Op, OpOptions, Operator, Padding, Tensor,
};
pub use onnx::to_onnx;

/// Why a `.tflite` file cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TfliteError {
    #[error("not a TFLite model (file identifier {0:?}, expected \"TFL3\")")]
    Foreign(String),
    #[error("truncated or corrupt TFLite model: {0}")]
    Malformed(String),
    #[error("unsupported TFLite feature: {0}")]
    Unsupported(String),
}
