//! The routes of the JSON API (documented in `crates/server/API.md`) mounted on the application's
//! state, with the body limit, the access guard, and the page's assets for every other path.

use std::sync::Arc;

use axum::Router;
use axum::extract::DefaultBodyLimit;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};

use crate::app::App;
use crate::error::ApiError;
use crate::guard::Guard;

/// Largest request body (32 MiB); a larger one gets 413.
pub const BODY_LIMIT: usize = 32 * 1024 * 1024;

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
