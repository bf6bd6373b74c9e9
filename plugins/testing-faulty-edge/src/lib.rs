//! Test edge plugin written against the raw C ABI (no export macro), as a
//! plugin in C would be. With `fault = "none"` it returns the green channel of
//! each frame as its edge map; other faults return what a buggy plugin might,
//! so the tests can check that the host refuses each one without reading out
//! of bounds:
//!
//! `short_buffer`, `wrong_width`, `huge`, `missing_map`, `null_items`,
//! `bad_resize`, `error`, `unknown_status`, `null_instance`.

use std::ffi::c_void;

use gait_plugin::abi::{
    ABI_VERSION, GaitEdgeMap, GaitEdgeMaps, GaitError, GaitFrame, GaitImage, GaitPluginDescriptor,
    GaitResize, GaitStr, family, status,
};

struct Instance {
    fault: String,
}

/// What an `owner` token stands for: the pixel buffers and the map array.
struct Output {
    _buffers: Vec<Vec<u8>>,
    _maps: Vec<GaitEdgeMap>,
}

fn set_error(error: *mut GaitError, message: &'static str) {
    if !error.is_null() {
        // SAFETY: the host passes a writable error struct. A static message
        // needs no owner.
        unsafe {
            *error = GaitError {
                message: GaitStr::new(message),
                owner: std::ptr::null_mut(),
            }
        };
    }
}

unsafe extern "C" fn create(
    options: GaitStr,
    _models_dir: GaitStr,
    instance: *mut *mut c_void,
    error: *mut GaitError,
) -> i32 {
    // SAFETY: the host passes `len` readable bytes.
    let bytes = unsafe { std::slice::from_raw_parts(options.ptr, options.len) };
    let Ok(json) = serde_json::from_slice::<serde_json::Value>(bytes) else {
        set_error(error, "options are not JSON");
        return status::BAD_INPUT;
    };
    let fault = json["fault"].as_str().unwrap_or("none").to_string();
    if fault == "null_instance" {
        return status::OK;
    }
    // SAFETY: the host passes a writable slot.
    unsafe { *instance = Box::into_raw(Box::new(Instance { fault })).cast() };
    status::OK
}

unsafe extern "C" fn destroy(instance: *mut c_void) {
    // SAFETY: `instance` came from `create`.
    drop(unsafe { Box::from_raw(instance.cast::<Instance>()) });
}

unsafe extern "C" fn release(owner: *mut c_void) {
    // SAFETY: `owner` came from `detect_edges`.
    drop(unsafe { Box::from_raw(owner.cast::<Output>()) });
}

unsafe extern "C" fn detect_edges(
    instance: *mut c_void,
    frames: *const GaitFrame,
    count: usize,
    out: *mut GaitEdgeMaps,
    error: *mut GaitError,
) -> i32 {
    // SAFETY: the host passes its instance and `count` valid frames.
    let (fault, frames) = unsafe {
        (
            (*instance.cast::<Instance>()).fault.as_str(),
            std::slice::from_raw_parts(frames, count),
        )
    };
    match fault {
        "error" => {
            set_error(error, "the edge model exploded");
            return status::FAILED;
        }
        "unknown_status" => return 42,
        _ => {}
    }
    let mut buffers = Vec::new();
    let mut maps = Vec::new();
    for frame in frames {
        let (w, h) = (frame.image.width, frame.image.height);
        // SAFETY: the host's frame buffers hold `len` bytes.
        let rgb = unsafe { std::slice::from_raw_parts(frame.image.data, frame.image.len) };
        let mut green: Vec<u8> = rgb.chunks_exact(3).map(|p| p[1]).collect();
        if fault == "short_buffer" {
            green.pop();
        }
        let mut image = GaitImage {
            data: green.as_ptr(),
            len: green.len(),
            width: w,
            height: h,
            channels: 1,
        };
        let mut resize = GaitResize {
            src_width: w,
            src_height: h,
            dst_width: w,
            dst_height: h,
            scale_x: 1.0,
            scale_y: 1.0,
            offset_x: 0.0,
            offset_y: 0.0,
        };
        match fault {
            "wrong_width" => {
                image.width += 1;
                resize.dst_width += 1;
            }
            "huge" => {
                image.width = u32::MAX;
                image.height = u32::MAX;
            }
            "bad_resize" => resize.scale_x = f64::NAN,
            _ => {}
        }
        buffers.push(green);
        maps.push(GaitEdgeMap { image, resize });
    }
    if fault == "missing_map" {
        maps.pop();
    }
    let result = GaitEdgeMaps {
        items: if fault == "null_items" {
            std::ptr::null()
        } else {
            maps.as_ptr()
        },
        count: maps.len(),
        owner: std::ptr::null_mut(),
    };
    let owner = Box::into_raw(Box::new(Output {
        _buffers: buffers,
        _maps: maps,
    }));
    // SAFETY: the host passes a writable output struct.
    unsafe {
        *out = GaitEdgeMaps {
            owner: owner.cast(),
            ..result
        }
    };
    status::OK
}

static DESCRIPTOR: GaitPluginDescriptor = GaitPluginDescriptor {
    abi_version: ABI_VERSION,
    family: family::EDGE,
    name: GaitStr::new("testing-faulty-edge"),
    create: Some(create),
    destroy: Some(destroy),
    release: Some(release),
    detect_edges: Some(detect_edges),
    regenerate: None,
    estimate_poses: None,
    keypoint_names: None,
    reset: None,
};

/// The entry point.
#[unsafe(no_mangle)]
pub extern "C" fn gait_plugin_entry() -> *const GaitPluginDescriptor {
    &DESCRIPTOR
}
