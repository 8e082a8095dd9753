//! How an error becomes a response: [`ApiError`], answered as `{"error": "…"}` with the status
//! that says whose fault it is (API.md lists them).

use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use serde_json::json;

/// An error answered as `{"error": message}`.
#[derive(Clone, Debug)]
pub struct ApiError {
    /// The HTTP status: 4xx when the request is at fault, 5xx when the server is.
    pub status: StatusCode,
    /// The message sent as `error`, saying what is wrong.
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

    /// True for the error [`ApiError::cancelled`] makes.
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
