//! The C ABI between `gait` (the host) and a stage plugin, version [`ABI_VERSION`].
//!
//! A plugin is a shared library exporting [`ENTRY_SYMBOL`], an
//! [`EntryFn`] returning a pointer to a static [`GaitPluginDescriptor`]. The
//! descriptor's first field is always `abi_version: u32`, in every version, so
//! the host can refuse a plugin built for another version before it reads
//! anything else.
//!
//! Rules every plugin follows (the export macros implement them):
//! - Every function returning `i32` returns a [`status`] code. On anything but
//!   [`status::OK`] it may fill `*error` with a UTF-8 message; on OK it fills
//!   its output struct. The host zeroes output and error structs before a call.
//! - Everything the plugin hands out (messages, images, poses, names) stays
//!   valid until the host passes the struct's `owner` token to the
//!   descriptor's `release`; the host copies the data first. A null `owner`
//!   means nothing to release.
//! - Buffers the host passes in (frames, edge maps, option strings) are only
//!   valid during the call.
//! - No panic or C++ exception may unwind out of a function: it becomes
//!   [`status::PANICKED`].
//! - An instance may be called from any thread, one call at a time.
//!
//! Layouts: images are row-major, `channels` interleaved bytes per pixel,
//! `len == width * height * channels`; frames are RGB (3 channels), edge maps
//! gray (1 channel). Poses are flat `f64` triples `(x, y, likelihood)`,
//! `values[(pose * keypoints + k) * 3 + c]`. A missing keypoint is exactly
//! `(NaN, NaN, 0)`; any other non-finite value, or a likelihood outside [0, 1],
//! is refused by the host.

use std::ffi::c_void;

/// Version of this ABI. Bump it on any change of a struct or function below.
pub const ABI_VERSION: u32 = 1;

/// Name of the exported [`EntryFn`].
pub const ENTRY_SYMBOL: &str = "gait_plugin_entry";

/// Return codes of the plugin functions.
pub mod status {
    /// Success; the output struct is filled.
    pub const OK: i32 = 0;
    /// The input (options, frames) cannot be processed.
    pub const BAD_INPUT: i32 = 1;
    /// The stage failed for another reason (model, backend, I/O).
    pub const FAILED: i32 = 2;
    /// The stage panicked; the panic was caught inside the plugin.
    pub const PANICKED: i32 = 3;
}

/// Stage family of a plugin ([`GaitPluginDescriptor::family`]).
pub mod family {
    /// An `EdgeDetector`: `detect_edges` is set.
    pub const EDGE: u32 = 1;
    /// An `ImageRegenerator`: `regenerate` is set.
    pub const REGENERATOR: u32 = 2;
    /// A `PoseEstimator`: `estimate_poses` and `keypoint_names` are set.
    pub const POSE: u32 = 3;
}

/// A borrowed UTF-8 string (not NUL-terminated).
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct GaitStr {
    pub ptr: *const u8,
    pub len: usize,
}

impl GaitStr {
    /// The empty string (null pointer, length 0).
    pub const EMPTY: GaitStr = GaitStr {
        ptr: std::ptr::null(),
        len: 0,
    };

    /// Borrows `s`; usable in statics.
    pub const fn new(s: &str) -> GaitStr {
        GaitStr {
            ptr: s.as_ptr(),
            len: s.len(),
        }
    }
}

/// An image buffer: row-major, interleaved channels, no row padding.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct GaitImage {
    pub data: *const u8,
    pub len: usize,
    pub width: u32,
    pub height: u32,
    pub channels: u32,
}

/// `gait_core::Resize`: `target + 0.5 = (source + 0.5) * scale + offset`.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct GaitResize {
    pub src_width: u32,
    pub src_height: u32,
    pub dst_width: u32,
    pub dst_height: u32,
    pub scale_x: f64,
    pub scale_y: f64,
    pub offset_x: f64,
    pub offset_y: f64,
}

/// An input frame (RGB) with its index in the input sequence.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct GaitFrame {
    pub index: u64,
    pub image: GaitImage,
}

/// An edge map (gray) and how frame coordinates map onto it.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct GaitEdgeMap {
    pub image: GaitImage,
    pub resize: GaitResize,
}

/// An error message from the plugin.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct GaitError {
    pub message: GaitStr,
    pub owner: *mut c_void,
}

/// Edge maps returned by `detect_edges`, one per input frame.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct GaitEdgeMaps {
    pub items: *const GaitEdgeMap,
    pub count: usize,
    pub owner: *mut c_void,
}

/// Images returned by `regenerate`, one per input frame.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct GaitImages {
    pub items: *const GaitImage,
    pub count: usize,
    pub owner: *mut c_void,
}

