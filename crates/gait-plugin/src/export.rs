//! The plugin side: the C functions around a normal Rust stage, generic over
//! the stage type. Plugin authors use the `export_*!` macros, which put these
//! into a static descriptor; nothing here is called directly.
//!
//! Every function catches panics (`catch_unwind`) and turns them into
//! [`status::PANICKED`], so a panic never unwinds into the host. This needs
//! the plugin built with `panic = "unwind"` (the default): with
//! `panic = "abort"` a panic ends the whole process.

use std::any::Any;
use std::ffi::c_void;
use std::panic::{AssertUnwindSafe, catch_unwind};

use gait_core::{
    EdgeDetector, EdgeMap, Frame, ImageRegenerator, PoseEstimator, Resize, StageContext, StageError,
};
use image::{GrayImage, RgbImage};
use serde::de::DeserializeOwned;

use crate::abi::{
    ABI_VERSION, GaitEdgeMap, GaitEdgeMaps, GaitError, GaitFrame, GaitImage, GaitImages,
    GaitPluginDescriptor, GaitPoses, GaitResize, GaitStr, GaitStrs, family, status,
};

/// How a plugin stage is built from its `[stage.options]` table.
pub trait PluginStage: Sized + Send + 'static {
    /// The options table, deserialized from JSON. Use
    /// `#[serde(deny_unknown_fields, default)]` so typos are reported.
    type Options: DeserializeOwned;

    /// Builds the stage; `ctx.models_dir` is the host's models folder.
    fn create(options: Self::Options, ctx: &StageContext) -> Result<Self, StageError>;
}

/// The descriptor of an edge-detector plugin (used by [`crate::export_edge_detector!`]).
pub const fn edge_descriptor<T: EdgeDetector + PluginStage>(
    name: &'static str,
) -> GaitPluginDescriptor {
    GaitPluginDescriptor {
        detect_edges: Some(detect_edges::<T>),
        ..base::<T>(family::EDGE, name)
    }
}

/// The descriptor of a regenerator plugin (used by [`crate::export_regenerator!`]).
pub const fn regenerator_descriptor<T: ImageRegenerator + PluginStage>(
    name: &'static str,
) -> GaitPluginDescriptor {
    GaitPluginDescriptor {
        regenerate: Some(regenerate::<T>),
        ..base::<T>(family::REGENERATOR, name)
    }
}

/// The descriptor of a pose-estimator plugin (used by [`crate::export_pose_estimator!`]).
pub const fn pose_descriptor<T: PoseEstimator + PluginStage>(
    name: &'static str,
) -> GaitPluginDescriptor {
    GaitPluginDescriptor {
        estimate_poses: Some(estimate_poses::<T>),
        keypoint_names: Some(keypoint_names::<T>),
        reset: Some(reset::<T>),
        ..base::<T>(family::POSE, name)
    }
}

const fn base<T: PluginStage>(family: u32, name: &'static str) -> GaitPluginDescriptor {
    GaitPluginDescriptor {
        abi_version: ABI_VERSION,
        family,
        name: GaitStr::new(name),
        create: Some(create::<T>),
        destroy: Some(destroy::<T>),
        release: Some(release),
        detect_edges: None,
        regenerate: None,
        estimate_poses: None,
        keypoint_names: None,
        reset: None,
    }
}

/// Runs `f`, catching panics, and reports its outcome as a status code.
fn guard(error: *mut GaitError, f: impl FnOnce() -> Result<(), StageError>) -> i32 {
    let (code, message) = match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => return status::OK,
        Ok(Err(StageError::BadInput(m))) => (status::BAD_INPUT, m),
        Ok(Err(e)) => (status::FAILED, e.to_string()),
        Err(payload) => (status::PANICKED, panic_message(payload.as_ref())),
    };
    if !error.is_null() {
        let text: Box<str> = message.into_boxed_str();
        let message = GaitStr::new(&text);
        // SAFETY: the host passes a valid, writable error struct (or null).
        unsafe {
            *error = GaitError {
                message,
                owner: hand_out(text),
            }
        };
    }
    code
}

