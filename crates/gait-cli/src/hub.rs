//! Downloads of model files from the Hugging Face Hub (`gait models fetch hed`,
//! `openpose`, `sd15-controlnet-canny`), checked against the Hub's own
//! checksums (the sha256 of LFS files).

use std::fmt::Write as _;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::time::Duration;

use hf_hub::api::sync::{Api, ApiBuilder};
use hf_hub::{Repo, RepoType};
use sha1::Sha1;
use sha2::{Digest, Sha256};

/// The reachability check must fail fast when there is no network; the
/// downloads themselves have no overall limit (multi-GB files).
const PROBE_TIMEOUT: Duration = Duration::from_secs(10);

/// One repository at one revision and the files taken from it.
#[derive(Debug, Clone)]
pub struct HubRepo {
    pub id: String,
    pub revision: String,
    /// (path inside the repository, destination on disk)
    pub files: Vec<(String, PathBuf)>,
}

/// The default repository of each Hub-hosted model, and its files.
pub fn defaults(model: &str, models_dir: &Path) -> Option<Vec<HubRepo>> {
    let repo = |id: &str, dir: &Path, files: &[&str]| HubRepo {
        id: id.to_string(),
        revision: "main".to_string(),
        files: files.iter().map(|f| (f.to_string(), dir.join(f))).collect(),
    };
    match model {
        // gait-edge's HED (candle backend) reads <models>/ControlNetHED.pth.
        "hed" => Some(vec![repo(
            "lllyasviel/Annotators",
            models_dir,
            &["ControlNetHED.pth"],
        )]),
        // gait-pose's OpenPose (candle backend, COCO-18) reads
        // <models>/openpose/body_pose_model.pth.
        "openpose" => Some(vec![HubRepo {
            id: "lllyasviel/Annotators".to_string(),
            revision: "main".to_string(),
            files: vec![(
                "body_pose_model.pth".to_string(),
                models_dir.join(gait_pose::openpose::OpenposeConfig::FETCHED_CHECKPOINT),
            )],
        }]),
        // gait-diffuse reads these (configs when present; the tokenizer is
        // built from merges.txt alone) from its default folders.
        "sd15-controlnet-canny" => Some(vec![
            repo(
                "stable-diffusion-v1-5/stable-diffusion-v1-5",
                &models_dir.join("stable-diffusion-v1-5"),
                &[
                    "unet/config.json",
                    "unet/diffusion_pytorch_model.safetensors",
                    "vae/config.json",
                    "vae/diffusion_pytorch_model.safetensors",
                    "text_encoder/config.json",
                    "text_encoder/model.safetensors",
                    "tokenizer/merges.txt",
                ],
            ),
            repo(
                "lllyasviel/sd-controlnet-canny",
                &models_dir.join("sd-controlnet-canny"),
                &["config.json", "diffusion_pytorch_model.safetensors"],
            ),
        ]),
        _ => None,
    }
}

