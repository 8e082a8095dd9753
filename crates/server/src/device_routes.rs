//! The device panel's routes: the devices (`GET /api/devices`; connect, close, status, unlock,
//! home, jog, frame), the jobs (`POST /api/jobs`, `GET /api/jobs/{id}`; hold, resume, stop, the
//! answer to a question) and what the embedded simulator executed. Each names its device by id
//! (`device` in the body, `?device=` in a `GET`'s query) or means the default one. Each blocking
//! call to a device runs on a blocking thread; the state lives in `devices`.

use std::sync::Arc;

use axum::Json;
use axum::Router;
use axum::extract::{Path, Query, State};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use flatcut::gcode::Profile;
use flatcut_device::DeviceError;
use flatcut_device::grbl::{Job, Jog};
use serde::Deserialize;
use serde_json::{Value, json};

use crate::app::App;
use crate::device_state::PanelError;
use crate::devices::{OpenRequest, PlotJob, StartJob, Steer, project_id};
use crate::error::ApiError;
use crate::plotters::{PLOTTER_SIM, PlotterChoice};

type AppState = State<Arc<App>>;

impl From<PanelError> for ApiError {
    fn from(e: PanelError) -> ApiError {
        let status = match &e {
            PanelError::Busy(_) | PanelError::NotOpen | PanelError::NotOpenId(_) => {
                StatusCode::CONFLICT
            }
            PanelError::Bad(_) => StatusCode::BAD_REQUEST,
            PanelError::NoJob(_) => StatusCode::NOT_FOUND,
            PanelError::Device(d) => match d {
                DeviceError::Busy { .. }
                | DeviceError::NoJob { .. }
                | DeviceError::NoQuestion(_)
                | DeviceError::Closed { .. }
                | DeviceError::NotGrbl { .. }
                | DeviceError::NotPlotter { .. }
                | DeviceError::Controller(_) => StatusCode::CONFLICT,
                DeviceError::PortMissing { .. }
                | DeviceError::Open { .. }
                | DeviceError::SimConfig(_)
                | DeviceError::NothingFrom { .. } => StatusCode::BAD_REQUEST,
                _ => StatusCode::INTERNAL_SERVER_ERROR,
            },
        };
        ApiError {
            status,
            message: chain(&e),
        }
    }
}

/// An error with its causes, as the command line prints them.
fn chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut src = e.source();
    while let Some(c) = src {
        let t = c.to_string();
        if !s.contains(&t) {
            s.push_str(": ");
            s.push_str(&t);
        }
        src = c.source();
    }
    s
}

/// Runs a blocking device call off the async threads.
async fn blocking<T: Send + 'static>(
    f: impl FnOnce() -> Result<T, ApiError> + Send + 'static,
) -> Result<T, ApiError> {
    tokio::task::spawn_blocking(f)
        .await
        .map_err(|e| ApiError::internal(format!("the device call stopped: {e}")))?
}

/// The project's machine profile (the simulator is set up as its machine).
fn profile(app: &App) -> Result<Profile, ApiError> {
    let spec = app.bench().opened.project.profile_spec();
    Profile::resolve(&spec).map_err(|e| ApiError::bad(e.to_string()))
}

/// A JSON body that may be empty (`POST` with no body means the defaults).
fn body<T: for<'de> Deserialize<'de> + Default>(bytes: &[u8]) -> Result<T, ApiError> {
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Ok(T::default());
    }
    serde_json::from_slice(bytes).map_err(|e| ApiError::bad(format!("the request body: {e}")))
}

