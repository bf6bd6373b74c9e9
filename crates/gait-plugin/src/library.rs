//! The host side of loading: open the library, find the entry symbol, check
//! the ABI version and family, create an instance, and call it safely.

use gait_core::StageContext;
use libloading::Library;
use std::ffi::c_void;
use std::sync::Mutex;

use crate::PluginConfig;
use crate::abi::{
    ABI_VERSION, ENTRY_SYMBOL, EntryFn, GaitError, GaitPluginDescriptor, GaitStr, ReleaseFn,
    family, status,
};
use crate::error::PluginError;

/// Longest error message copied from a plugin; longer ones are cut.
const MAX_MESSAGE: usize = 64 * 1024;

/// One live plugin instance. Dropping it destroys the instance; the library
/// stays loaded (see [`open`]).
pub(crate) struct Instance {
    pub(crate) raw: *mut c_void,
    pub(crate) descriptor: GaitPluginDescriptor,
    pub(crate) release: ReleaseFn,
    pub(crate) name: String,
}

// SAFETY: the ABI requires instances to be usable from any thread, one call
// at a time; `&mut self` on every call gives the one-at-a-time part, and the
// export helpers only accept `Send` stages.
unsafe impl Send for Instance {}

impl Drop for Instance {
    fn drop(&mut self) {
        if let Some(destroy) = self.descriptor.destroy {
            // SAFETY: `raw` came from this library's `create` and is destroyed once.
            unsafe { destroy(self.raw) };
        }
    }
}

/// Which stage table asks, for the family check and messages.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Wanted {
    pub family: u32,
    pub table: &'static str,
    pub noun: &'static str,
}

pub(crate) const EDGE: Wanted = Wanted {
    family: family::EDGE,
    table: "edge",
    noun: "an edge detector",
};
pub(crate) const REGENERATOR: Wanted = Wanted {
    family: family::REGENERATOR,
    table: "regenerator",
    noun: "an image regenerator",
};
pub(crate) const POSE: Wanted = Wanted {
    family: family::POSE,
    table: "pose",
    noun: "a pose estimator",
};

fn family_noun(f: u32) -> String {
    match f {
        family::EDGE => EDGE.noun.to_string(),
        family::REGENERATOR => REGENERATOR.noun.to_string(),
        family::POSE => POSE.noun.to_string(),
        other => format!("of unknown stage family {other}"),
    }
}

/// Opens the library of `cfg` and creates one instance of its stage.
pub(crate) fn open(
    cfg: &PluginConfig,
    ctx: &StageContext,
    wanted: Wanted,
) -> Result<Instance, PluginError> {
    let path = cfg.resolved_path();
    if !path.is_file() {
        return Err(PluginError::NotFound { path });
    }
    // SAFETY: loading a library runs its initialisers; plugins are trusted
    // code the user chose in the config, like any other native library.
    let library = unsafe { Library::new(&path) }.map_err(|e| PluginError::Open {
        path: path.clone(),
        reason: e.to_string(),
    })?;
    let descriptor = read_descriptor(&library, &path, wanted);
    keep_loaded(library);
    let descriptor = descriptor?;
    let name = plugin_name(&descriptor, &path);
    let create = descriptor.create.ok_or_else(|| missing(&path, "create"))?;
    let release = descriptor
        .release
        .ok_or_else(|| missing(&path, "release"))?;
    if descriptor.destroy.is_none() {
        return Err(missing(&path, "destroy"));
    }
    let required = match wanted.family {
        family::EDGE => [("detect_edges", descriptor.detect_edges.is_some())].to_vec(),
        family::REGENERATOR => [("regenerate", descriptor.regenerate.is_some())].to_vec(),
        _ => [
            ("estimate_poses", descriptor.estimate_poses.is_some()),
            ("keypoint_names", descriptor.keypoint_names.is_some()),
        ]
        .to_vec(),
    };
    if let Some((f, _)) = required.iter().find(|(_, present)| !present) {
        return Err(missing(&path, f));
    }

    let options = cfg.options_json();
    let models_dir = ctx.models_dir.to_string_lossy();
    let mut raw: *mut c_void = std::ptr::null_mut();
    let result = call(&name, "create", release, |error| {
        // SAFETY: the strings live across the call; `raw` and `error` are writable.
        unsafe {
            create(
                GaitStr::new(&options),
                GaitStr::new(&models_dir),
                &mut raw,
                error,
            )
        }
    });
    if let Err(e) = result {
        // A plugin may have stored an instance before failing; it is its job
        // to not do that, but it is not ours to free it with a foreign `destroy`.
        return Err(match e {
            PluginError::BadInput {
                plugin, message, ..
            } => PluginError::Options {
                plugin,
                reason: message,
            },
            other => other,
        });
    }
    if raw.is_null() {
        return Err(PluginError::Malformed {
            plugin: name,
            call: "create",
            reason: "reported success but returned no instance".into(),
        });
    }
    Ok(Instance {
        raw,
        descriptor,
        release,
        name,
    })
}

/// Libraries are never unloaded: a plugin may have started threads (a
/// thread pool), registered thread-local destructors or kept caches that
/// outlive its instances, and unmapping its code under them would crash the
/// host. Loading the same file again only bumps the loader's reference count.
fn keep_loaded(library: Library) {
    static LOADED: Mutex<Vec<Library>> = Mutex::new(Vec::new());
    LOADED
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
        .push(library);
}

