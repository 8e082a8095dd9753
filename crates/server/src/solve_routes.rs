//! The routes that run the pipeline on the design as it is now, through the library's own
//! stages (`flatcut::run::flatten_project`, then `finish_project`), so every file served is the
//! one `flatcut run` writes for the same design: the flattening with its heat maps and figures,
//! the pattern, the nest and the jobs. Long solves tell their progress on `/api/events` and can
//! be cancelled.

use crate::app::Unread;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use axum::extract::{Query, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use flatcut::design::Design;
use flatcut::flatten::{FlattenError, FlattenHooks};
use flatcut::pipeline::PipelineError;
use flatcut::project::Project;
use flatcut::run::{Event, RunError};
use serde::Deserialize;
use serde_json::json;

use crate::app::{App, Finished, Flattened, lock};
use crate::error::ApiError;
use crate::events::Events;
use crate::task;

type AppState = State<Arc<App>>;

/// Whether a run stopped because it was cancelled.
fn cancelled(e: &RunError) -> bool {
    matches!(
        e,
        RunError::Pipeline(PipelineError::Flatten {
            source: FlattenError::Cancelled { .. },
            ..
        })
    ) || e.to_string().contains("cancelled")
}

fn run_error(e: RunError) -> ApiError {
    if cancelled(&e) {
        ApiError::cancelled()
    } else {
        ApiError::bad(e.to_string())
    }
}

/// An observer publishing a run's events.
fn observer(events: Events) -> impl FnMut(&Event<'_>) {
    move |e: &Event<'_>| {
        match *e {
        Event::Started { stage, detail } => events.publish(
            "stage",
            json!({ "stage": stage.name(), "state": "started", "detail": detail }),
        ),
        Event::Progress {
            stage,
            done,
            total,
            what,
        } => events.publish(
            "progress",
            json!({ "stage": stage.name(), "done": done, "total": total, "what": what }),
        ),
        Event::Warning { stage, message } => events.publish(
            "warning",
            json!({ "stage": stage.name(), "message": message }),
        ),
        Event::Finished { stage, elapsed } => events.publish(
            "stage",
            json!({ "stage": stage.name(), "state": "finished", "elapsed_s": elapsed.as_secs_f64() }),
        ),
    }
    }
}

/// Which sizes of a graded design a flattening covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sizes {
    /// The base size alone: what the page shows live after every edit (a graded design's
    /// other sizes are the base scaled, so its lines, regions and strains are the base's).
    Base,
    /// Every size, as `flatcut run` flattens them: the pattern, nest and jobs, and on demand.
    All,
}

/// The design and project to flatten for `sizes`: for the base size alone, the grading keeps
/// only its base size and the project's `[order]` only that size (so its pieces are named and
/// reported as in the graded run, `<piece> <base>`). `None`: the design is not graded, so the
/// base is every size.
fn base_only(design: &Design, project: &Project) -> Option<(Design, Project)> {
    let g = design.grading.as_ref()?;
    if !g.sizes.iter().any(|z| z.name == g.base) {
        return None;
    }
    let mut d = design.clone();
    let mut p = project.clone();
    if let Some(g) = d.grading.as_mut() {
        let base = g.base.clone();
        g.sizes.retain(|z| z.name == base);
        if let Some(order) = p.order.as_mut() {
            order.retain(|size, _| *size == base);
        }
    }
    Some((d, p))
}

/// Starts (or joins) the flattening of the design as it is now, in `sizes`, and waits for it.
/// An ungraded design has one flattening for both.
pub async fn flattened(app: &Arc<App>, sizes: Sizes) -> Result<Arc<Flattened>, ApiError> {
    let (design, project, revision) = {
        let b = app.bench();
        (b.design().clone(), b.opened.project.clone(), b.revision())
    };
    let all_sizes: Vec<String> = design
        .grading
        .as_ref()
        .map(|g| g.sizes.iter().map(|z| z.name.clone()).collect())
        .unwrap_or_default();
    let (design, project, slot) = match (sizes, base_only(&design, &project)) {
        (Sizes::Base, Some((d, p))) => (d, p, &app.flatten),
        (Sizes::All, Some(_)) => (design, project, &app.graded),
        (_, None) => (design, project, &app.flatten),
    };
    let events = app.events.clone();
    let opts = app.run.clone();
    let rx = lock(slot).get_or_start(revision, move |cancel: Arc<AtomicBool>| {
        let t0 = Instant::now();
        let progress_events = events.clone();
        let hooks = FlattenHooks::default()
            .with_cancel(cancel)
            .with_progress(Arc::new(move |p: &flatcut::flatten::FlattenProgress| {
                progress_events.publish(
                    "solver",
                    json!({
                        "stage": p.stage,
                        "iteration": p.iteration,
                        "max_iterations": p.max_iterations,
                        "energy": p.energy,
                        "elapsed_s": p.elapsed.as_secs_f64(),
                    }),
                )
            }));
        let opts = opts.with_flatten_hooks(hooks);
        let mut obs = observer(events.clone());
        let flats = flatcut::run::flatten_project(&project, Some(&design), &opts, &mut obs)
            .map_err(run_error)?;
        let mating = flatcut::flat::mating_seams(&flats);
        let limits = (
            project.material.max_stretch_pct,
            project.material.max_compress_pct,
        );
        let elapsed = t0.elapsed().as_secs_f64();
        let mut view =
            crate::views::flatten_view(&design, &flats, &mating, limits, revision, elapsed);
        view["sizes"] = json!(all_sizes);
        events.publish(
            "flattened",
            json!({
                "revision": revision,
                "pieces": flats.len(),
                "sizes": view["sizes"],
                "elapsed_s": elapsed,
            }),
        );
        Ok(Flattened {
            revision,
            flats,
            view: view.to_string(),
        })
    });
    task::wait(rx).await
}

