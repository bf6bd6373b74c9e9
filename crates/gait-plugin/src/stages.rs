//! The host's stage objects: each wraps one plugin instance and implements
//! the matching gait-core stage trait.

use gait_core::{
    EdgeDetector, EdgeMap, Frame, ImageRegenerator, Pose, PoseEstimator, StageContext, StageError,
};

use crate::PluginConfig;
use crate::abi::{
    GaitEdgeMap, GaitEdgeMaps, GaitFrame, GaitImage, GaitImages, GaitPoses, GaitResize, GaitStrs,
};
use crate::error::PluginError;
use crate::library::{self, Instance, Owned, call};
use crate::output;

/// Loads an `[edge] kind = "plugin"` stage.
pub fn load_edge_detector(
    cfg: &PluginConfig,
    ctx: &StageContext,
) -> Result<Box<dyn EdgeDetector>, StageError> {
    let instance = library::open(cfg, ctx, library::EDGE)?;
    Ok(Box::new(PluginEdgeDetector { instance }))
}

/// Loads a `[regenerator] kind = "plugin"` stage.
pub fn load_regenerator(
    cfg: &PluginConfig,
    ctx: &StageContext,
) -> Result<Box<dyn ImageRegenerator>, StageError> {
    let instance = library::open(cfg, ctx, library::REGENERATOR)?;
    Ok(Box::new(PluginRegenerator { instance }))
}

/// Loads a `[pose] kind = "plugin"` stage; its keypoint names are read and
/// checked once, here.
pub fn load_pose_estimator(
    cfg: &PluginConfig,
    ctx: &StageContext,
) -> Result<Box<dyn PoseEstimator>, StageError> {
    let instance = library::open(cfg, ctx, library::POSE)?;
    let names = keypoint_names(&instance)?;
    Ok(Box::new(PluginPoseEstimator { instance, names }))
}

/// Views of the host's frames for one call; they borrow the frames' pixels.
fn abi_frames(frames: &[Frame]) -> Vec<GaitFrame> {
    frames
        .iter()
        .map(|f| GaitFrame {
            index: f.index as u64,
            image: GaitImage {
                data: f.image.as_raw().as_ptr(),
                len: f.image.as_raw().len(),
                width: f.width(),
                height: f.height(),
                channels: 3,
            },
        })
        .collect()
}

fn malformed(instance: &Instance, call: &'static str, reason: String) -> StageError {
    PluginError::Malformed {
        plugin: instance.name.clone(),
        call,
        reason,
    }
    .into()
}

struct PluginEdgeDetector {
    instance: Instance,
}

impl EdgeDetector for PluginEdgeDetector {
    fn detect(&mut self, frames: &[Frame]) -> Result<Vec<EdgeMap>, StageError> {
        let inst = &self.instance;
        let detect = inst
            .descriptor
            .detect_edges
            .ok_or_else(|| malformed(inst, "detect_edges", "no detect_edges function".into()))?;
        let input = abi_frames(frames);
        let mut out = GaitEdgeMaps {
            items: std::ptr::null(),
            count: 0,
            owner: std::ptr::null_mut(),
        };
        let result = call(&inst.name, "detect_edges", inst.release, |error| {
            // SAFETY: `input` borrows live frames; `out` and `error` are writable.
            unsafe { detect(inst.raw, input.as_ptr(), input.len(), &mut out, error) }
        });
        let _owned = Owned::new(inst.release, out.owner);
        result?;
        // SAFETY: filled by the plugin with OK status; released by `_owned` after.
        unsafe { output::edge_maps(&out, frames) }.map_err(|r| malformed(inst, "detect_edges", r))
    }
}

struct PluginRegenerator {
    instance: Instance,
}