/// Poses returned by `estimate_poses`: `poses * keypoints * 3` values.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct GaitPoses {
    pub values: *const f64,
    pub len: usize,
    pub poses: usize,
    pub keypoints: usize,
    pub owner: *mut c_void,
}

/// Strings returned by `keypoint_names`.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct GaitStrs {
    pub items: *const GaitStr,
    pub count: usize,
    pub owner: *mut c_void,
}

/// Builds an instance from the plugin's options (a JSON object) and the
/// models folder; on OK stores a non-null instance in `*instance`.
pub type CreateFn = unsafe extern "C" fn(
    options_json: GaitStr,
    models_dir: GaitStr,
    instance: *mut *mut c_void,
    error: *mut GaitError,
) -> i32;
/// Frees an instance.
pub type DestroyFn = unsafe extern "C" fn(instance: *mut c_void);
/// Frees what an `owner` token stands for.
pub type ReleaseFn = unsafe extern "C" fn(owner: *mut c_void);
/// `EdgeDetector::detect`.
pub type DetectEdgesFn = unsafe extern "C" fn(
    instance: *mut c_void,
    frames: *const GaitFrame,
    count: usize,
    out: *mut GaitEdgeMaps,
    error: *mut GaitError,
) -> i32;
/// `ImageRegenerator::regenerate`; `edges` is null or has `count` maps.
pub type RegenerateFn = unsafe extern "C" fn(
    instance: *mut c_void,
    frames: *const GaitFrame,
    edges: *const GaitEdgeMap,
    count: usize,
    out: *mut GaitImages,
    error: *mut GaitError,
) -> i32;
/// `PoseEstimator::estimate`.
pub type EstimatePosesFn = unsafe extern "C" fn(
    instance: *mut c_void,
    frames: *const GaitFrame,
    count: usize,
    out: *mut GaitPoses,
    error: *mut GaitError,
) -> i32;
/// `PoseEstimator::keypoint_names`.
pub type KeypointNamesFn =
    unsafe extern "C" fn(instance: *mut c_void, out: *mut GaitStrs, error: *mut GaitError) -> i32;
/// `PoseEstimator::reset`.
pub type ResetFn = unsafe extern "C" fn(instance: *mut c_void);

/// What [`ENTRY_SYMBOL`] returns. Functions a family does not use are null.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct GaitPluginDescriptor {
    /// Always the first field, in every ABI version.
    pub abi_version: u32,
    /// One of [`family`].
    pub family: u32,
    /// A human-readable name for messages.
    pub name: GaitStr,
    pub create: Option<CreateFn>,
    pub destroy: Option<DestroyFn>,
    pub release: Option<ReleaseFn>,
    pub detect_edges: Option<DetectEdgesFn>,
    pub regenerate: Option<RegenerateFn>,
    pub estimate_poses: Option<EstimatePosesFn>,
    pub keypoint_names: Option<KeypointNamesFn>,
    pub reset: Option<ResetFn>,
}

// SAFETY: a descriptor is immutable data (a static string and function
// pointers); sharing it between threads is sound.
unsafe impl Sync for GaitPluginDescriptor {}

/// The type of [`ENTRY_SYMBOL`].
pub type EntryFn = unsafe extern "C" fn() -> *const GaitPluginDescriptor;

#[cfg(test)]
mod tests {
    use std::mem::{offset_of, size_of};

    use super::*;

    /// The layout is the ABI: changing it without bumping ABI_VERSION would
    /// let old plugins pass the handshake and then be misread.
    #[test]
    fn layout_of_version_1_on_64_bit() {
        if size_of::<usize>() != 8 {
            return;
        }
        assert_eq!(ABI_VERSION, 1);
        assert_eq!(offset_of!(GaitPluginDescriptor, abi_version), 0);
        assert_eq!(size_of::<GaitStr>(), 16);
        assert_eq!(size_of::<GaitImage>(), 32);
        assert_eq!(size_of::<GaitResize>(), 48);
        assert_eq!(size_of::<GaitFrame>(), 40);
        assert_eq!(size_of::<GaitEdgeMap>(), 80);
        assert_eq!(size_of::<GaitError>(), 24);
        assert_eq!(size_of::<GaitEdgeMaps>(), 24);
        assert_eq!(size_of::<GaitImages>(), 24);
        assert_eq!(size_of::<GaitPoses>(), 40);
        assert_eq!(size_of::<GaitStrs>(), 24);
        assert_eq!(offset_of!(GaitPluginDescriptor, create), 24);
        assert_eq!(size_of::<GaitPluginDescriptor>(), 24 + 8 * 8);
    }
}
