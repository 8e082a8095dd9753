//! The application: its shared state, the routes of the JSON API (documented in
//! `crates/server/API.md`), and how an error becomes a response (`{"error": "…"}` with the
//! status that says whose fault it is).

use std::sync::{Arc, Mutex, MutexGuard};

use axum::Router;
use axum::extract::DefaultBodyLimit;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use flatcut::flat::Flat;
use flatcut::run::{ProjectOutputs, RunOptions};
use serde_json::json;

use crate::bench::Bench;
use crate::devices::Devices;
use crate::events::Events;
use crate::guard::Guard;
use crate::task::Slot;

/// Largest request body (32 MiB); a larger one gets 413.
pub const BODY_LIMIT: usize = 32 * 1024 * 1024;

/// A design flattened: its pieces and the page's view of them (serialised once).
pub struct Flattened {
    pub revision: u64,
    pub flats: Vec<Flat>,
    pub view: String,
}

/// Everything after the flattening, for one revision: the files `flatcut run` writes.
pub struct Finished {
    /// The design revision they were made for.
    pub revision: u64,
    pub outputs: ProjectOutputs,
}

/// The server's state, shared by every request.
pub struct App {
    bench: Mutex<Bench>,
    pub events: Events,
    pub run: RunOptions,
    /// The live flattening: a graded design's base size (every piece of an ungraded one).
    pub flatten: Mutex<Slot<Flattened>>,
    /// Every size of a graded design: for the pattern, nest and jobs, and on demand.
    pub graded: Mutex<Slot<Flattened>>,
    pub finish: Mutex<Slot<Finished>>,
    /// The last regions view: (revision, JSON text).
    pub regions: Mutex<Option<(u64, Arc<String>)>>,
    /// The device panel: the device open and the jobs streamed to it.
    pub devices: Devices,
}

impl App {
    pub fn new(bench: Bench) -> App {
        let events = Events::default();
        App {
            bench: Mutex::new(bench),
            devices: Devices::new(events.clone()),
            events,
            run: RunOptions::default(),
            flatten: Mutex::new(Slot::default()),
            graded: Mutex::new(Slot::default()),
            finish: Mutex::new(Slot::default()),
            regions: Mutex::new(None),
        }
    }

    /// The design state (a poisoned lock is taken over: every change of the bench is made
    /// whole or not at all).
    pub fn bench(&self) -> MutexGuard<'_, Bench> {
        self.bench.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Tells every page the design changed.
    pub fn design_changed(&self, why: &str) {
        let b = self.bench();
        self.events.publish(
            "design",
            json!({
                "revision": b.revision(),
                "saved": b.saved(),
                "can_undo": b.can_undo(),
                "can_redo": b.can_redo(),
                "why": why,
            }),
        );
    }
}

/// Locks a mutex, taking over a poisoned one.
pub fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// An error answered as `{"error": message}`.
#[derive(Clone, Debug)]
pub struct ApiError {
    pub status: StatusCode,
    pub message: String,
}

impl ApiError {
    /// The request (or the design it carries) is wrong: 400.
    pub fn bad(message: impl Into<String>) -> Self {
        ApiError {
            status: StatusCode::BAD_REQUEST,
            message: message.into(),
        }
    }

    /// The server could not do what it should have: 500.
    pub fn internal(message: impl Into<String>) -> Self {
        ApiError {
            status: StatusCode::INTERNAL_SERVER_ERROR,
            message: message.into(),
        }
    }

    /// A computation was cancelled (by the page, or by a newer edit): 409.
    pub fn cancelled() -> Self {
        ApiError {
            status: StatusCode::CONFLICT,
            message: "cancelled".into(),
        }
    }

    pub fn is_cancelled(&self) -> bool {
        self.status == StatusCode::CONFLICT && self.message == "cancelled"
    }

    /// The design changed while the request was worked on: 409, ask again.
    pub fn stale() -> Self {
        ApiError {
            status: StatusCode::CONFLICT,
            message: "the design changed meanwhile; send the request again".into(),
        }
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        (self.status, axum::Json(json!({ "error": self.message }))).into_response()
    }
}

/// The body of a request whose route takes none (`POST /api/flatten` with `{}`), read and
/// dropped: a connection closed with request bytes unread is reset by the kernel, and the client
/// loses the answer it was reading.
pub type Unread = axum::body::Bytes;

/// The whole application: API routes, assets, the body limit and the access guard.
pub fn router(app: Arc<App>, guard: Guard) -> Router {
    use crate::{design_routes as d, solve_routes as s};
    let api = Router::new()
        .route("/api/health", get(d::health))
        .route("/api/design", get(d::get_design).put(d::put_design))
        .route("/api/design/undo", post(d::undo))
        .route("/api/design/redo", post(d::redo))
        .route("/api/design/save", post(d::save))
        .route("/api/lines", post(d::add_line))
        .route("/api/regions", get(d::regions))
        .route("/api/regions/name", post(d::name_region))
        .route("/api/flatten", post(s::flatten))
        .route("/api/flatten/cancel", post(s::cancel))
        .route("/api/summary.json", get(s::summary))
        .route("/api/pattern.svg", get(s::pattern_svg))
        .route("/api/pattern.dxf", get(s::pattern_dxf))
        .route("/api/layout.svg", get(s::layout_svg))
        .route("/api/layout.dxf", get(s::layout_dxf))
        .route("/api/job.gcode", get(s::job_gcode))
        .route("/api/job.plt", get(s::job_hpgl))
        .route("/api/report.html", get(s::report_html))
        .route("/api/events", get(d::events))
        .merge(crate::device_routes::routes())
        .fallback(api_not_found)
        .with_state(app);
    api.layer(DefaultBodyLimit::max(BODY_LIMIT))
        .layer(axum::middleware::from_fn_with_state(
            guard,
            crate::guard::check,
        ))
}

async fn api_not_found(uri: axum::http::Uri) -> Response {
    if uri.path().starts_with("/api/") {
        ApiError {
            status: StatusCode::NOT_FOUND,
            message: format!("no route {} (see API.md)", uri.path()),
        }
        .into_response()
    } else {
        crate::assets::serve(uri).await
    }
}
