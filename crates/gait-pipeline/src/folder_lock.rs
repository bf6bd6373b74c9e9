//! One writer per run folder: `.gait.lock`, held with an exclusive `flock`
//! for as long as a run (or a study, or a save of corrections) writes there.
//! The kernel drops the lock when its holder dies, so a crashed run never
//! leaves a folder locked; the file names the holder for the one who waits.
//! Taking the lock removes the temporary files a killed writer left there.

use std::fs::{self, File, OpenOptions, TryLockError};
use std::io::{Read, Seek, Write};
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

use crate::PipelineError;

const NAME: &str = ".gait.lock";

/// Held while alive; the lock file goes when it is dropped.
#[derive(Debug)]
pub struct FolderLock {
    file: File,
    path: PathBuf,
}

impl FolderLock {
    /// Locks `dir` (created if missing) for `what` (e.g. "gait run"), or
    /// fails at once naming the process that holds it.
    pub fn acquire(dir: &Path, what: &str) -> Result<Self, PipelineError> {
        let io = |e| PipelineError::io(format!("locking {}", dir.display()), e);
        fs::create_dir_all(dir).map_err(io)?;
        let path = dir.join(NAME);
        loop {
            let mut file = OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(&path)
                .map_err(io)?;
            match file.try_lock() {
                Ok(()) => {}
                Err(TryLockError::WouldBlock) => return Err(busy(dir, &mut file)),
                Err(TryLockError::Error(e)) => return Err(io(e)),
            }
            // A holder that ended between our open and our lock removed the
            // file we hold: lock the one now at the path instead.
            if !same_file(&file, &path) {
                continue;
            }
            let holder = format!("{} {what}\n", std::process::id());
            file.set_len(0).map_err(io)?;
            file.rewind().map_err(io)?;
            file.write_all(holder.as_bytes()).map_err(io)?;
            // Ours now: what a killed writer left half-written can go.
            crate::atomic::remove_stale(dir);
            return Ok(Self { file, path });
        }
    }
}

impl Drop for FolderLock {
    fn drop(&mut self) {
        // Removed while still locked, so nobody takes a lock on a file about to go.
        let _ = fs::remove_file(&self.path);
        let _ = self.file.unlock();
    }
}

fn same_file(file: &File, path: &Path) -> bool {
    match (file.metadata(), fs::metadata(path)) {
        (Ok(a), Ok(b)) => a.ino() == b.ino() && a.dev() == b.dev(),
        _ => false,
    }
}

/// The error for a folder another process holds, with its pid and command.
fn busy(dir: &Path, file: &mut File) -> PipelineError {
    let mut text = String::new();
    let _ = file.read_to_string(&mut text);
    let holder = match text.trim().split_once(' ') {
        Some((pid, what)) => format!("{what} (pid {pid})"),
        None => "another gait process".to_string(),
    };
    PipelineError::Busy {
        path: dir.to_path_buf(),
        holder,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_writer_is_refused_with_the_holders_pid_until_the_first_ends() {
        let dir = tempfile::tempdir().unwrap();
        let first = FolderLock::acquire(dir.path(), "gait run").unwrap();
        let err = FolderLock::acquire(dir.path(), "gait run")
            .unwrap_err()
            .to_string();
        let pid = std::process::id().to_string();
        assert!(err.contains(&pid) && err.contains("gait run"), "{err}");
        drop(first);
        assert!(!dir.path().join(NAME).exists());
        let again = FolderLock::acquire(dir.path(), "gait review save");
        assert!(again.is_ok());
    }

    #[test]
    fn a_lock_file_left_by_a_dead_holder_does_not_block() {
        let dir = tempfile::tempdir().unwrap();
        // What a killed holder leaves: the file with its pid, but no lock (the kernel dropped it).
        fs::write(dir.path().join(NAME), "999999 gait run\n").unwrap();
        let lock = FolderLock::acquire(dir.path(), "gait run").unwrap();
        let text = fs::read_to_string(dir.path().join(NAME)).unwrap();
        assert_eq!(text, format!("{} gait run\n", std::process::id()));
        drop(lock);
    }
}
