//! OpenPose body estimator (the paper's pose model): the CMU network
//! (VGG-19 front end + 6 refinement stages of part-affinity fields and
//! heatmaps) on candle or ONNX Runtime, then OpenPose's decoding into people.

pub mod decode;
pub mod net;
