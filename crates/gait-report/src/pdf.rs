//! `report.pdf`: report.html printed by headless Chromium (A4, from the page's
//! print styles), so the PDF has exactly the HTML's content.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use gait_eval::EvalError;

/// Browsers tried on the PATH, in order (`$CHROMIUM` first when set).
const NAMES: [&str; 4] = ["chromium", "chromium-browser", "google-chrome", "chrome"];

/// The Chromium to print with: `$CHROMIUM`, else the first of [`NAMES`] on the PATH.
pub fn find_chromium() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("CHROMIUM").filter(|p| !p.is_empty()) {
        return Some(PathBuf::from(p));
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .flat_map(|d| NAMES.map(|n| d.join(n)))
        .find(|p| p.is_file())
}

/// Prints `html` to `pdf` (written under a temporary name, then renamed).
pub fn print_pdf(chromium: &Path, html: &Path, pdf: &Path) -> Result<(), EvalError> {
    let html = std::fs::canonicalize(html)
        .map_err(|e| EvalError::io(format!("finding {}", html.display()), e))?;
    let tmp = pdf.with_file_name(".report.pdf.partial");
    let profile = tempfile_dir(pdf)?;
    let mut child = Command::new(chromium)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-pdf-header-footer",
            "--run-all-compositor-stages-before-draw",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(format!("--print-to-pdf={}", tmp.display()))
        .arg(format!("file://{}", html.display()))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| EvalError::io(format!("starting {}", chromium.display()), e))?;
    let start = Instant::now();
    // A headless Chromium that cannot print (no display libraries, a broken
    // profile) may hang instead of exiting; the run must not.
    while child
        .try_wait()
        .map_err(|e| EvalError::io("waiting for chromium", e))?
        .is_none()
    {
        if start.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            let _ = std::fs::remove_dir_all(&profile);
            let _ = std::fs::remove_file(&tmp);
            return Err(EvalError::io(
                "printing report.pdf",
                std::io::Error::other("chromium did not finish within 120 s"),
            ));
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let out = child
        .wait_with_output()
        .map_err(|e| EvalError::io("waiting for chromium", e))?;
    let _ = std::fs::remove_dir_all(&profile);
    let ok = std::fs::metadata(&tmp)
        .map(|m| m.len() > 0)
        .unwrap_or(false);
    if !ok {
        // An empty or cut-short file (a full disk) is not left behind.
        let _ = std::fs::remove_file(&tmp);
        let said = String::from_utf8_lossy(&out.stderr);
        let last = said
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("no output");
        return Err(EvalError::io(
            "printing report.pdf",
            std::io::Error::other(format!("chromium wrote no PDF ({})", last.trim())),
        ));
    }
    std::fs::rename(&tmp, pdf).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        EvalError::io(format!("renaming {}", tmp.display()), e)
    })
}

/// A fresh browser profile beside the PDF, so printing never touches the
/// user's own Chromium profile.
fn tempfile_dir(pdf: &Path) -> Result<PathBuf, EvalError> {
    let dir = pdf.with_file_name(format!(".chromium-profile-{}", std::process::id()));
    std::fs::create_dir_all(&dir)
        .map_err(|e| EvalError::io(format!("creating {}", dir.display()), e))?;
    Ok(dir)
}