impl ImageRegenerator for PluginRegenerator {
    fn regenerate(
        &mut self,
        frames: &[Frame],
        edges: Option<&[EdgeMap]>,
    ) -> Result<Vec<Frame>, StageError> {
        let inst = &self.instance;
        let regenerate = inst
            .descriptor
            .regenerate
            .ok_or_else(|| malformed(inst, "regenerate", "no regenerate function".into()))?;
        if let Some(e) = edges
            && e.len() != frames.len()
        {
            return Err(StageError::BadInput(format!(
                "{} edge maps for {} frames",
                e.len(),
                frames.len()
            )));
        }
        let input = abi_frames(frames);
        let edge_input: Option<Vec<GaitEdgeMap>> = edges.map(|maps| {
            maps.iter()
                .map(|m| GaitEdgeMap {
                    image: GaitImage {
                        data: m.image.as_raw().as_ptr(),
                        len: m.image.as_raw().len(),
                        width: m.image.width(),
                        height: m.image.height(),
                        channels: 1,
                    },
                    resize: GaitResize {
                        src_width: m.resize.src_width,
                        src_height: m.resize.src_height,
                        dst_width: m.resize.dst_width,
                        dst_height: m.resize.dst_height,
                        scale_x: m.resize.scale_x,
                        scale_y: m.resize.scale_y,
                        offset_x: m.resize.offset_x,
                        offset_y: m.resize.offset_y,
                    },
                })
                .collect()
        });
        let edge_ptr = edge_input.as_ref().map_or(std::ptr::null(), |e| e.as_ptr());
        let mut out = GaitImages {
            items: std::ptr::null(),
            count: 0,
            owner: std::ptr::null_mut(),
        };
        let result = call(&inst.name, "regenerate", inst.release, |error| {
            // SAFETY: inputs borrow live buffers; `out` and `error` are writable.
            unsafe {
                regenerate(
                    inst.raw,
                    input.as_ptr(),
                    edge_ptr,
                    input.len(),
                    &mut out,
                    error,
                )
            }
        });
        let _owned = Owned::new(inst.release, out.owner);
        result?;
        // SAFETY: filled by the plugin with OK status; released by `_owned` after.
        unsafe { output::images(&out, frames) }.map_err(|r| malformed(inst, "regenerate", r))
    }
}

struct PluginPoseEstimator {
    instance: Instance,
    names: Vec<String>,
}

fn keypoint_names(inst: &Instance) -> Result<Vec<String>, StageError> {
    let names = inst
        .descriptor
        .keypoint_names
        .ok_or_else(|| malformed(inst, "keypoint_names", "no keypoint_names function".into()))?;
    let mut out = GaitStrs {
        items: std::ptr::null(),
        count: 0,
        owner: std::ptr::null_mut(),
    };
    let result = call(&inst.name, "keypoint_names", inst.release, |error| {
        // SAFETY: `out` and `error` are writable.
        unsafe { names(inst.raw, &mut out, error) }
    });
    let _owned = Owned::new(inst.release, out.owner);
    result?;
    // SAFETY: filled by the plugin with OK status; released by `_owned` after.
    unsafe { output::names(&out) }.map_err(|r| malformed(inst, "keypoint_names", r))
}

impl PoseEstimator for PluginPoseEstimator {
    fn keypoint_names(&self) -> Vec<String> {
        self.names.clone()
    }

    fn estimate(&mut self, frames: &[Frame]) -> Result<Vec<Pose>, StageError> {
        let inst = &self.instance;
        let estimate = inst.descriptor.estimate_poses.ok_or_else(|| {
            malformed(inst, "estimate_poses", "no estimate_poses function".into())
        })?;
        let input = abi_frames(frames);
        let mut out = GaitPoses {
            values: std::ptr::null(),
            len: 0,
            poses: 0,
            keypoints: 0,
            owner: std::ptr::null_mut(),
        };
        let result = call(&inst.name, "estimate_poses", inst.release, |error| {
            // SAFETY: `input` borrows live frames; `out` and `error` are writable.
            unsafe { estimate(inst.raw, input.as_ptr(), input.len(), &mut out, error) }
        });
        let _owned = Owned::new(inst.release, out.owner);
        result?;
        // SAFETY: filled by the plugin with OK status; released by `_owned` after.
        unsafe { output::poses(&out, frames, &self.names) }
            .map_err(|r| malformed(inst, "estimate_poses", r))
    }

    fn reset(&mut self) {
        if let Some(reset) = self.instance.descriptor.reset {
            // SAFETY: a live instance, used by one call at a time.
            unsafe { reset(self.instance.raw) };
        }
    }
}