/// Starts flattening the design as it is now without waiting for it: every edit does, so the
/// page's `POST /api/flatten` that follows finds the solve under way (or done).
pub fn prefetch(app: &Arc<App>) {
    let app = app.clone();
    tokio::spawn(async move {
        // A failure is the page's to hear when it asks.
        let _ = flattened(&app, Sizes::Base).await;
    });
}

/// The query string of `POST /api/flatten`.
#[derive(Deserialize)]
pub struct FlattenQuery {
    /// `all`: every size of a graded design (default: the base size, the live preview).
    sizes: Option<String>,
}

/// `POST /api/flatten[?sizes=all]`: every piece flattened within the project's limits, with its
/// figures, heat map and meshes, and the mating seams (see API.md for the keys); of a graded
/// design the base size, or with `sizes=all` every size.
pub async fn flatten(
    State(app): AppState,
    Query(q): Query<FlattenQuery>,
    _body: Unread,
) -> Result<Response, ApiError> {
    let sizes = match q.sizes.as_deref() {
        None | Some("base") => Sizes::Base,
        Some("all") => Sizes::All,
        Some(other) => {
            return Err(ApiError::bad(format!(
                "sizes={other}: `base` (the default) or `all`"
            )));
        }
    };
    let f = flattened(&app, sizes).await?;
    Ok((
        [
            (header::CONTENT_TYPE, "application/json".to_string()),
            (
                axum::http::HeaderName::from_static("x-flatcut-revision"),
                f.revision.to_string(),
            ),
        ],
        f.view.clone(),
    )
        .into_response())
}

/// `POST /api/flatten/cancel`: stops the running solve (and nest).
pub async fn cancel(State(app): AppState, _body: Unread) -> axum::Json<serde_json::Value> {
    let a = lock(&app.flatten).cancel();
    let g = lock(&app.graded).cancel();
    let b = lock(&app.finish).cancel();
    axum::Json(json!({ "cancelled": a || g || b }))
}

/// Every stage after the flattening for the design as it is now.
pub(crate) async fn finished(app: &Arc<App>) -> Result<Arc<Finished>, ApiError> {
    let flat = flattened(app, Sizes::All).await?;
    let project = app.bench().opened.project.clone();
    let events = app.events.clone();
    let opts = app.run.clone();
    let flats = flat.flats.clone();
    let revision = flat.revision;
    let rx = lock(&app.finish).get_or_start(revision, move |_cancel| {
        let mut obs = observer(events);
        let outputs =
            flatcut::run::finish_project(&project, flats, &opts, &mut obs).map_err(run_error)?;
        Ok(Finished { revision, outputs })
    });
    task::wait(rx).await
}

/// One output file of the run, as an attachment named as `flatcut run` names it.
async fn file(app: &Arc<App>, name: &str, kind: &'static str) -> Result<Response, ApiError> {
    let f = finished(app).await?;
    let out = f
        .outputs
        .files
        .iter()
        .find(|f| f.name == name)
        .ok_or_else(|| ApiError {
            status: axum::http::StatusCode::NOT_FOUND,
            message: format!("the run wrote no {name}"),
        })?;
    Ok(bytes(name, kind, out.bytes.clone()))
}

fn bytes(name: &str, kind: &'static str, body: Vec<u8>) -> Response {
    (
        [
            (header::CONTENT_TYPE, kind.to_string()),
            (
                header::CONTENT_DISPOSITION,
                format!("inline; filename=\"{name}\""),
            ),
        ],
        body,
    )
        .into_response()
}