fn panic_message(payload: &(dyn Any + Send)) -> String {
    let text = payload
        .downcast_ref::<&str>()
        .copied()
        .or_else(|| payload.downcast_ref::<String>().map(String::as_str))
        .unwrap_or("(no message)");
    format!("panicked: {text}")
}

/// Boxes `value` so the host can hold it as an `owner` token until `release`.
/// Moving a `Vec` into the box keeps its heap buffer, so pointers taken into
/// it before stay valid.
fn hand_out<V: 'static>(value: V) -> *mut c_void {
    let boxed: Box<dyn Any> = Box::new(value);
    Box::into_raw(Box::new(boxed)).cast()
}

unsafe extern "C" fn release(owner: *mut c_void) {
    if owner.is_null() {
        return;
    }
    // A panicking destructor must not unwind into the host; there is nobody
    // to report it to, so it is dropped.
    let _ = catch_unwind(|| {
        // SAFETY: `owner` came from `hand_out` and is released once.
        drop(unsafe { Box::from_raw(owner.cast::<Box<dyn Any>>()) });
    });
}

/// Borrows a host string as UTF-8.
///
/// # Safety
/// `s` points to `len` readable bytes (or is null with `len == 0`).
unsafe fn host_str<'a>(s: GaitStr, what: &str) -> Result<&'a str, StageError> {
    if s.ptr.is_null() || s.len == 0 {
        return Ok("");
    }
    // SAFETY: per the contract above.
    let bytes = unsafe { std::slice::from_raw_parts(s.ptr, s.len) };
    std::str::from_utf8(bytes)
        .map_err(|e| StageError::BadInput(format!("{what} is not UTF-8: {e}")))
}

unsafe extern "C" fn create<T: PluginStage>(
    options_json: GaitStr,
    models_dir: GaitStr,
    instance: *mut *mut c_void,
    error: *mut GaitError,
) -> i32 {
    guard(error, || {
        if instance.is_null() {
            return Err(StageError::BadInput("null instance slot".into()));
        }
        // SAFETY: the host passes valid strings for the duration of the call.
        let json = unsafe { host_str(options_json, "options") }?;
        let json = if json.is_empty() { "{}" } else { json };
        let options: T::Options =
            serde_json::from_str(json).map_err(|e| StageError::BadInput(e.to_string()))?;
        // SAFETY: as above.
        let ctx = StageContext::new(unsafe { host_str(models_dir, "models_dir") }?);
        let stage = Box::new(T::create(options, &ctx)?);
        // SAFETY: checked non-null; the host owns the slot.
        unsafe { *instance = Box::into_raw(stage).cast() };
        Ok(())
    })
}

unsafe extern "C" fn destroy<T: PluginStage>(instance: *mut c_void) {
    if instance.is_null() {
        return;
    }
    let _ = catch_unwind(|| {
        // SAFETY: `instance` came from `create::<T>` and is destroyed once.
        drop(unsafe { Box::from_raw(instance.cast::<T>()) });
    });
}

/// The instance behind the host's pointer.
///
/// # Safety
/// `instance` is null or came from `create::<T>` and is not in use elsewhere.
unsafe fn stage<'a, T>(instance: *mut c_void) -> Result<&'a mut T, StageError> {
    // SAFETY: per the contract above.
    unsafe { instance.cast::<T>().as_mut() }
        .ok_or_else(|| StageError::BadInput("null instance".into()))
}

/// Borrows `count` items of a host array.
///
/// # Safety
/// `ptr` points to `count` valid items, or `count == 0`.
unsafe fn host_slice<'a, X>(ptr: *const X, count: usize) -> Result<&'a [X], StageError> {
    if count == 0 {
        return Ok(&[]);
    }
    if ptr.is_null() {
        return Err(StageError::BadInput(format!("null array of {count} items")));
    }
    // SAFETY: per the contract above.
    Ok(unsafe { std::slice::from_raw_parts(ptr, count) })
}