fn missing(path: &std::path::Path, function: &str) -> PluginError {
    PluginError::BadDescriptor {
        path: path.to_path_buf(),
        reason: format!("its descriptor has no `{function}` function"),
    }
}

/// Finds the entry symbol, checks the version first, then copies the
/// descriptor and checks the family.
fn read_descriptor(
    library: &Library,
    path: &std::path::Path,
    wanted: Wanted,
) -> Result<GaitPluginDescriptor, PluginError> {
    // SAFETY: the symbol, if present, is an `EntryFn` by the ABI's definition.
    let entry = unsafe { library.get::<EntryFn>(ENTRY_SYMBOL.as_bytes()) }.map_err(|_| {
        PluginError::NoEntry {
            path: path.to_path_buf(),
            symbol: ENTRY_SYMBOL,
        }
    })?;
    // SAFETY: calling the entry point of a loaded plugin.
    let ptr = unsafe { entry() };
    if ptr.is_null() {
        return Err(PluginError::BadDescriptor {
            path: path.to_path_buf(),
            reason: format!("`{ENTRY_SYMBOL}` returned null"),
        });
    }
    if !ptr.cast::<u32>().is_aligned() {
        return Err(PluginError::BadDescriptor {
            path: path.to_path_buf(),
            reason: format!("`{ENTRY_SYMBOL}` returned a misaligned pointer"),
        });
    }
    // SAFETY: every ABI version starts its descriptor with a u32 version.
    let version = unsafe { ptr.cast::<u32>().read() };
    if version != ABI_VERSION {
        return Err(PluginError::AbiMismatch {
            path: path.to_path_buf(),
            plugin: version,
            host: ABI_VERSION,
        });
    }
    if !ptr.is_aligned() {
        return Err(PluginError::BadDescriptor {
            path: path.to_path_buf(),
            reason: format!("`{ENTRY_SYMBOL}` returned a misaligned pointer"),
        });
    }
    // SAFETY: same version, so the pointer is to a descriptor of this layout.
    let descriptor = unsafe { ptr.read() };
    if descriptor.family != wanted.family {
        return Err(PluginError::WrongFamily {
            path: path.to_path_buf(),
            table: wanted.table,
            found: family_noun(descriptor.family),
            wanted: wanted.noun,
        });
    }
    Ok(descriptor)
}

fn plugin_name(d: &GaitPluginDescriptor, path: &std::path::Path) -> String {
    // SAFETY: the name is a static string of the plugin (any bytes are fine).
    let name = unsafe { copy_bytes(d.name, 256) }
        .map(|b| String::from_utf8_lossy(&b).into_owned())
        .unwrap_or_default();
    if name.trim().is_empty() {
        path.display().to_string()
    } else {
        name
    }
}

/// Copies at most `max` bytes of a plugin string; `None` for a null pointer
/// with a non-zero length.
///
/// # Safety
/// `s.ptr` points to `s.len` readable bytes (if non-null).
pub(crate) unsafe fn copy_bytes(s: GaitStr, max: usize) -> Option<Vec<u8>> {
    if s.len == 0 {
        return Some(Vec::new());
    }
    if s.ptr.is_null() {
        return None;
    }
    // SAFETY: per the contract above; reading fewer bytes is fine.
    Some(unsafe { std::slice::from_raw_parts(s.ptr, s.len.min(max)) }.to_vec())
}

/// Releases a plugin `owner` token when dropped, so every path out of a call
/// (including validation errors) gives the plugin its memory back.
pub(crate) struct Owned {
    release: ReleaseFn,
    owner: *mut c_void,
}

impl Owned {
    pub(crate) fn new(release: ReleaseFn, owner: *mut c_void) -> Self {
        Self { release, owner }
    }
}

impl Drop for Owned {
    fn drop(&mut self) {
        if !self.owner.is_null() {
            // SAFETY: the token came from this plugin and is released once.
            unsafe { (self.release)(self.owner) };
        }
    }
}

/// Runs one plugin call with a fresh error struct and turns its status into a
/// result, copying and releasing any error message.
pub(crate) fn call(
    plugin: &str,
    what: &'static str,
    release: ReleaseFn,
    f: impl FnOnce(*mut GaitError) -> i32,
) -> Result<(), PluginError> {
    let mut error = GaitError {
        message: GaitStr::EMPTY,
        owner: std::ptr::null_mut(),
    };
    let code = f(&mut error);
    let _owned = Owned::new(release, error.owner);
    if code == status::OK {
        return Ok(());
    }
    // SAFETY: the plugin filled `message` with a readable string (or nothing).
    let message = unsafe { copy_bytes(error.message, MAX_MESSAGE) }
        .map(|b| String::from_utf8_lossy(&b).into_owned())
        .filter(|m| !m.trim().is_empty())
        .unwrap_or_else(|| "(no message)".into());
    let (plugin, call) = (plugin.to_string(), what);
    Err(match code {
        status::BAD_INPUT => PluginError::BadInput {
            plugin,
            call,
            message,
        },
        status::FAILED | status::PANICKED => PluginError::Failed {
            plugin,
            call,
            message,
        },
        other => PluginError::Malformed {
            plugin,
            call,
            reason: format!("unknown status code {other} (message: {message})"),
        },
    })
}
