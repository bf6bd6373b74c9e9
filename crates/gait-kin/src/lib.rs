//! Keypoint post-processing, sagittal joint angles, gait events and cycles.
