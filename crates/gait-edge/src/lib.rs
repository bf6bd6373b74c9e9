//! Edge detectors implementing [`gait_core::EdgeDetector`].