/// `GET /api/devices`.
async fn devices(State(app): AppState) -> Result<Json<Value>, ApiError> {
    let project_device = app.bench().opened.project.device.clone();
    let a = app.clone();
    blocking(move || Ok(Json(a.devices.list(&project_device)))).await
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct ConnectBody {
    /// `simulator`, `simulator:<name>` or a serial port (default: the project's device).
    device: Option<String>,
    baud: Option<u32>,
    speed: Option<f64>,
    #[serde(default)]
    instant: bool,
    /// `grbl` (default; `hpgl` for `plotter-sim`) or `hpgl`: a serial port opened as an HP-GL
    /// plotter.
    protocol: Option<String>,
    /// An HP-GL plotter's profile (`vinyl`, `pen-hpgl`, a profile file with `[hpgl]`; default:
    /// the project's when it has `[hpgl]`, else `vinyl`).
    profile: Option<String>,
}

/// `POST /api/devices/connect`: opens the device and connects (banner, `$I`, `$$`); an HP-GL
/// plotter (`plotter-sim`, or `protocol: "hpgl"`) is opened with its profile's flow control.
async fn connect(State(app): AppState, raw: axum::body::Bytes) -> Result<Json<Value>, ApiError> {
    let b: ConnectBody = body(&raw)?;
    let project_device = app.bench().opened.project.device.clone();
    let device = b.device.unwrap_or_else(|| project_id(&project_device));
    let profile = profile(&app)?;
    let hpgl = match b.protocol.as_deref() {
        None => device == PLOTTER_SIM,
        Some("hpgl") => true,
        Some("grbl") if device != PLOTTER_SIM => false,
        Some(p) => {
            return Err(ApiError::bad(format!(
                "protocol {p:?} for {device}: `grbl` or `hpgl` (the embedded plotter is HP-GL)"
            )));
        }
    };
    if !hpgl && b.profile.is_some() {
        return Err(ApiError::bad(
            "a profile is for an HP-GL plotter: add `protocol: \"hpgl\"`",
        ));
    }
    let plotter = match hpgl {
        true => Some(
            PlotterChoice::new(b.profile.as_deref(), &profile, b.baud).map_err(ApiError::bad)?,
        ),
        false => None,
    };
    let req = OpenRequest {
        baud: b.baud.or(project_device.baud.filter(|_| !hpgl)),
        device,
        speed: b.speed,
        instant: b.instant,
        plotter,
    };
    let a = app.clone();
    blocking(move || Ok(Json(a.devices.connect(&req, &profile)?))).await
}

/// A body that names a device, or none (the default device).
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct DeviceBody {
    device: Option<String>,
}

/// `?device=ID` (none: the default device).
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct DeviceQuery {
    device: Option<String>,
}

/// `POST /api/devices/close` `{device}`: closes the device (a running job stops, tool off); for
/// a simulator, what it executed. With no device open (and none named), `{closed: null}`.
async fn close(State(app): AppState, raw: axum::body::Bytes) -> Result<Json<Value>, ApiError> {
    let b: DeviceBody = body(&raw)?;
    let a = app.clone();
    blocking(move || match a.devices.close(b.device.as_deref()) {
        Err(PanelError::NotOpen) => Ok(Json(json!({ "closed": null }))),
        r => Ok(Json(r?)),
    })
    .await
}

/// `GET /api/devices/status[?device=ID]`: the controller's state and position now.
async fn status(
    State(app): AppState,
    Query(q): Query<DeviceQuery>,
) -> Result<Json<Value>, ApiError> {
    let a = app.clone();
    blocking(move || {
        let s = a.devices.with_device(q.device.as_deref(), |d| d.status())?;
        Ok(Json(json!({
            "state": s.map(|s| s.state.name()),
            "work": s.and_then(|s| s.work),
            "machine": s.and_then(|s| s.machine),
        })))
    })
    .await
}

/// `GET /api/devices/sim[?device=ID]`: what an open embedded simulator executed so far.
async fn sim(State(app): AppState, Query(q): Query<DeviceQuery>) -> Result<Json<Value>, ApiError> {
    let a = app.clone();
    blocking(move || Ok(Json(a.devices.sim(q.device.as_deref())?))).await
}

/// A command between jobs to device `device` (the default one when `None`), answered
/// `{ok: true}`.
async fn command(
    app: Arc<App>,
    device: Option<String>,
    f: impl FnOnce(&flatcut_device::Device) -> Result<(), DeviceError> + Send + 'static,
) -> Result<Json<Value>, ApiError> {
    blocking(move || {
        app.devices.with_device(device.as_deref(), f)?;
        Ok(Json(json!({ "ok": true })))
    })
    .await
}

/// `POST /api/devices/unlock` `{device}` (`$X`).
async fn unlock(State(app): AppState, raw: axum::body::Bytes) -> Result<Json<Value>, ApiError> {
    let b: DeviceBody = body(&raw)?;
    command(app, b.device, |d| d.unlock()).await
}

/// `POST /api/devices/home` `{device}` (`$H`).
async fn home(State(app): AppState, raw: axum::body::Bytes) -> Result<Json<Value>, ApiError> {
    let b: DeviceBody = body(&raw)?;
    command(app, b.device, |d| d.home()).await
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct JogBody {
    device: Option<String>,
    /// mm per axis.
    by: [f64; 3],
    /// mm/min.
    feed: f64,
}

/// `POST /api/devices/jog` `{by: [x, y, z], feed}`.
async fn jog(State(app): AppState, raw: axum::body::Bytes) -> Result<Json<Value>, ApiError> {
    let b: JogBody = body(&raw)?;
    if !(b.feed.is_finite() && b.feed > 0.0) || b.by.iter().any(|v| !v.is_finite()) {
        return Err(ApiError::bad(
            "a jog needs finite distances `by` (mm) and a feed > 0 (mm/min)",
        ));
    }
    command(app, b.device, move |d| {
        d.jog(Jog {
            by: b.by,
            feed: b.feed,
        })
    })
    .await
}

/// `POST /api/devices/jog/cancel` `{device}`.
async fn jog_cancel(State(app): AppState, raw: axum::body::Bytes) -> Result<Json<Value>, ApiError> {
    let b: DeviceBody = body(&raw)?;
    command(app, b.device, |d| d.jog_cancel()).await
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct SheetBody {
    /// The device's id (none: the default device, else the project's).
    device: Option<String>,
    sheet: Option<usize>,
    /// Frame feed, mm/min.
    feed: Option<f64>,
    /// Continue the sheet's job from its journal.
    #[serde(default)]
    resume: bool,
    /// Clear an alarm lock (`$X`) first: only when the machine position is known to be right.
    #[serde(default)]
    unlock: bool,
    /// Continue the sheet's job from this line of its file (1-based), whatever its journal
    /// says ran: the operator's answer when a resume cannot tell (`flatcut send --resume-from`).
    resume_from: Option<usize>,
}

/// Default frame feed, mm/min.
const FRAME_FEED: f64 = 2000.0;

/// Sheet `n`'s job text (as `flatcut run` writes it) and the revision it was made for.
async fn sheet_job(app: &Arc<App>, n: usize) -> Result<(String, String, u64), ApiError> {
    if n == 0 {
        return Err(ApiError::bad("sheets are numbered from 1"));
    }
    let f = crate::solve_routes::finished(app).await?;
    let name = format!("job-{n}.gcode");
    let file = f
        .outputs
        .files
        .iter()
        .find(|x| x.name == name)
        .ok_or_else(|| ApiError {
            status: StatusCode::NOT_FOUND,
            message: format!("the run has no sheet {n}"),
        })?;
    let text = String::from_utf8(file.bytes.clone())
        .map_err(|_| ApiError::internal(format!("{name} is not text")))?;
    Ok((name, text, f.revision))
}

/// `POST /api/devices/frame` `{device, sheet, feed}`: traces the rectangle the sheet's job cuts in,
/// tool off.
async fn frame(State(app): AppState, raw: axum::body::Bytes) -> Result<Json<Value>, ApiError> {
    let b: SheetBody = body(&raw)?;
    let (name, text, _) = sheet_job(&app, b.sheet.unwrap_or(1)).await?;
    let job = Job::parse(&text).map_err(|e| ApiError::bad(format!("{name}: {e}")))?;
    let Some((lo, hi)) = job.extent else {
        return Err(ApiError::bad(format!(
            "{name} moves nowhere: nothing to frame"
        )));
    };
    let feed = b.feed.unwrap_or(FRAME_FEED);
    if !(feed.is_finite() && feed > 0.0) {
        return Err(ApiError::bad("the frame's feed must be > 0 mm/min"));
    }
    command(app, b.device, move |d| {
        d.frame([lo[0], lo[1]], [hi[0], hi[1]], feed)
    })
    .await
}

/// `POST /api/jobs` `{device, sheet, resume, unlock, resume_from}`: streams the sheet's
/// `job-N.gcode` to the device named, or the default device open, or the project's device (the
/// embedded simulator as its machine by default),
/// from its journal with `resume`, from line `resume_from` of the file with it; 201 with the
/// job, 409 while another job runs, 400 for a `resume_from` after which nothing is sent.
/// On an HP-GL plotter (the device named or the default one, or `plotter-sim`), the sheet's
/// HP-GL for the plotter's profile (`GET /api/job.plt`'s bytes) instead.
async fn start_job(State(app): AppState, raw: axum::body::Bytes) -> Result<Response, ApiError> {
    let b: SheetBody = body(&raw)?;
    let n = b.sheet.unwrap_or(1);
    let plotter = match app.devices.plotter_of(b.device.as_deref()) {
        Some(p) => Some(p),
        None if b.device.as_deref() == Some(PLOTTER_SIM) => {
            Some(PlotterChoice::new(None, &profile(&app)?, None).map_err(ApiError::bad)?)
        }
        None => None,
    };
    if let Some(plotter) = plotter {
        return start_plot(app, b, n, plotter).await;
    }
    let (name, gcode, revision) = sheet_job(&app, n).await?;
    let (project_device, dir) = {
        let bench = app.bench();
        let dir = bench
            .opened
            .design_path
            .parent()
            .map(std::path::Path::to_path_buf)
            .unwrap_or_default();
        (bench.opened.project.device.clone(), dir)
    };
    let profile = profile(&app)?;
    let job = StartJob {
        name,
        sheet: n,
        revision,
        gcode,
        dir,
        resume: b.resume,
        unlock: b.unlock,
        resume_from: b.resume_from,
        device: b.device,
    };
    let a = app.clone();
    let view = blocking(move || Ok(a.devices.start(job, &project_device, &profile)?)).await?;
    Ok((StatusCode::CREATED, Json(view)).into_response())
}

/// A job on an HP-GL plotter: the sheet's HP-GL for the plotter's profile, streamed.
async fn start_plot(
    app: Arc<App>,
    b: SheetBody,
    n: usize,
    plotter: PlotterChoice,
) -> Result<Response, ApiError> {
    if b.resume || b.resume_from.is_some() || b.unlock {
        return Err(ApiError::bad(
            "an HP-GL plotter has no journal to resume from and no alarm to unlock: start the \
             sheet anew",
        ));
    }
    let (name, hpgl, revision) =
        crate::solve_routes::sheet_hpgl(&app, n, Some(&plotter.profile)).await?;
    let job = PlotJob {
        name,
        sheet: n,
        revision,
        hpgl,
        device: b.device,
        plotter,
    };
    let profile = profile(&app)?;
    let a = app.clone();
    let view = blocking(move || Ok(a.devices.start_plot(job, &profile)?)).await?;
    Ok((StatusCode::CREATED, Json(view)).into_response())
}

/// `GET /api/jobs`: the jobs of this session.
async fn jobs(State(app): AppState) -> Json<Value> {
    Json(app.devices.jobs())
}

/// `GET /api/jobs/{id}`.
async fn job(State(app): AppState, Path(id): Path<u64>) -> Result<Json<Value>, ApiError> {
    Ok(Json(app.devices.job(id)?))
}

async fn steer(app: &App, id: u64, what: Steer) -> Result<Json<Value>, ApiError> {
    Ok(Json(app.devices.steer(id, what)?))
}

/// `POST /api/jobs/{id}/hold`: feed hold.
async fn hold(
    State(app): AppState,
    Path(id): Path<u64>,
    _b: axum::body::Bytes,
) -> Result<Json<Value>, ApiError> {
    steer(&app, id, Steer::Hold).await
}

/// `POST /api/jobs/{id}/resume`: cycle start after a hold or the job's own pause.
async fn resume(
    State(app): AppState,
    Path(id): Path<u64>,
    _b: axum::body::Bytes,
) -> Result<Json<Value>, ApiError> {
    steer(&app, id, Steer::Resume).await
}

/// `POST /api/jobs/{id}/stop`: feed hold, soft reset, tool off; the journal says what ran.
async fn stop(
    State(app): AppState,
    Path(id): Path<u64>,
    _b: axum::body::Bytes,
) -> Result<Json<Value>, ApiError> {
    steer(&app, id, Steer::Stop).await
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AnswerBody {
    question: u64,
    yes: bool,
}

/// `POST /api/jobs/{id}/answer` `{question, yes}`.
async fn answer(
    State(app): AppState,
    Path(id): Path<u64>,
    Json(b): Json<AnswerBody>,
) -> Result<Json<Value>, ApiError> {
    Ok(Json(app.devices.answer(id, b.question, b.yes)?))
}

/// The device panel's routes: `/api/devices…` (choose, connect, status, jog, frame, the
/// simulator) and `/api/jobs…` (start, list, hold, resume, stop, answer a question).
pub fn routes() -> Router<Arc<App>> {
    Router::new()
        .route("/api/devices", get(devices))
        .route("/api/devices/connect", post(connect))
        .route("/api/devices/close", post(close))
        .route("/api/devices/status", get(status))
        .route("/api/devices/sim", get(sim))
        .route("/api/devices/unlock", post(unlock))
        .route("/api/devices/home", post(home))
        .route("/api/devices/jog", post(jog))
        .route("/api/devices/jog/cancel", post(jog_cancel))
        .route("/api/devices/frame", post(frame))
        .route("/api/jobs", post(start_job).get(jobs))
        .route("/api/jobs/{id}", get(job))
        .route("/api/jobs/{id}/hold", post(hold))
        .route("/api/jobs/{id}/resume", post(resume))
        .route("/api/jobs/{id}/stop", post(stop))
        .route("/api/jobs/{id}/answer", post(answer))
}
