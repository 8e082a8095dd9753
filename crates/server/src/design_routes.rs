//! The routes that read and change the design: health, the design tree, undo/redo/save, style
//! lines, regions and their names, and the event stream.

use crate::app::Unread;
use std::path::PathBuf;
use std::sync::Arc;

use axum::Json;
use axum::extract::{Query, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use flatcut::design::Design;
use flatcut::geom::Tolerances;
use serde::Deserialize;
use serde_json::{Value, json};

use crate::app::{App, lock};
use crate::edit;
use crate::error::ApiError;

type AppState = State<Arc<App>>;

impl From<crate::bench::BenchError> for ApiError {
    fn from(e: crate::bench::BenchError) -> Self {
        match e {
            crate::bench::BenchError::Save { .. } => ApiError::internal(e.to_string()),
            other => ApiError::bad(other.to_string()),
        }
    }
}

impl From<edit::EditError> for ApiError {
    fn from(e: edit::EditError) -> Self {
        ApiError::bad(e.to_string())
    }
}

/// What the page needs to know about the design's state.
fn state_json(app: &App) -> Value {
    let b = app.bench();
    json!({
        "revision": b.revision(),
        "saved": b.saved(),
        "can_undo": b.can_undo(),
        "can_redo": b.can_redo(),
        "design_path": b.opened.design_path.display().to_string(),
    })
}

/// `GET /api/health`: alive, what is open, the design's revision.
pub async fn health(State(app): AppState) -> Json<Value> {
    let mut v = state_json(&app);
    let b = app.bench();
    v["status"] = json!("ok");
    v["version"] = json!(env!("CARGO_PKG_VERSION"));
    v["input"] = json!({
        "kind": b.opened.kind,
        "path": b.opened.input.display().to_string(),
        "project": b.opened.project.name,
        "profile": b.opened.project.machine.profile,
        "limit_stretch_pct": b.opened.project.material.max_stretch_pct,
        "limit_compress_pct": b.opened.project.material.max_compress_pct,
    });
    Json(v)
}

/// `GET /api/design`: the design as its JSON tree (the revision in `X-Flatcut-Revision`).
pub async fn get_design(State(app): AppState) -> Response {
    let b = app.bench();
    (
        [("x-flatcut-revision", b.revision().to_string())],
        Json(b.tree()),
    )
        .into_response()
}

/// The query string of `PUT /api/design`.
#[derive(Deserialize, Default)]
pub struct PutQuery {
    /// `name`: give every region no piece names a piece of its own, and drop pieces that name a
    /// region another piece names first (what the page asks after moving or removing points).
    regions: Option<String>,
}

/// `PUT /api/design`: replaces the design by the tree in the body; a design the loader refuses
/// is 400 with the loader's message, and nothing changes.
pub async fn put_design(
    State(app): AppState,
    Query(q): Query<PutQuery>,
    body: axum::body::Bytes,
) -> Result<Json<Value>, ApiError> {
    let tree: Value = serde_json::from_slice(&body)
        .map_err(|e| ApiError::bad(format!("request body:{}:{}: {e}", e.line(), e.column())))?;
    let reconcile = q.regions.as_deref() == Some("name");
    let (revision, added, removed) = change(&app, move |ctx| {
        let design = ctx.candidate(&tree)?;
        if !reconcile {
            return Ok((tree, Vec::new(), Vec::new()));
        }
        reconcile_all(&tree, &design, ctx)
    })
    .await?;
    let mut v = state_json(&app);
    v["revision"] = json!(revision);
    v["added"] = json!(added);
    v["removed"] = json!(removed);
    Ok(Json(v))
}

/// What an edit computed away from the lock needs: the tree and design it starts from, where
/// mesh files resolve, and the tessellation tolerance of the run.
pub struct EditCtx {
    /// The design document as it is before the edit.
    pub doc: crate::document::DesignDocument,
    /// The same design as its JSON tree, which edits transform.
    pub tree: Value,
    /// The same design as loaded.
    pub design: Design,
    /// The design file: relative mesh paths resolve from its directory.
    pub design_path: PathBuf,
    /// The run's tolerances (tessellation, weld; mm).
    pub tol: Tolerances,
}

impl EditCtx {
    /// The directory relative paths in the design resolve from (the design file's; empty for a
    /// bare file name, i.e. the current directory).
    pub fn base(&self) -> PathBuf {
        self.design_path
            .parent()
            .map(PathBuf::from)
            .unwrap_or_default()
    }

    /// The design a tree loads to, as the command line would load it from the file once saved
    /// (its errors locate lines and columns in that file).
    pub fn candidate(&self, tree: &Value) -> Result<Design, ApiError> {
        let mut doc = self.doc.clone();
        doc.apply(tree).map_err(|e| ApiError::bad(e.to_string()))?;
        Design::from_file_text(&doc.text(), &self.design_path)
            .map_err(|e| ApiError::bad(e.to_string()))
    }
}

/// Pieces kept in step with the regions of every part (see [`edit::reconcile`]).
fn reconcile_all(
    tree: &Value,
    design: &Design,
    ctx: &EditCtx,
) -> Result<(Value, Vec<String>, Vec<String>), ApiError> {
    let mut tree = tree.clone();
    let (mut added, mut removed) = (Vec::new(), Vec::new());
    for k in 0..design.parts.len() {
        let (t, a, r) = edit::reconcile(&tree, design, k, &ctx.base(), &ctx.tol)?;
        tree = t;
        added.extend(a);
        removed.extend(r);
    }
    Ok((tree, added, removed))
}

/// Runs an edit: `f` computes the new tree from a snapshot on a blocking thread (tessellating
/// takes time), then the tree replaces the design if nothing changed it meanwhile. Returns the
/// new revision and what `f` returned besides.
async fn change<A: Send + 'static, B: Send + 'static>(
    app: &Arc<App>,
    f: impl FnOnce(&EditCtx) -> Result<(Value, A, B), ApiError> + Send + 'static,
) -> Result<(u64, A, B), ApiError> {
    let (ctx, revision) = {
        let b = app.bench();
        (
            EditCtx {
                doc: b.document().clone(),
                tree: b.tree(),
                design: b.design().clone(),
                design_path: b.opened.design_path.clone(),
                tol: Tolerances::DEFAULT.with_chord_mm(app.run.chord_mm),
            },
            b.revision(),
        )
    };
    let (tree, a, b) = tokio::task::spawn_blocking(move || f(&ctx))
        .await
        .map_err(|e| ApiError::internal(e.to_string()))??;
    let new = {
        let mut bench = app.bench();
        if bench.revision() != revision {
            return Err(ApiError::stale());
        }
        bench.set_tree(&tree)?
    };
    if new != revision {
        app.design_changed("edit");
        crate::solve_routes::prefetch(app);
    }
    Ok((new, a, b))
}

/// `POST /api/design/undo`.
pub async fn undo(State(app): AppState, _body: Unread) -> Result<Json<Value>, ApiError> {
    app.bench().undo()?;
    app.design_changed("undo");
    crate::solve_routes::prefetch(&app);
    Ok(Json(state_json(&app)))
}

/// `POST /api/design/redo`.
pub async fn redo(State(app): AppState, _body: Unread) -> Result<Json<Value>, ApiError> {
    app.bench().redo()?;
    app.design_changed("redo");
    crate::solve_routes::prefetch(&app);
    Ok(Json(state_json(&app)))
}

/// `POST /api/design/save`: writes the design to its file (comments and untouched keys kept).
pub async fn save(State(app): AppState, _body: Unread) -> Result<Json<Value>, ApiError> {
    let path = app.bench().save()?.display().to_string();
    app.design_changed("save");
    let mut v = state_json(&app);
    v["path"] = json!(path);
    Ok(Json(v))
}

/// The body of `POST /api/lines`: a style line's part, name, points and notches (mm).
#[derive(Deserialize)]
pub struct LineRequest {
    /// The part's name (or index; may be left out when the design has one part).
    #[serde(default)]
    part: Value,
    /// The line's name (default `line <n>`).
    #[serde(default)]
    name: Option<String>,
    points: Value,
    #[serde(default)]
    notches: Option<Value>,
}

/// `POST /api/lines` `{part, name, points, notches}`: adds a style line. The design loader
/// traces it at once: a line that does not close on the boundary or another line, or leaves the
/// surface, is 400 with the loader's message. A region the line closes gets a piece of its own.
pub async fn add_line(
    State(app): AppState,
    Json(req): Json<LineRequest>,
) -> Result<Json<Value>, ApiError> {
    let (revision, (name, added), removed) = change(&app, move |ctx| {
        let part = edit::part_index(&ctx.design, &req.part)?;
        let pts = edit::points(&req.points, "points")?;
        let notches = match &req.notches {
            Some(n) => edit::points(n, "notches")?,
            None => Vec::new(),
        };
        let name = req
            .name
            .clone()
            .unwrap_or_else(|| edit::free_line_name(&ctx.design, part));
        let tree = edit::add_line(&ctx.tree, &ctx.design, part, &name, &pts, &notches)?;
        let design = ctx.candidate(&tree)?;
        let (tree, added, removed) = edit::reconcile(&tree, &design, part, &ctx.base(), &ctx.tol)?;
        Ok((tree, (name, added), removed))
    })
    .await?;
    let mut v = state_json(&app);
    v["revision"] = json!(revision);
    v["line"] = json!(name);
    v["added"] = json!(added);
    v["removed"] = json!(removed);
    Ok(Json(v))
}

/// The body of `POST /api/regions/name`: the part, a point `at` in the region (mm) and the
/// name to give it.
#[derive(Deserialize)]
pub struct NameRequest {
    #[serde(default)]
    part: Value,
    at: Value,
    name: String,
}

/// `POST /api/regions/name` `{part, at, name}`: names the region around `at`.
pub async fn name_region(
    State(app): AppState,
    Json(req): Json<NameRequest>,
) -> Result<Json<Value>, ApiError> {
    let (revision, (), ()) = change(&app, move |ctx| {
        let part = edit::part_index(&ctx.design, &req.part)?;
        let at = edit::points(&Value::Array(vec![req.at.clone()]), "at")?[0];
        let tree = edit::name_region(
            &ctx.tree,
            &ctx.design,
            part,
            at,
            &req.name,
            &ctx.base(),
            &ctx.tol,
        )?;
        Ok((tree, (), ()))
    })
    .await?;
    let mut v = state_json(&app);
    v["revision"] = json!(revision);
    Ok(Json(v))
}

/// `GET /api/regions`: every part's surface split by its lines, with its regions' pieces (a part
/// whose lines cannot be traced comes with its bare surface and the loader's error).
pub async fn regions(State(app): AppState) -> Result<Response, ApiError> {
    let (design, path, revision) = {
        let b = app.bench();
        (
            b.design().clone(),
            b.opened.design_path.clone(),
            b.revision(),
        )
    };
    if let Some((rev, text)) = lock(&app.regions).clone()
        && rev == revision
    {
        return Ok(json_text(&text));
    }
    let tol = Tolerances::DEFAULT.with_chord_mm(app.run.chord_mm);
    let text = tokio::task::spawn_blocking(move || regions_json(&design, &path, &tol, revision))
        .await
        .map_err(|e| ApiError::internal(e.to_string()))?;
    let text = Arc::new(text);
    *lock(&app.regions) = Some((revision, text.clone()));
    Ok(json_text(&text))
}

fn json_text(text: &str) -> Response {
    (
        [(header::CONTENT_TYPE, "application/json")],
        text.to_string(),
    )
        .into_response()
}

fn regions_json(
    design: &Design,
    path: &std::path::Path,
    tol: &Tolerances,
    revision: u64,
) -> String {
    let base = path.parent().unwrap_or(std::path::Path::new("."));
    let parts: Vec<Value> = design
        .parts
        .iter()
        .enumerate()
        .map(|(k, p)| match p.regions(base, tol) {
            Ok(r) => crate::views::part_view(design, k, &r),
            Err(e) => {
                let mut bare = p.clone();
                bare.lines.clear();
                bare.edges.clear();
                let surface = bare.regions(base, tol).ok();
                crate::views::part_error_view(p, k, surface.as_ref(), &e.to_string())
            }
        })
        .collect();
    json!({ "revision": revision, "parts": parts }).to_string()
}

/// `GET /api/events`: server-sent events (see [`crate::events`]).
pub async fn events(State(app): AppState) -> impl IntoResponse {
    let rx = app.events.subscribe();
    crate::events::stream(state_json(&app), rx)
}