/// Copies a host image after checking its size.
///
/// # Safety
/// `image.data` points to `image.len` readable bytes.
unsafe fn host_pixels(image: &GaitImage, channels: u32) -> Result<Vec<u8>, StageError> {
    let expected = (image.width as usize)
        .checked_mul(image.height as usize)
        .and_then(|n| n.checked_mul(channels as usize));
    if image.channels != channels || expected != Some(image.len) {
        return Err(StageError::BadInput(format!(
            "image {}x{}x{} with {} bytes, expected {} channels",
            image.width, image.height, image.channels, image.len, channels
        )));
    }
    // SAFETY: per the contract above.
    Ok(unsafe { host_slice(image.data, image.len) }?.to_vec())
}

/// # Safety
/// `frames` points to `count` frames whose buffers are valid.
unsafe fn host_frames(frames: *const GaitFrame, count: usize) -> Result<Vec<Frame>, StageError> {
    // SAFETY: per the contract above.
    let frames = unsafe { host_slice(frames, count) }?;
    frames
        .iter()
        .map(|f| {
            // SAFETY: per the contract above.
            let pixels = unsafe { host_pixels(&f.image, 3) }?;
            let image = RgbImage::from_raw(f.image.width, f.image.height, pixels)
                .ok_or_else(|| StageError::BadInput("frame buffer too small".into()))?;
            let index = usize::try_from(f.index)
                .map_err(|_| StageError::BadInput(format!("frame index {} too large", f.index)))?;
            Ok(Frame::new(index, image))
        })
        .collect()
}

fn resize_to_abi(r: &Resize) -> GaitResize {
    GaitResize {
        src_width: r.src_width,
        src_height: r.src_height,
        dst_width: r.dst_width,
        dst_height: r.dst_height,
        scale_x: r.scale_x,
        scale_y: r.scale_y,
        offset_x: r.offset_x,
        offset_y: r.offset_y,
    }
}

fn resize_from_abi(r: &GaitResize) -> Resize {
    Resize {
        src_width: r.src_width,
        src_height: r.src_height,
        dst_width: r.dst_width,
        dst_height: r.dst_height,
        scale_x: r.scale_x,
        scale_y: r.scale_y,
        offset_x: r.offset_x,
        offset_y: r.offset_y,
    }
}

fn image_to_abi(pixels: &[u8], width: u32, height: u32, channels: u32) -> GaitImage {
    GaitImage {
        data: pixels.as_ptr(),
        len: pixels.len(),
        width,
        height,
        channels,
    }
}

unsafe extern "C" fn detect_edges<T: EdgeDetector + PluginStage>(
    instance: *mut c_void,
    frames: *const GaitFrame,
    count: usize,
    out: *mut GaitEdgeMaps,
    error: *mut GaitError,
) -> i32 {
    guard(error, || {
        // SAFETY: the host keeps the instance and the frames valid and exclusive for the call.
        let (stage, frames) = unsafe { (stage::<T>(instance)?, host_frames(frames, count)?) };
        let maps = stage.detect(&frames)?;
        let items: Vec<GaitEdgeMap> = maps
            .iter()
            .map(|m| GaitEdgeMap {
                image: image_to_abi(m.image.as_raw(), m.image.width(), m.image.height(), 1),
                resize: resize_to_abi(&m.resize),
            })
            .collect();
        let result = GaitEdgeMaps {
            items: items.as_ptr(),
            count: items.len(),
            owner: hand_out((maps, items)),
        };
        // SAFETY: `out` is the host's writable output struct.
        unsafe { write_out(out, result) }
    })
}

unsafe extern "C" fn regenerate<T: ImageRegenerator + PluginStage>(
    instance: *mut c_void,
    frames: *const GaitFrame,
    edges: *const GaitEdgeMap,
    count: usize,
    out: *mut GaitImages,
    error: *mut GaitError,
) -> i32 {
    guard(error, || {
        // SAFETY: the host keeps the instance and the frames valid and exclusive for the call.
        let (stage, frames) = unsafe { (stage::<T>(instance)?, host_frames(frames, count)?) };
        let edges = if edges.is_null() {
            None
        } else {
            // SAFETY: a non-null `edges` has `count` valid maps.
            let raw = unsafe { host_slice(edges, count) }?;
            let maps = raw
                .iter()
                .zip(&frames)
                .map(|(e, f)| {
                    // SAFETY: as above.
                    let pixels = unsafe { host_pixels(&e.image, 1) }?;
                    let image = GrayImage::from_raw(e.image.width, e.image.height, pixels)
                        .ok_or_else(|| StageError::BadInput("edge buffer too small".into()))?;
                    Ok(EdgeMap {
                        index: f.index,
                        image,
                        resize: resize_from_abi(&e.resize),
                    })
                })
                .collect::<Result<Vec<_>, StageError>>()?;
            Some(maps)
        };
        let images = stage.regenerate(&frames, edges.as_deref())?;
        let items: Vec<GaitImage> = images
            .iter()
            .map(|f| image_to_abi(f.image.as_raw(), f.width(), f.height(), 3))
            .collect();
        let result = GaitImages {
            items: items.as_ptr(),
            count: items.len(),
            owner: hand_out((images, items)),
        };
        // SAFETY: `out` is the host's writable output struct.
        unsafe { write_out(out, result) }
    })
}

