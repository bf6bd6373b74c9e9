//! The link from a checklist's frame to `gait review`: each run folder has its own port on
//! 127.0.0.1, derived from the folder's path, which `gait review RUN` listens on unless told
//! otherwise. So a report's frame links reach the review of that run while it runs, from the
//! report opened in any browser (the page keeps the session's token in the browser's storage
//! for that address, so a link needs none).

use std::path::Path;

/// Run folders' ports: 20000-24999, below the ranges systems draw outgoing connections' local
/// ports from (Linux 32768-60999, macOS and Windows 49152-65535), where a busy machine's own
/// connections would take one now and then. A port that is taken (another program, or another
/// folder's review on the same port) makes `gait review` serve on a free one and say that the
/// report's links will not reach it.
const FIRST: u16 = 20000;
const SPAN: u64 = 5000;

/// The port `gait review` serves the run folder `run` on by default.
pub fn review_port(run: &Path) -> u16 {
    let path = std::fs::canonicalize(run)
        .or_else(|_| std::path::absolute(run))
        .unwrap_or_else(|_| run.to_path_buf());
    // FNV-1a: stable across builds and platforms (the standard hasher is not).
    let hash = path
        .to_string_lossy()
        .bytes()
        .fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
            (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
        });
    FIRST + (hash % SPAN) as u16
}

/// The address that shows frame `frame` of run folder `run` in its running `gait review`.
pub fn review_url(run: &Path, frame: usize) -> String {
    format!("http://127.0.0.1:{}/?frame={frame}", review_port(run))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_keeps_its_port_however_it_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let run = dir.path().join("run");
        std::fs::create_dir(&run).unwrap();
        let port = review_port(&run);
        assert!((FIRST..FIRST + SPAN as u16).contains(&port));
        assert_eq!(review_port(&run.join("..").join("run")), port);
        let other = dir.path().join("other");
        std::fs::create_dir(&other).unwrap();
        assert_ne!(review_port(&other), port);
        assert_eq!(
            review_url(&run, 90),
            format!("http://127.0.0.1:{port}/?frame=90")
        );
    }
}
