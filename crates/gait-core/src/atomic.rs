//! Files appear under their final name only when complete: written to a
//! hidden temporary sibling (`.NAME.PID.N.partial`), flushed to disk, then
//! renamed. A killed run, a full disk or a failed write never leaves a file
//! that looks finished but is not, and concurrent writers of one file (runs
//! sharing a cache) each rename a whole file over the other.

use std::ffi::OsString;
use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// The suffix of temporary files; [`remove_stale`] looks for it.
pub const PARTIAL: &str = ".partial";

/// Distinguishes the temporary files of concurrent writes from one process.
static NEXT: AtomicU64 = AtomicU64::new(0);

/// Writes `bytes` to `path` atomically.
pub fn write(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_with(path, |w| w.write_all(bytes))
}

/// Writes `bytes` to `path` atomically for a killed process, without waiting
/// for the disk: for files whose content is checked when read (the stage
/// cache's checksummed entries), where the rare entry a power cut leaves empty
/// or torn is found and computed again. A flush per cache entry cost the
/// sample's run about a second.
pub fn write_unsynced(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_impl(path, |w| w.write_all(bytes), false)
}

/// Lets `fill` write into a temporary file, then renames it to `path`; on
/// any error the temporary file is removed.
pub fn write_with<F>(path: &Path, fill: F) -> io::Result<()>
where
    F: FnOnce(&mut BufWriter<File>) -> io::Result<()>,
{
    write_impl(path, fill, true)
}

fn write_impl<F>(path: &Path, fill: F, sync: bool) -> io::Result<()>
where
    F: FnOnce(&mut BufWriter<File>) -> io::Result<()>,
{
    let (tmp, file) = create_temp(path)?;
    let result = (|| {
        let mut w = BufWriter::new(file);
        fill(&mut w)?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        if sync {
            file.sync_all()?;
        }
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// A new temporary sibling of `path`, never one another writer holds.
fn create_temp(path: &Path) -> io::Result<(PathBuf, File)> {
    let name = path
        .file_name()
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "not a file path"))?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    loop {
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let mut tmp = OsString::from(".");
        tmp.push(name);
        tmp.push(format!(".{}.{n}{PARTIAL}", std::process::id()));
        let tmp = dir.join(tmp);
        match OpenOptions::new().write(true).create_new(true).open(&tmp) {
            Ok(f) => return Ok((tmp, f)),
            // Left by a killed process that had our pid: take the next name.
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
}

/// Removes the temporary files a killed writer left directly in `dir`
/// (call it only on a folder no other process writes into now); how many.
pub fn remove_stale(dir: &Path) -> usize {
    let Ok(entries) = fs::read_dir(dir) else {
        return 0;
    };
    entries
        .flatten()
        .filter(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            name.starts_with('.') && name.ends_with(PARTIAL)
        })
        .filter(|e| fs::remove_file(e.path()).is_ok())
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_failed_write_leaves_nothing_and_keeps_the_old_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.csv");
        fs::write(&path, b"old").unwrap();
        let err = write_with(&path, |w| {
            w.write_all(b"half")?;
            Err(io::Error::other("interrupted"))
        });
        assert!(err.is_err());
        assert_eq!(names(dir.path()), vec!["out.csv"]);
        assert_eq!(fs::read(&path).unwrap(), b"old");
        write(&path, b"whole").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"whole");
    }

    #[test]
    fn a_missing_folder_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        assert!(write(&dir.path().join("no/such/out.csv"), b"x").is_err());
    }

    #[test]
    fn stale_temporary_files_are_removed_and_nothing_else() {
        let dir = tempfile::tempdir().unwrap();
        fs::write(dir.path().join(".angles.csv.123.0.partial"), b"ha").unwrap();
        fs::write(dir.path().join("angles.csv"), b"whole").unwrap();
        fs::write(dir.path().join("notes.partial"), b"a user's").unwrap();
        assert_eq!(remove_stale(dir.path()), 1);
        assert_eq!(names(dir.path()), vec!["angles.csv", "notes.partial"]);
    }
}