unsafe extern "C" fn estimate_poses<T: PoseEstimator + PluginStage>(
    instance: *mut c_void,
    frames: *const GaitFrame,
    count: usize,
    out: *mut GaitPoses,
    error: *mut GaitError,
) -> i32 {
    guard(error, || {
        // SAFETY: the host keeps the instance and the frames valid and exclusive for the call.
        let (stage, frames) = unsafe { (stage::<T>(instance)?, host_frames(frames, count)?) };
        let poses = stage.estimate(&frames)?;
        let keypoints = poses.first().map_or(0, |p| p.keypoints.len());
        if let Some((i, p)) = poses
            .iter()
            .enumerate()
            .find(|(_, p)| p.keypoints.len() != keypoints)
        {
            return Err(StageError::backend(
                "plugin",
                format!(
                    "pose {i} has {} keypoints, pose 0 has {keypoints}",
                    p.keypoints.len()
                ),
            ));
        }
        let values: Vec<f64> = poses
            .iter()
            .flat_map(|p| &p.keypoints)
            .flat_map(|k| [k.x, k.y, k.likelihood])
            .collect();
        let result = GaitPoses {
            values: values.as_ptr(),
            len: values.len(),
            poses: poses.len(),
            keypoints,
            owner: hand_out(values),
        };
        // SAFETY: `out` is the host's writable output struct.
        unsafe { write_out(out, result) }
    })
}

unsafe extern "C" fn keypoint_names<T: PoseEstimator + PluginStage>(
    instance: *mut c_void,
    out: *mut GaitStrs,
    error: *mut GaitError,
) -> i32 {
    guard(error, || {
        // SAFETY: the host keeps the instance valid and exclusive for the call.
        let stage = unsafe { stage::<T>(instance) }?;
        let names: Vec<String> = stage.keypoint_names();
        let items: Vec<GaitStr> = names.iter().map(|n| GaitStr::new(n)).collect();
        let result = GaitStrs {
            items: items.as_ptr(),
            count: items.len(),
            owner: hand_out((names, items)),
        };
        // SAFETY: `out` is the host's writable output struct.
        unsafe { write_out(out, result) }
    })
}

unsafe extern "C" fn reset<T: PoseEstimator + PluginStage>(instance: *mut c_void) {
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: the host keeps the instance valid and exclusive for the call.
        if let Ok(stage) = unsafe { stage::<T>(instance) } {
            stage.reset();
        }
    }));
}

/// Stores an output struct; releases it instead when `out` is null.
///
/// # Safety
/// `out` is null or writable.
unsafe fn write_out<O: Copy + HasOwner>(out: *mut O, value: O) -> Result<(), StageError> {
    if out.is_null() {
        // SAFETY: the owner came from `hand_out` and was never handed over.
        unsafe { release(value.owner()) };
        return Err(StageError::BadInput("null output struct".into()));
    }
    // SAFETY: per the contract above.
    unsafe { *out = value };
    Ok(())
}

trait HasOwner {
    fn owner(&self) -> *mut c_void;
}

macro_rules! has_owner {
    ($($t:ty),*) => {$(
        impl HasOwner for $t {
            fn owner(&self) -> *mut c_void {
                self.owner
            }
        }
    )*};
}
has_owner!(GaitEdgeMaps, GaitImages, GaitPoses, GaitStrs);
