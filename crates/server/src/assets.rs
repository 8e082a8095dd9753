//! The page itself: the bundle `tools/web/build.sh` writes into `crates/server/assets/`,
//! compiled into the binary, so `cargo run` serves it with no node and no file read at run time.
//! Only these files are ever served; any other path is 404, so no path can reach the disk.

use axum::http::{StatusCode, Uri, header};
use axum::response::{IntoResponse, Response};

/// (URL path, content type, bytes) of every asset.
pub const ASSETS: [(&str, &str, &[u8]); 3] = [
    (
        "/",
        "text/html; charset=utf-8",
        include_bytes!("../assets/index.html"),
    ),
    (
        "/app.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../assets/app.js"),
    ),
    (
        "/app.css",
        "text/css; charset=utf-8",
        include_bytes!("../assets/app.css"),
    ),
];

/// The asset at `uri`'s path (`/index.html` is `/`), or 404.
pub async fn serve(uri: Uri) -> Response {
    let path = match uri.path() {
        "/index.html" => "/",
        p => p,
    };
    match ASSETS.iter().find(|(p, _, _)| *p == path) {
        Some((_, kind, bytes)) => (
            [
                (header::CONTENT_TYPE, *kind),
                (header::CACHE_CONTROL, "no-cache"),
                (header::X_CONTENT_TYPE_OPTIONS, "nosniff"),
            ],
            *bytes,
        )
            .into_response(),
        None => (StatusCode::NOT_FOUND, "not found").into_response(),
    }
}