/// The query string of the routes that serve one sheet's layout or job (`sheet`, `profile`).
#[derive(Deserialize)]
pub struct SheetQuery {
    /// 1-based sheet number (default 1).
    sheet: Option<usize>,
    /// `flatcut hpgl`'s profile for `job.plt` (default: the project's, when it has `[hpgl]`,
    /// else `vinyl`).
    profile: Option<String>,
}

fn sheet(q: &SheetQuery) -> Result<usize, ApiError> {
    match q.sheet {
        Some(0) => Err(ApiError::bad("sheets are numbered from 1")),
        Some(n) => Ok(n),
        None => Ok(1),
    }
}

/// `GET /api/summary.json`: the run's `summary.json` (utilisation, sheets, cut length, time).
pub async fn summary(State(app): AppState) -> Result<Response, ApiError> {
    file(&app, "summary.json", "application/json").await
}

/// `GET /api/pattern.svg`: `pattern.svg` of `flatcut run`.
pub async fn pattern_svg(State(app): AppState) -> Result<Response, ApiError> {
    file(&app, "pattern.svg", "image/svg+xml").await
}

/// `GET /api/pattern.dxf`: `pattern.dxf` of `flatcut run`.
pub async fn pattern_dxf(State(app): AppState) -> Result<Response, ApiError> {
    file(&app, "pattern.dxf", "application/dxf").await
}

/// `GET /api/layout.svg?sheet=N`: `layout-N.svg` of `flatcut run`.
pub async fn layout_svg(
    State(app): AppState,
    Query(q): Query<SheetQuery>,
) -> Result<Response, ApiError> {
    file(&app, &format!("layout-{}.svg", sheet(&q)?), "image/svg+xml").await
}

/// `GET /api/layout.dxf?sheet=N`: `layout-N.dxf` of `flatcut run`.
pub async fn layout_dxf(
    State(app): AppState,
    Query(q): Query<SheetQuery>,
) -> Result<Response, ApiError> {
    file(
        &app,
        &format!("layout-{}.dxf", sheet(&q)?),
        "application/dxf",
    )
    .await
}

/// `GET /api/job.gcode?sheet=N`: `job-N.gcode` of `flatcut run`.
pub async fn job_gcode(
    State(app): AppState,
    Query(q): Query<SheetQuery>,
) -> Result<Response, ApiError> {
    file(
        &app,
        &format!("job-{}.gcode", sheet(&q)?),
        "text/plain; charset=utf-8",
    )
    .await
}

/// `GET /api/report.html`: the run's distortion report.
pub async fn report_html(State(app): AppState) -> Result<Response, ApiError> {
    file(&app, "report.html", "text/html; charset=utf-8").await
}

/// `GET /api/job.plt?sheet=N&profile=P`: the sheet as HP-GL/1, as `flatcut hpgl layout-N.svg
/// --profile P` writes it.
pub async fn job_hpgl(
    State(app): AppState,
    Query(q): Query<SheetQuery>,
) -> Result<Response, ApiError> {
    let n = sheet(&q)?;
    let profile = match &q.profile {
        Some(p) => {
            Some(flatcut::gcode::Profile::resolve(p).map_err(|e| ApiError::bad(e.to_string()))?)
        }
        None => None,
    };
    let (name, text, _) = sheet_hpgl(&app, n, profile.as_ref()).await?;
    Ok(bytes(&name, "application/vnd.hp-hpgl", text.into_bytes()))
}

/// Sheet `n` as HP-GL/1 for `profile` (`None`: the project's when it has `[hpgl]`, else
/// `vinyl`), as `flatcut hpgl layout-N.svg --profile P` writes it: its file name (`job-N.plt`),
/// its text and the revision it was made for. `GET /api/job.plt` serves it, and a plotter's
/// job streams it.
pub async fn sheet_hpgl(
    app: &Arc<App>,
    n: usize,
    profile: Option<&flatcut::gcode::Profile>,
) -> Result<(String, String, u64), ApiError> {
    if n == 0 {
        return Err(ApiError::bad("sheets are numbered from 1"));
    }
    let f = finished(app).await?;
    let profile = match profile {
        Some(p) => p.clone(),
        None => crate::plotters::default_profile(&f.outputs.profile).map_err(ApiError::internal)?,
    };
    let svg = f
        .outputs
        .files
        .iter()
        .find(|x| x.name == format!("layout-{n}.svg"))
        .ok_or_else(|| ApiError {
            status: axum::http::StatusCode::NOT_FOUND,
            message: format!("the run has no sheet {n}"),
        })?;
    let name = format!("layout-{n}.svg");
    let (text, _warnings) =
        flatcut::plot::hpgl_of_svg(&String::from_utf8_lossy(&svg.bytes), &name, &profile)
            .map_err(|e| ApiError::bad(e.to_string()))?;
    Ok((format!("job-{n}.plt"), text, f.revision))
}
