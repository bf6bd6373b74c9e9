//! Reading a checkpoint's tensors by name: PyTorch `.pth` (the zip format of
//! torch >= 1.6 through `candle_core::pickle`, and the older "legacy" format,
//! which `body_pose_model.pth` may well be in) and `.safetensors`. Shared by
//! the stages that load PyTorch weights (OpenPose, HED), so every one gets the
//! same checks of declared lengths and shapes before candle allocates them.

use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

use candle_core::pickle::{Object, Stack, TensorInfo};
use candle_core::{DType, Device, Tensor};

/// Why a checkpoint could not be read (one line, for the model error).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct CheckpointError(String);

/// `torch.save`'s legacy format starts with a pickle (protocol 2) of this
/// magic number (a 10-byte long): `\x80\x02\x8a\x0a` + its bytes + STOP.
const LEGACY_MAGIC: [u8; 15] = [
    0x80, 0x02, 0x8a, 0x0a, 0x6c, 0xfc, 0x9c, 0x46, 0xf9, 0x20, 0x6a, 0xa8, 0x50, 0x19, 0x2e,
];
const ZIP_MAGIC: [u8; 4] = *b"PK\x03\x04";

fn read_err(e: impl ToString) -> CheckpointError {
    CheckpointError(e.to_string())
}

/// Every tensor in the file, converted to f32, by name.
pub fn read_tensors(path: &Path) -> Result<HashMap<String, Tensor>, CheckpointError> {
    let mut head = [0u8; 15];
    let n = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut head))
        .map_err(read_err)?;
    let head = &head[..n];
    // candle's readers index into what the file declares and can panic on a malformed one.
    let guarded = |f: fn(&Path) -> Result<HashMap<String, Tensor>, CheckpointError>| {
        crate::guard::quietly("reading the checkpoint", || f(path)).map_err(read_err)?
    };
    let tensors = if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("safetensors"))
    {
        candle_core::safetensors::load(path, &Device::Cpu).map_err(read_err)?
    } else if head.starts_with(&ZIP_MAGIC) {
        guarded(read_zip_pth)?
    } else if head == LEGACY_MAGIC {
        guarded(read_legacy_pth)?
    } else {
        return Err(CheckpointError(
            "neither a PyTorch checkpoint (.pth, zip or legacy format) nor .safetensors".into(),
        ));
    };
    tensors
        .into_iter()
        .map(|(name, t)| {
            let t = if t.dtype() == DType::F32 {
                t
            } else {
                t.to_dtype(DType::F32).map_err(read_err)?
            };
            Ok((name, t))
        })
        .collect()
}

/// The entries of a zip checkpoint with their sizes, after checking the pickle's declared
/// lengths (candle allocates them before reading).
fn zip_entries(path: &Path) -> Result<HashMap<String, u64>, CheckpointError> {
    let file = std::fs::File::open(path).map_err(read_err)?;
    let mut zip = zip::ZipArchive::new(file).map_err(read_err)?;
    let mut sizes = HashMap::new();
    for k in 0..zip.len() {
        let mut entry = zip.by_index(k).map_err(read_err)?;
        let name = entry.name().map_err(read_err)?.to_string();
        if name.ends_with("data.pkl") {
            let mut pickle = Vec::new();
            // A pickle of tensor names and shapes is small; a larger one is not a checkpoint.
            (&mut entry)
                .take(MAX_PICKLE)
                .read_to_end(&mut pickle)
                .map_err(read_err)?;
            crate::pickle_guard::check(&pickle).map_err(read_err)?;
        }
        sizes.insert(name, entry.size());
    }
    Ok(sizes)
}

/// The largest pickle of names and shapes read from a zip checkpoint.
const MAX_PICKLE: u64 = 256 << 20;

fn read_zip_pth(path: &Path) -> Result<HashMap<String, Tensor>, CheckpointError> {
    let sizes = zip_entries(path)?;
    let pth = candle_core::pickle::PthTensors::new(path, None).map_err(read_err)?;
    // A tensor's declared shape must fit in its storage entry before candle allocates it.
    for (name, info) in pth.tensor_infos() {
        let need = info
            .layout
            .shape()
            .elem_count()
            .checked_mul(info.dtype.size_in_bytes())
            .and_then(|n| n.checked_add(info.layout.start_offset() * info.dtype.size_in_bytes()));
        let have = sizes.get(&info.path).copied().unwrap_or(0);
        if need.is_none_or(|n| n as u64 > have) {
            return Err(CheckpointError(format!(
                "tensor `{name}` declares shape {:?} but its storage `{}` holds {have} bytes",
                info.layout.dims(),
                info.path
            )));
        }
    }
    let mut out = HashMap::new();
    for name in pth.tensor_infos().keys() {
        let t = pth
            .get(name)
            .map_err(|e| CheckpointError(format!("tensor `{name}`: {e}")))?
            .ok_or_else(|| CheckpointError(format!("tensor `{name}` vanished")))?;
        out.insert(name.clone(), t);
    }
    Ok(out)
}

