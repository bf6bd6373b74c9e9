//! Pose estimators implementing [`gait_core::PoseEstimator`].
