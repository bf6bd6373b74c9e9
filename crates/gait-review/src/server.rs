//! The local HTTP server: one page, its data, the frames, and the one write (corrections.toml).

use std::net::{Ipv4Addr, SocketAddr};
use std::sync::Arc;

use axum::Router;
use axum::body::Bytes;
use axum::extract::{Path as UrlPath, Query, Request, State};
use axum::http::{StatusCode, header};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use gait_kin::Corrections;
use serde::Deserialize;
use tokio::sync::Mutex;

use crate::analysis::{self, AnalysisView};
use crate::frames::{FrameStore, RegeneratedStore};
use crate::page;
use crate::source::ReviewSource;

/// What every request handler shares.
pub(crate) struct App {
    pub token: String,
    pub src: Arc<ReviewSource>,
    pub frames: Option<FrameStore>,
    pub regenerated: Option<RegeneratedStore>,
    /// The page's data that never changes (keypoints, names, video), as JSON.
    pub run_json: String,
    /// The analysis with the corrections saved last; the lock also orders the saves.
    pub current: Mutex<AnalysisView>,
}

type Shared = Arc<App>;

/// The routes: the page, and its data behind the token check.
pub(crate) fn router(app: Shared) -> Router {
    // The page itself holds no data: a report's frame link opens it without the token, which
    // the page then takes from the browser's storage for this address.
    let open = Router::new().route("/", get(index));
    Router::new()
        .route("/api/run", get(run_data))
        .route("/api/analysis", get(current_analysis))
        .route("/api/corrections", post(save_corrections))
        .route("/api/frame/{n}", get(frame))
        .layer(middleware::from_fn_with_state(app.clone(), require_token))
        .with_state(app)
        .merge(open)
}

/// Binds the loopback interface only: `port` 0 lets the system pick a free port.
pub(crate) async fn bind(port: u16) -> std::io::Result<tokio::net::TcpListener> {
    tokio::net::TcpListener::bind(SocketAddr::from((Ipv4Addr::LOCALHOST, port))).await
}

/// Compares in time independent of where the strings differ.
fn same(a: &str, b: &str) -> bool {
    a.len() == b.len()
        && a.bytes()
            .zip(b.bytes())
            .fold(0u8, |acc, (x, y)| acc | (x ^ y))
            == 0
}

async fn require_token(State(app): State<Shared>, req: Request, next: Next) -> Response {
    let given = req
        .uri()
        .query()
        .unwrap_or("")
        .split('&')
        .find_map(|kv| kv.strip_prefix("token="));
    match given {
        Some(t) if same(t, &app.token) => next.run(req).await,
        _ => (
            StatusCode::FORBIDDEN,
            "this review session needs its token: open the URL `gait review` printed",
        )
            .into_response(),
    }
}

fn json(body: String) -> Response {
    ([(header::CONTENT_TYPE, "application/json")], body).into_response()
}

fn error(status: StatusCode, message: &str) -> Response {
    (status, axum::Json(serde_json::json!({ "error": message }))).into_response()
}

async fn index() -> Response {
    (
        [
            (header::CONTENT_TYPE, "text/html; charset=utf-8"),
            // Everything the page needs is in it: nothing may be loaded from elsewhere.
            (
                header::CONTENT_SECURITY_POLICY,
                "default-src 'self'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; img-src 'self' blob: data:; connect-src 'self'",
            ),
        ],
        page::html(),
    )
        .into_response()
}

async fn run_data(State(app): State<Shared>) -> Response {
    json(app.run_json.clone())
}

async fn current_analysis(State(app): State<Shared>) -> Response {
    let view = app.current.lock().await;
    axum::Json(&*view).into_response()
}

/// Recomputes with the posted corrections (JSON of the corrections.toml tables); saves them
/// only when the analysis accepts them, so a rejected edit leaves the file as it was.
async fn save_corrections(State(app): State<Shared>, body: Bytes) -> Response {
    let c: Corrections = match serde_json::from_slice(&body) {
        Ok(c) => c,
        Err(e) => {
            let msg = format!("{}: {e}", app.src.corrections_path.display());
            return error(StatusCode::BAD_REQUEST, &msg);
        }
    };
    let mut current = app.current.lock().await;
    let src = app.src.clone();
    let work = tokio::task::spawn_blocking(move || {
        let view = analysis::recompute(&src, &c)?;
        // Not while a run writes into the folder (it reads corrections.toml at its end).
        let folder = src
            .corrections_path
            .parent()
            .unwrap_or(std::path::Path::new("."));
        let _lock =
            gait_pipeline::FolderLock::acquire(folder, "gait review save").map_err(|e| {
                gait_kin::KinError::Io {
                    context: format!("saving {}", src.corrections_path.display()),
                    source: std::io::Error::other(e.to_string()),
                }
            })?;
        gait_pipeline::atomic::write(&src.corrections_path, &analysis::toml_bytes(&c)).map_err(
            |e| gait_kin::KinError::Io {
                context: format!("saving {}", src.corrections_path.display()),
                source: e,
            },
        )?;
        Ok::<_, gait_kin::KinError>(view)
    })
    .await;
    match work {
        Ok(Ok(view)) => {
            *current = view;
            axum::Json(&*current).into_response()
        }
        Ok(Err(e)) => {
            let msg = e
                .to_string()
                .split_whitespace()
                .collect::<Vec<_>>()
                .join(" ");
            error(StatusCode::BAD_REQUEST, &msg)
        }
        Err(e) => error(StatusCode::INTERNAL_SERVER_ERROR, &e.to_string()),
    }
}

#[derive(Deserialize)]
struct FrameQuery {
    #[serde(default)]
    kind: Option<String>,
}

async fn frame(
    State(app): State<Shared>,
    UrlPath(n): UrlPath<usize>,
    Query(q): Query<FrameQuery>,
) -> Response {
    let image = |mime: &'static str, bytes: Arc<Vec<u8>>| {
        (
            [
                (header::CONTENT_TYPE, mime),
                (header::CACHE_CONTROL, "private, max-age=3600"),
            ],
            bytes.as_ref().clone(),
        )
            .into_response()
    };
    match q.kind.as_deref().unwrap_or("original") {
        "original" => {
            let Some(store) = app.frames.clone() else {
                let why = app.src.video.as_ref().err().cloned().unwrap_or_default();
                return error(StatusCode::NOT_FOUND, &why);
            };
            match tokio::task::spawn_blocking(move || store.get(n)).await {
                Ok(Ok(bytes)) => image("image/jpeg", bytes),
                Ok(Err(e)) => error(StatusCode::NOT_FOUND, &e.0),
                Err(e) => error(StatusCode::INTERNAL_SERVER_ERROR, &e.to_string()),
            }
        }
        "regenerated" => match app.regenerated.as_ref().and_then(|r| r.get(n)) {
            Some(bytes) => image("image/png", bytes),
            None => error(
                StatusCode::NOT_FOUND,
                &format!("no regenerated image of frame {n}"),
            ),
        },
        other => error(
            StatusCode::BAD_REQUEST,
            &format!("unknown frame kind `{other}` (original | regenerated)"),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::same;

    #[test]
    fn tokens_match_only_whole() {
        assert!(same("5f60a7", "5f60a7"));
        assert!(!same("5f60a7", "5f60a8"));
        assert!(!same("5f60a7", "5f60a"));
        assert!(!same("", "5f60a7"));
    }
}