/// The legacy format: pickles of the magic number, the protocol version, the
/// system info and the object (whose tensors name storages by key), then a
/// pickled list of storage keys, then each storage as a little-endian u64
/// element count followed by its raw bytes.
fn read_legacy_pth(path: &Path) -> Result<HashMap<String, Tensor>, CheckpointError> {
    // In memory, so that each pickle's declared lengths can be checked before candle reads it.
    let bytes = std::fs::read(path).map_err(read_err)?;
    let mut r = std::io::Cursor::new(bytes.as_slice());
    // Skipped, not parsed: candle's unpickler cannot take a 10-byte long.
    let mut magic = [0u8; LEGACY_MAGIC.len()];
    r.read_exact(&mut magic).map_err(read_err)?;
    let _protocol = unpickle(&mut r)?;
    let _sys_info = unpickle(&mut r)?;
    let Object::Dict(entries) = unpickle(&mut r)? else {
        return Err(CheckpointError(
            "the checkpoint is not a dict of tensors (a state_dict)".into(),
        ));
    };
    let mut infos: Vec<TensorInfo> = Vec::with_capacity(entries.len());
    for (name, value) in entries {
        // The storage tuple of this format has the same first five fields as
        // the zip format's, so candle's parser applies.
        if let Some(info) = value
            .into_tensor_info(name, Path::new(""))
            .map_err(read_err)?
        {
            infos.push(info);
        }
    }
    let keys = match unpickle(&mut r)? {
        Object::List(k) | Object::Tuple(k) => k
            .into_iter()
            .map(|k| {
                k.unicode()
                    .map_err(|o| read_err(format!("storage key {o:?}")))
            })
            .collect::<Result<Vec<_>, _>>()?,
        o => return Err(read_err(format!("expected storage keys, found {o:?}"))),
    };
    let key_of = |info: &TensorInfo| info.path.trim_start_matches('/').to_string();
    let mut storages: HashMap<String, Vec<u8>> = HashMap::new();
    for key in keys {
        let dtype = infos
            .iter()
            .find(|i| key_of(i) == key)
            .map(|i| i.dtype)
            .ok_or_else(|| read_err(format!("storage {key} belongs to no tensor")))?;
        let mut count = [0u8; 8];
        r.read_exact(&mut count).map_err(read_err)?;
        let bytes = (u64::from_le_bytes(count) as usize)
            .checked_mul(dtype.size_in_bytes())
            .ok_or_else(|| read_err("storage size overflows"))?;
        let mut data = Vec::new();
        (&mut r)
            .take(bytes as u64)
            .read_to_end(&mut data)
            .map_err(read_err)?;
        if data.len() != bytes {
            return Err(read_err(format!("storage {key} is truncated")));
        }
        storages.insert(key, data);
    }
    let mut out = HashMap::new();
    for info in infos {
        let layout = &info.layout;
        if !layout.is_contiguous() {
            return Err(read_err(format!(
                "tensor `{}` is not contiguous",
                info.name
            )));
        }
        let data = storages
            .get(&key_of(&info))
            .ok_or_else(|| read_err(format!("tensor `{}`: storage missing", info.name)))?;
        let start = layout.start_offset();
        let len = layout.shape().elem_count() * info.dtype.size_in_bytes();
        let bytes = data
            .get(start..start + len)
            .ok_or_else(|| read_err(format!("tensor `{}` overruns its storage", info.name)))?;
        let t = Tensor::from_raw_buffer(bytes, info.dtype, layout.dims(), &Device::Cpu)
            .map_err(read_err)?;
        out.insert(info.name, t);
    }
    Ok(out)
}

fn unpickle(r: &mut std::io::Cursor<&[u8]>) -> Result<Object, CheckpointError> {
    let at = (r.position() as usize).min(r.get_ref().len());
    crate::pickle_guard::check(&r.get_ref()[at..]).map_err(read_err)?;
    let mut stack = Stack::empty();
    stack.read_loop(r).map_err(read_err)?;
    stack.finalize().map_err(read_err)
}
