//! Writing a file so that readers never see half of it: a temporary file in the same folder,
//! flushed to disk, then renamed over the target.

use std::path::Path;

use crate::error::C3dError;

/// Writes `bytes` to `path` atomically (same folder, so the rename cannot cross file systems).
pub(crate) fn write(path: &Path, bytes: &[u8]) -> Result<(), C3dError> {
    gait_core::atomic::write(path, bytes).map_err(|source| C3dError::Io {
        path: path.to_path_buf(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    #[test]
    fn replaces_the_target_and_leaves_no_temporary_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.c3d");
        fs::write(&path, b"old").unwrap();
        write(&path, b"new contents").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"new contents");
        let names: Vec<_> = fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("out.c3d")]);
    }

    #[test]
    fn missing_folder_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("no/such/folder/out.c3d");
        let e = write(&path, b"x").unwrap_err();
        assert!(matches!(e, C3dError::Io { .. }), "{e}");
        assert!(e.to_string().contains("out.c3d"));
    }
}