/// Why a fetch failed, as one line for the user.
#[derive(Debug, thiserror::Error)]
pub enum HubError {
    #[error("cannot reach the Hugging Face Hub at {endpoint} ({reason}): {manual}")]
    Unreachable {
        endpoint: String,
        reason: String,
        manual: String,
    },
    #[error("{repo} at revision {revision} is not available from {endpoint} (HTTP {status})")]
    NoRepo {
        repo: String,
        revision: String,
        endpoint: String,
        status: u16,
    },
    #[error("download of {file} from {repo} failed: {reason}")]
    Download {
        file: String,
        repo: String,
        reason: String,
    },
    #[error(
        "checksum mismatch for {file} from {repo}: the Hub says {expected}, the download has {actual}; the file was deleted"
    )]
    Checksum {
        file: String,
        repo: String,
        expected: String,
        actual: String,
    },
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> HubError + '_ {
    move |source| HubError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Downloads every file of `repos` not already on disk (every file when
/// `force`) into `models_dir`; returns the files written.
///
/// `HF_ENDPOINT` replaces the Hub's address, `HF_TOKEN` (or the token file of
/// `HF_HOME`) authenticates. Each file is downloaded under a temporary folder
/// inside `models_dir`, checked against the Hub's checksum and only then
/// renamed to its destination; the temporary folder is always removed.
pub fn fetch(repos: &[HubRepo], models_dir: &Path, force: bool) -> Result<Vec<PathBuf>, HubError> {
    let wanted: Vec<HubRepo> = repos
        .iter()
        .map(|r| HubRepo {
            files: r
                .files
                .iter()
                .filter(|(_, d)| force || !d.is_file())
                .cloned()
                .collect(),
            ..r.clone()
        })
        .filter(|r| !r.files.is_empty())
        .collect();
    if wanted.is_empty() {
        return Ok(Vec::new());
    }
    let endpoint = std::env::var("HF_ENDPOINT")
        .ok()
        .filter(|e| !e.is_empty())
        .unwrap_or_else(|| "https://huggingface.co".to_string());
    let endpoint = endpoint.trim_end_matches('/').to_string();
    let tmp = models_dir.join(format!(".gait-fetch-{}", std::process::id()));
    let mut builder = ApiBuilder::from_env()
        .with_endpoint(endpoint.clone())
        .with_cache_dir(tmp.clone())
        .with_progress(true);
    if let Some(token) = std::env::var("HF_TOKEN").ok().filter(|t| !t.is_empty()) {
        builder = builder.with_token(Some(token));
    }
    let api = builder.build().map_err(|e| HubError::Unreachable {
        endpoint: endpoint.clone(),
        reason: e.to_string(),
        manual: manual(&wanted, &endpoint),
    })?;
    // Probe before creating anything so that an offline run leaves no trace.
    for r in &wanted {
        probe(&api, r, &endpoint, &wanted)?;
    }
    std::fs::create_dir_all(&tmp).map_err(io(&tmp))?;
    let result = download_all(&api, &wanted);
    // Partial downloads and hf-hub's cache layout live only in `tmp`.
    let _ = std::fs::remove_dir_all(&tmp);
    result
}

/// The manual alternative: each file's URL and where it goes.
fn manual(repos: &[HubRepo], endpoint: &str) -> String {
    let mut s = String::new();
    for r in repos {
        for (file, dest) in &r.files {
            let name = file.rsplit('/').next().unwrap_or(file);
            if !s.is_empty() {
                s.push_str("; ");
            }
            let _ = write!(
                s,
                "download {name} from {endpoint}/{}/resolve/{}/{file} and put it at {}",
                r.id,
                r.revision,
                dest.display()
            );
        }
    }
    s
}

fn hub_repo(r: &HubRepo) -> Repo {
    Repo::with_revision(r.id.clone(), RepoType::Model, r.revision.clone())
}

fn probe(api: &Api, r: &HubRepo, endpoint: &str, all: &[HubRepo]) -> Result<(), HubError> {
    match api
        .repo(hub_repo(r))
        .info_request()
        .timeout(PROBE_TIMEOUT)
        .call()
    {
        Ok(_) => Ok(()),
        Err(e) => {
            let reason = crate::error::one_line(&e.to_string());
            match e.into_response() {
                Some(resp) => Err(HubError::NoRepo {
                    repo: r.id.clone(),
                    revision: r.revision.clone(),
                    endpoint: endpoint.to_string(),
                    status: resp.status(),
                }),
                None => Err(HubError::Unreachable {
                    endpoint: endpoint.to_string(),
                    reason,
                    manual: manual(all, endpoint),
                }),
            }
        }
    }
}

fn download_all(api: &Api, repos: &[HubRepo]) -> Result<Vec<PathBuf>, HubError> {
    let mut written = Vec::new();
    for r in repos {
        let repo = api.repo(hub_repo(r));
        for (file, dest) in &r.files {
            eprintln!("{} {file} -> {}", r.id, dest.display());
            let failed = |reason: String| HubError::Download {
                file: file.clone(),
                repo: r.id.clone(),
                reason: crate::error::one_line(&reason),
            };
            let pointer = repo.download(file).map_err(|e| failed(e.to_string()))?;
            // hf-hub stores the file as blobs/<ETag> (the pointer is a
            // symlink to it): the ETag is the Hub's checksum of the content.
            let blob = std::fs::canonicalize(&pointer).map_err(io(&pointer))?;
            let etag = blob
                .file_name()
                .and_then(|n| n.to_str())
                .unwrap_or_default()
                .to_string();
            verify(&blob, &etag).map_err(|e| match e {
                Verify::Io(source) => HubError::Io {
                    path: blob.clone(),
                    source,
                },
                Verify::Unknown => failed(format!("the Hub's ETag `{etag}` is not a checksum")),
                Verify::Mismatch(actual) => {
                    let _ = std::fs::remove_file(&blob);
                    HubError::Checksum {
                        file: file.clone(),
                        repo: r.id.clone(),
                        expected: etag.clone(),
                        actual,
                    }
                }
            })?;
            if let Some(parent) = dest.parent() {
                std::fs::create_dir_all(parent).map_err(io(parent))?;
            }
            std::fs::rename(&blob, dest).map_err(io(dest))?;
            written.push(dest.clone());
        }
    }
    Ok(written)
}

#[derive(Debug)]
enum Verify {
    Io(std::io::Error),
    /// The ETag is neither a sha256 nor a git sha1.
    Unknown,
    /// The checksum the content actually has.
    Mismatch(String),
}

/// LFS files carry their sha256 as ETag; plain git files their git blob
/// sha1 (`sha1("blob <len>\0" + content)`).
fn verify(path: &Path, etag: &str) -> Result<(), Verify> {
    let is_hex = |n: usize| etag.len() == n && etag.bytes().all(|b| b.is_ascii_hexdigit());
    let actual = if is_hex(64) {
        hash_file::<Sha256>(path, None)
    } else if is_hex(40) {
        let len = std::fs::metadata(path).map_err(Verify::Io)?.len();
        hash_file::<Sha1>(path, Some(format!("blob {len}\0").as_bytes()))
    } else {
        return Err(Verify::Unknown);
    }
    .map_err(Verify::Io)?;
    if actual.eq_ignore_ascii_case(etag) {
        Ok(())
    } else {
        Err(Verify::Mismatch(actual))
    }
}

fn hash_file<D: Digest>(path: &Path, prefix: Option<&[u8]>) -> std::io::Result<String> {
    let mut hasher = D::new();
    if let Some(p) = prefix {
        hasher.update(p);
    }
    let mut file = std::fs::File::open(path)?;
    let mut buf = vec![0u8; 1 << 20];
    loop {
        let n = file.read(&mut buf)?;
        if n == 0 {
            break;
        }
        hasher.update(&buf[..n]);
    }
    Ok(hasher.finalize().iter().fold(String::new(), |mut s, b| {
        let _ = write!(s, "{b:02x}");
        s
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, content: &[u8]) -> PathBuf {
        let p = dir.join("f");
        std::fs::write(&p, content).unwrap();
        p
    }

    #[test]
    fn lfs_etag_is_sha256() {
        let dir = tempfile::tempdir().unwrap();
        let p = write(dir.path(), b"abc");
        // FIPS 180-2 test vector for "abc".
        let abc = "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad";
        assert!(verify(&p, abc).is_ok());
        let other = "ca7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad";
        match verify(&p, other) {
            Err(Verify::Mismatch(actual)) => assert_eq!(actual, abc),
            r => panic!("{r:?}"),
        }
    }

    #[test]
    fn plain_etag_is_git_blob_sha1() {
        let dir = tempfile::tempdir().unwrap();
        // `printf 'hello\n' | git hash-object --stdin`
        let p = write(dir.path(), b"hello\n");
        assert!(verify(&p, "ce013625030ba8dba906f756967f9e9ca394464a").is_ok());
        assert!(matches!(
            verify(&p, "0000000000000000000000000000000000000000"),
            Err(Verify::Mismatch(_))
        ));
        assert!(matches!(verify(&p, "W/\"xyz\""), Err(Verify::Unknown)));
    }

    #[test]
    fn manual_names_url_and_destination() {
        let repos = defaults("hed", Path::new("/m")).unwrap();
        assert_eq!(
            manual(&repos, "https://huggingface.co"),
            "download ControlNetHED.pth from https://huggingface.co/lllyasviel/Annotators/resolve/main/ControlNetHED.pth and put it at /m/ControlNetHED.pth"
        );
    }
}
