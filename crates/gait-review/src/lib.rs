//! `gait review`: a page in the browser to look at a run frame by frame and correct it.
//!
//! [`serve`] starts a local web server (loopback only, a random token in the URL) for a
//! [`ReviewSource`]: a run folder, or a keypoints file with its video. The page shows each frame
//! with the skeleton, the lower-limb keypoints and joint angles over time with the events,
//! walking bouts and rejected cycles, and takes corrections (swaps, events, excluded frames,
//! dragged keypoints). Every change is recomputed from the keypoints by gait-kin, exactly as
//! `gait kin --corrections` would, and saved atomically to corrections.toml: the only file the
//! server writes. No model runs.

mod analysis;
mod checklist;
mod error;
mod frames;
mod page;
mod run_view;
mod server;
mod source;

use std::io::Write as _;
use std::sync::Arc;

pub use analysis::{AnalysisView, recompute};
pub use error::ReviewError;
pub use source::ReviewSource;

/// How to serve.
#[derive(Debug, Clone, Default)]
pub struct ServeOptions {
    /// Port on 127.0.0.1 (taken or an error); None: `link_port`, else a free one.
    pub port: Option<u16>,
    /// The port the run's report links to (`gait_checklist::review_port`): tried first when
    /// no port is given; a free one if it is taken, with a warning.
    pub link_port: Option<u16>,
    /// Launch the system's browser on the page.
    pub open: bool,
    /// The frame the page opens at (a checklist's frame), else the first walking bout's.
    pub frame: Option<usize>,
}

fn token() -> Result<String, ReviewError> {
    let mut bytes = [0u8; 16];
    getrandom::fill(&mut bytes).map_err(|e| ReviewError::Io {
        context: "drawing the session token".into(),
        source: std::io::Error::other(e.to_string()),
    })?;
    Ok(bytes.iter().map(|b| format!("{b:02x}")).collect())
}

/// Checks the saved corrections, starts decoding the frames, prints the page's URL on stdout
/// and serves until interrupted (Ctrl-C).
pub fn serve(src: ReviewSource, opts: &ServeOptions) -> Result<(), ReviewError> {
    let current = analysis::recompute(&src, &src.corrections)?;
    let frames = match (&src.video, src.seq.frames.first(), src.seq.frames.last()) {
        (Ok(v), Some(&a), Some(&b)) => Some(frames::FrameStore::start(v.clone(), a..=b)),
        _ => None,
    };
    let regenerated = src.regenerated.clone().map(frames::RegeneratedStore::new);
    let run_json = run_view::json(
        &src,
        regenerated.as_ref().map_or(Vec::new(), |r| r.frames()),
    );
    let app = Arc::new(server::App {
        token: token()?,
        src: Arc::new(src),
        frames,
        regenerated,
        run_json,
        current: tokio::sync::Mutex::new(current),
    });
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .map_err(|e| ReviewError::Io {
            context: "starting the server".into(),
            source: e,
        })?;
    runtime.block_on(async {
        let listener = listen(opts).await?;
        let addr = listener.local_addr().map_err(|e| ReviewError::Io {
            context: "reading the server's address".into(),
            source: e,
        })?;
        let at = opts.frame.map_or(String::new(), |f| format!("&frame={f}"));
        let url = format!("http://{addr}/?token={}{at}", app.token);
        println!("{url}");
        let _ = std::io::stdout().flush();
        eprintln!(
            "review of {}: open the URL above; Ctrl-C stops",
            app.src.title
        );
        if opts.open {
            open_browser(&url);
        }
        axum::serve(listener, server::router(app))
            .with_graceful_shutdown(async {
                let _ = tokio::signal::ctrl_c().await;
            })
            .await
            .map_err(|e| ReviewError::Io {
                context: "serving the review".into(),
                source: e,
            })
    })
}

/// The listener on the port asked for, else the run's own port, else a free one.
async fn listen(opts: &ServeOptions) -> Result<tokio::net::TcpListener, ReviewError> {
    if let (None, Some(own)) = (opts.port, opts.link_port) {
        match server::bind(own).await {
            Ok(l) => return Ok(l),
            Err(e) => eprintln!(
                "warning: this run's own port 127.0.0.1:{own} is taken ({e}): serving on a free port, so the frame links of its report will not reach this review"
            ),
        }
    }
    let port = opts.port.unwrap_or(0);
    server::bind(port).await.map_err(|e| ReviewError::Io {
        context: format!("listening on 127.0.0.1:{port} (is the port in use? try another --port)"),
        source: e,
    })
}

/// The desktop's opener (`$BROWSER`, else xdg-open / open); a failure is only a warning, since
/// the URL is printed anyway.
fn open_browser(url: &str) {
    let opener = std::env::var("BROWSER")
        .ok()
        .filter(|b| !b.is_empty())
        .unwrap_or_else(|| {
            if cfg!(target_os = "macos") {
                "open"
            } else {
                "xdg-open"
            }
            .to_string()
        });
    if let Err(e) = std::process::Command::new(&opener)
        .arg(url)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
    {
        eprintln!("warning: could not launch `{opener}` ({e}): open the URL by hand");
    }
}
