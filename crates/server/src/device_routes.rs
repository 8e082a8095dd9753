//! The device panel's routes: `GET /api/devices`, `POST /api/jobs`, `GET /api/jobs/{id}`.
//! Not built yet: they answer 501 until the device-session library they stream through exists.

use std::sync::Arc;

use axum::Router;
use axum::http::StatusCode;
use axum::routing::{get, post};

use crate::app::{ApiError, App};

fn not_yet() -> ApiError {
    ApiError {
        status: StatusCode::NOT_IMPLEMENTED,
        message: "the device panel is not built yet".into(),
    }
}

async fn devices() -> ApiError {
    not_yet()
}

async fn jobs() -> ApiError {
    not_yet()
}

pub fn routes() -> Router<Arc<App>> {
    Router::new()
        .route("/api/devices", get(devices))
        .route("/api/jobs", post(jobs))
        .route("/api/jobs/{id}", get(jobs))
}
