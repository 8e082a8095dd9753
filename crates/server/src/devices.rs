//! The device panel's state: the device open (the project's `[device]`, by default the embedded
//! GRBL simulator set up as the project's machine), the jobs streamed to it with their live
//! progress, and the device's events turned into `/api/events` (`device`, `job`) so every open
//! page sees the same state. The session itself — the link, the sender, the journal, the
//! operator's questions — is the `flatcut-device` library's, as it is for `flatcut send`.
//!
//! One job per device at a time (the library refuses a second: 409). A stopped server closes the
//! device, which stops a running job with the tool off and its journal written.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use flatcut::gcode::Profile;
use flatcut_device::grbl::{CancelToken, Job, PausePolicy, SendError, SendOptions};
use flatcut_device::sim::SimReport;
use flatcut_device::{
    Asked, Device, DeviceError, DeviceEvent, JobHandle, JobRequest, SimMachine, SimSetup, Target,
};
use serde_json::{Value as Json, json};

use crate::device_views::{
    controller_view, progress_view, question_view, report_view, sim_view, status_view,
};
use crate::events::Events;

/// The device id of the embedded simulator in the API.
pub const SIMULATOR: &str = "simulator";
/// The embedded simulator's default time scale: a sheet of the shoe (about 6 minutes of machine
/// time) streams in seconds while progress, hold and resume stay visible (as `flatcut send`).
pub const DEFAULT_SIM_SPEED: f64 = 50.0;

/// What the page asked to open.
#[derive(Clone, Debug, PartialEq)]
pub struct OpenRequest {
    /// `simulator` or a serial port's path.
    pub device: String,
    /// Baud rate of the link (GRBL's 115200 when absent); the simulator's link is paced at it.
    pub baud: Option<u32>,
    /// The simulator's time scale (1: real time).
    pub speed: Option<f64>,
    /// The simulator's motion completes at once.
    pub instant: bool,
}

/// What a job is doing, as the page shows it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JobState {
    Running,
    /// Feed hold asked for by the operator.
    Held,
    /// The job paused itself (`M0`) and waits.
    Paused,
    /// A question waits for the operator's answer.
    Asking,
    Done,
    Failed,
    /// Stopped by the operator (or the server stopping): tool off, journal written.
    Stopped,
}

impl JobState {
    pub fn name(self) -> &'static str {
        match self {
            JobState::Running => "running",
            JobState::Held => "held",
            JobState::Paused => "paused",
            JobState::Asking => "asking",
            JobState::Done => "done",
            JobState::Failed => "failed",
            JobState::Stopped => "stopped",
        }
    }

    pub fn ended(self) -> bool {
        matches!(self, JobState::Done | JobState::Failed | JobState::Stopped)
    }
}

/// One job streamed from the workbench.
pub struct JobRecord {
    pub id: u64,
    /// Its file name as `flatcut run` writes it (`job-1.gcode`).
    pub name: String,
    pub sheet: usize,
    /// The design revision its G-code was made from.
    pub revision: u64,
    pub device: String,
    pub journal: PathBuf,
    pub resume: bool,
    /// The line of the file the operator resumed from (1-based).
    pub resume_from: Option<usize>,
    pub state: JobState,
    pub progress: Option<Json>,
    pub notices: Vec<String>,
    pub question: Option<Asked>,
    pub message: String,
    pub report: Option<Json>,
    /// The lines a refused resume could not tell ran or not: the page
    /// asks for the line to continue from.
    pub in_doubt: Option<Json>,
    /// The job as parsed (what the lines in doubt are, and where).
    job: Arc<Job>,
    /// Wall-clock seconds per second of machine time (for the ETA), `None`: instant motion.
    wall_per_machine_s: Option<f64>,
    control: CancelToken,
    stop_asked: bool,
}

impl JobRecord {
    /// The job as `GET /api/jobs/{id}` and the `job` event give it.
    pub fn view(&self) -> Json {
        json!({
            "id": self.id,
            "name": self.name,
            "sheet": self.sheet,
            "revision": self.revision,
            "device": self.device,
            "journal": self.journal.display().to_string(),
            "resume": self.resume,
            "resume_from": self.resume_from,
            "state": self.state.name(),
            "progress": self.progress,
            "notices": self.notices,
            "question": self.question.as_ref().map(question_view),
            "message": self.message,
            "report": self.report,
            "in_doubt": self.in_doubt,
        })
    }
}

/// The device open now.
struct OpenDevice {
    /// `simulator` or the port's path.
    id: String,
    /// Which opening this is (its watcher's events belong to it).
    generation: u64,
    device: Arc<Device>,
    controller: Option<Json>,
    status: Option<Json>,
    /// The simulator's time scale (`None` on a port).
    speed: Option<f64>,
}

#[derive(Default)]
struct Inner {
    open: Option<OpenDevice>,
    jobs: BTreeMap<u64, JobRecord>,
    /// The job on the open device, if one runs.
    current: Option<u64>,
    /// What the last embedded simulator closed had executed.
    last_sim: Option<SimReport>,
    /// Openings so far.
    generations: u64,
}

/// The shared state: behind a lock, and the events every page hears.
struct Shared {
    inner: Mutex<Inner>,
    events: Events,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, Inner> {
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn publish_job(&self, inner: &Inner, id: u64) {
        if let Some(j) = inner.jobs.get(&id) {
            self.events.publish("job", j.view());
        }
    }

    fn publish_device(&self, inner: &Inner, what: &str) {
        self.events.publish("device", device_view(inner, what));
    }
}

fn device_view(inner: &Inner, what: &str) -> Json {
    match &inner.open {
        Some(o) => json!({
            "event": what,
            "open": true,
            "id": o.id,
            "description": o.device.target().describe(),
            "link": o.device.link(),
            "busy": inner.current.is_some(),
            "job": inner.current,
            "speed": o.speed,
            "controller": o.controller,
            "status": o.status,
        }),
        None => json!({ "event": what, "open": false, "job": Json::Null }),
    }
}

/// Why the device panel could not do what it was asked.
#[derive(Debug, thiserror::Error)]
pub enum PanelError {
    #[error(transparent)]
    Device(#[from] DeviceError),
    /// A job is running: nothing else but hold, resume, stop and answers.
    #[error("{0}")]
    Busy(String),
    #[error("{0}")]
    Bad(String),
    #[error("no device is open: connect one first")]
    NotOpen,
    #[error("no job {0}")]
    NoJob(u64),
}

/// The device panel: see the module docs.
pub struct Devices {
    shared: Arc<Shared>,
}

impl Devices {
    pub fn new(events: Events) -> Devices {
        Devices {
            shared: Arc::new(Shared {
                inner: Mutex::new(Inner::default()),
                events,
            }),
        }
    }

    /// `GET /api/devices`: the devices to choose from (the serial ports, then the simulator),
    /// the project's own, and the one open.
    pub fn list(&self, project_device: &flatcut::project::Device) -> Json {
        let devices: Vec<Json> = flatcut_device::list()
            .into_iter()
            .map(|d| match d.target {
                Target::Port { path, baud } => json!({
                    "id": path, "kind": "port", "baud": baud, "description": d.description,
                }),
                Target::Simulator(_) => json!({
                    "id": SIMULATOR, "kind": "simulator", "description": d.description,
                    "speed": DEFAULT_SIM_SPEED,
                }),
            })
            .collect();
        let inner = self.shared.lock();
        json!({
            "devices": devices,
            "project_device": project_id(project_device),
            "open": device_view(&inner, "state"),
            "job": inner.current.and_then(|id| inner.jobs.get(&id)).map(JobRecord::view),
        })
    }

    /// Opens `req` (closing the device open now, when it runs no job) and connects to it (its
    /// banner, `$I`, `$$`); status reports follow as `device` events. Blocking.
    pub fn connect(&self, req: &OpenRequest, profile: &Profile) -> Result<Json, PanelError> {
        let device = self.open(req, profile)?;
        let info = device.connect()?;
        let mut inner = self.shared.lock();
        if let Some(o) = inner.open.as_mut() {
            o.controller = Some(controller_view(&info));
        }
        self.shared.publish_device(&inner, "connected");
        Ok(device_view(&inner, "connected"))
    }

    /// The device `req` names, opened (the one open already when it is the same).
    fn open(&self, req: &OpenRequest, profile: &Profile) -> Result<Arc<Device>, PanelError> {
        let target = target(req, profile)?;
        {
            let inner = self.shared.lock();
            if let Some(o) = &inner.open {
                if o.device.target() == &target {
                    return Ok(o.device.clone());
                }
                if inner.current.is_some() {
                    return Err(PanelError::Busy(format!(
                        "a job is running on {}: stop it before opening another device",
                        o.device.target().describe()
                    )));
                }
            }
        }
        self.close();
        let speed = match &target {
            Target::Simulator(s) => Some(s.speed),
            Target::Port { .. } => None,
        };
        let device = Arc::new(Device::open(target)?);
        let sub = device.subscribe();
        let mut inner = self.shared.lock();
        inner.generations += 1;
        let generation = inner.generations;
        inner.open = Some(OpenDevice {
            id: req.device.clone(),
            generation,
            device: device.clone(),
            controller: None,
            status: None,
            speed,
        });
        self.shared.publish_device(&inner, "opened");
        drop(inner);
        let shared = self.shared.clone();
        std::thread::Builder::new()
            .name("flatcut-serve-device".into())
            .spawn(move || forward(&shared, generation, &sub))
            .map_err(|e| PanelError::Bad(format!("cannot watch the device: {e}")))?;
        Ok(device)
    }

    /// The device open now, or the project's device opened (by default the embedded simulator
    /// as the project's machine).
    fn open_or_default(
        &self,
        project_device: &flatcut::project::Device,
        profile: &Profile,
    ) -> Result<Arc<Device>, PanelError> {
        if let Some(o) = &self.shared.lock().open {
            return Ok(o.device.clone());
        }
        let req = OpenRequest {
            device: project_id(project_device),
            baud: project_device.baud,
            speed: None,
            instant: false,
        };
        self.open(&req, profile)
    }

    /// Closes the device open (a running job is stopped with the tool off first) and says what
    /// the embedded simulator executed. Blocking.
    pub fn close(&self) -> Option<Json> {
        let open = {
            let mut inner = self.shared.lock();
            if let Some(j) = inner.current.and_then(|id| inner.jobs.get_mut(&id)) {
                j.stop_asked = true;
            }
            inner.open.take()
        };
        let o = open?;
        let closed = close_device(o.device);
        // The job's end is recorded by its waiter as soon as the closed worker gives it.
        let t0 = Instant::now();
        while self.shared.lock().current.is_some() && t0.elapsed() < Duration::from_secs(5) {
            std::thread::sleep(Duration::from_millis(10));
        }
        let mut inner = self.shared.lock();
        let view = closed.as_ref().map(sim_view);
        if closed.is_some() {
            inner.last_sim = closed;
        }
        self.shared.publish_device(&inner, "closed");
        Some(json!({ "closed": o.id, "sim": view }))
    }

    /// What the last embedded simulator closed had executed (`None`: none was closed).
    pub fn last_sim(&self) -> Option<SimReport> {
        self.shared.lock().last_sim.clone()
    }

    /// What the open embedded simulator executed so far (between jobs).
    pub fn sim(&self) -> Result<Json, PanelError> {
        let device = self.device()?;
        match device.sim_report()? {
            Some(r) => Ok(sim_view(&r)),
            None => Err(PanelError::Bad(
                "the device open is a serial port, not the simulator".into(),
            )),
        }
    }

    fn device(&self) -> Result<Arc<Device>, PanelError> {
        self.shared
            .lock()
            .open
            .as_ref()
            .map(|o| o.device.clone())
            .ok_or(PanelError::NotOpen)
    }

    /// Runs `f` on the device open (unlock, home, jog, frame, status). Blocking.
    pub fn with_device<T>(
        &self,
        f: impl FnOnce(&Device) -> Result<T, DeviceError>,
    ) -> Result<T, PanelError> {
        let d = self.device()?;
        Ok(f(&d)?)
    }

    /// Starts streaming `gcode` (sheet `sheet` of revision `revision`, `name` as `flatcut run`
    /// names its file) to the device open, or the project's device. Blocking (it may open the
    /// device).
    pub fn start(
        &self,
        job: StartJob,
        project_device: &flatcut::project::Device,
        profile: &Profile,
    ) -> Result<Json, PanelError> {
        let device = self.open_or_default(project_device, profile)?;
        let parsed = JobRequest::parse(job.name.clone(), &job.gcode)
            .map_err(|e| PanelError::Bad(format!("cannot prepare {}: {e}", job.name)))?;
        let lines = Arc::new(parsed.job.clone());
        let opts = SendOptions::default()
            .with_journal(&job.journal)
            .with_resume(job.resume)
            .with_unlock(job.unlock)
            // The operator decides at the page: a job's own pause waits for resume or stop.
            .with_on_pause(PausePolicy::Wait);
        let control = CancelToken::new();
        let mut req = parsed
            .with_options(opts)
            .with_control(control.clone())
            .with_questions(true);
        if let Some(line) = job.resume_from {
            req = req.resume_from_line(line)?;
        }
        let wall = device.target().wall_per_machine_second();
        let describe = device.target().describe();
        let mut inner = self.shared.lock();
        if inner.current.is_some() {
            return Err(PanelError::Busy(format!(
                "a job is running on {describe}: it takes one job at a time"
            )));
        }
        let id = inner.jobs.keys().next_back().map_or(1, |k| k + 1);
        let handle = device.start(req).map_err(|e| match e {
            DeviceError::Busy { .. } => PanelError::Busy(e.to_string()),
            e => PanelError::Device(e),
        })?;
        inner.jobs.insert(
            id,
            JobRecord {
                id,
                name: job.name,
                sheet: job.sheet,
                revision: job.revision,
                device: describe,
                journal: job.journal,
                resume: job.resume || job.resume_from.is_some(),
                resume_from: job.resume_from,
                state: JobState::Running,
                progress: None,
                notices: Vec::new(),
                question: None,
                message: String::new(),
                report: None,
                in_doubt: None,
                job: lines,
                wall_per_machine_s: wall,
                control,
                stop_asked: false,
            },
        );
        inner.current = Some(id);
        self.shared.publish_job(&inner, id);
        self.shared.publish_device(&inner, "busy");
        let view = inner.jobs[&id].view();
        drop(inner);
        let shared = self.shared.clone();
        std::thread::Builder::new()
            .name("flatcut-serve-job".into())
            .spawn(move || wait_for_end(&shared, id, handle))
            .map_err(|e| PanelError::Bad(format!("cannot watch the job: {e}")))?;
        Ok(view)
    }

    /// `GET /api/jobs/{id}`.
    pub fn job(&self, id: u64) -> Result<Json, PanelError> {
        let inner = self.shared.lock();
        inner
            .jobs
            .get(&id)
            .map(JobRecord::view)
            .ok_or(PanelError::NoJob(id))
    }

    /// `GET /api/jobs`: every job of this session, newest last.
    pub fn jobs(&self) -> Json {
        let inner = self.shared.lock();
        json!({ "jobs": inner.jobs.values().map(JobRecord::view).collect::<Vec<_>>() })
    }

    /// Steers job `id`: hold, resume or stop.
    pub fn steer(&self, id: u64, what: Steer) -> Result<Json, PanelError> {
        let mut inner = self.shared.lock();
        let j = inner.jobs.get_mut(&id).ok_or(PanelError::NoJob(id))?;
        if j.state.ended() {
            return Err(PanelError::Bad(format!(
                "job {id} has ended ({})",
                j.state.name()
            )));
        }
        match what {
            Steer::Hold => {
                j.control.hold();
                if j.state == JobState::Running {
                    j.state = JobState::Held;
                }
            }
            Steer::Resume => {
                j.control.resume();
                if matches!(j.state, JobState::Held | JobState::Paused) {
                    j.state = JobState::Running;
                }
            }
            Steer::Stop => {
                j.stop_asked = true;
                j.control.abort();
            }
        }
        let v = j.view();
        self.shared.publish_job(&inner, id);
        Ok(v)
    }

    /// Answers the question job `id` asks.
    pub fn answer(&self, id: u64, question: u64, yes: bool) -> Result<Json, PanelError> {
        let device = self.device()?;
        device.answer(question, yes)?;
        let mut inner = self.shared.lock();
        let j = inner.jobs.get_mut(&id).ok_or(PanelError::NoJob(id))?;
        if j.question.as_ref().is_some_and(|q| q.id == question) {
            j.question = None;
            if j.state == JobState::Asking {
                j.state = JobState::Running;
            }
        }
        let v = j.view();
        self.shared.publish_job(&inner, id);
        Ok(v)
    }
}

/// A job to start.
pub struct StartJob {
    pub name: String,
    pub sheet: usize,
    pub revision: u64,
    pub gcode: String,
    pub journal: PathBuf,
    pub resume: bool,
    pub unlock: bool,
    /// Resume from this line of the file (1-based), whatever the journal says.
    pub resume_from: Option<usize>,
}

/// What the page asks of a running job.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Steer {
    Hold,
    Resume,
    Stop,
}

/// The API's id of a project's `[device]`.
fn project_id(d: &flatcut::project::Device) -> String {
    if d.is_simulator() {
        SIMULATOR.to_string()
    } else {
        d.port.clone().unwrap_or_else(|| SIMULATOR.to_string())
    }
}

/// The machine `profile` describes, for the embedded simulator to be (as `flatcut run` sets it
/// up), so a job that does not fit the machine is refused as the machine would refuse it.
fn machine(profile: &Profile) -> SimMachine {
    SimMachine {
        limits: flatcut::gcode::time::limits(profile),
        work_area: profile.work_area_mm,
    }
}

/// The device a request names.
fn target(req: &OpenRequest, profile: &Profile) -> Result<Target, PanelError> {
    if req.device == SIMULATOR {
        let speed = req.speed.unwrap_or(DEFAULT_SIM_SPEED);
        if !(speed.is_finite() && speed > 0.0 && speed <= 1000.0) {
            return Err(PanelError::Bad(format!(
                "speed {speed}: the simulator's time scale is a number in (0, 1000]"
            )));
        }
        let mut setup = SimSetup::default()
            .with_machine(machine(profile))
            .with_speed(speed)
            .with_instant(req.instant)
            .with_laser(profile.kind == flatcut::gcode::ToolKind::Laser);
        if let Some(b) = req.baud {
            setup.baud = b;
        }
        return Ok(Target::Simulator(setup));
    }
    if req.device.is_empty() {
        return Err(PanelError::Bad(
            "name a device: `simulator` or a serial port".into(),
        ));
    }
    Ok(Target::Port {
        path: req.device.clone(),
        baud: req.baud.unwrap_or(SimSetup::default().baud),
    })
}

/// Longest wait for a request that still uses a device being closed (a command's own timeout
/// bounds it) before the device is left to close when that request ends.
const CLOSE_WAIT: Duration = Duration::from_secs(30);

/// Closes a device no longer listed as open: a running job is stopped first (feed hold, soft
/// reset, tool off, journal written), then the link and the simulator, whose record comes back.
/// A request still using the device (a command under way) is waited for up to [`CLOSE_WAIT`];
/// beyond, the device closes when that request lets go of it.
fn close_device(mut device: Arc<Device>) -> Option<SimReport> {
    if device.is_busy() {
        let _ = device.stop();
    }
    let t0 = Instant::now();
    loop {
        match Arc::try_unwrap(device) {
            Ok(d) => return d.close().sim,
            Err(d) if t0.elapsed() < CLOSE_WAIT => {
                device = d;
                std::thread::sleep(Duration::from_millis(20));
            }
            Err(_) => return None,
        }
    }
}

/// Turns the device's events into the panel's state and the pages' events, until it closes.
fn forward(shared: &Shared, generation: u64, sub: &flatcut_device::Subscription) {
    while let Some(e) = sub.recv() {
        let mut inner = shared.lock();
        let mine = inner
            .open
            .as_ref()
            .is_some_and(|o| o.generation == generation);
        let job = inner.current;
        match e {
            DeviceEvent::Connected(info) => {
                if let Some(o) = inner.open.as_mut().filter(|_| mine) {
                    o.controller = Some(controller_view(&info));
                }
                shared.publish_device(&inner, "connected");
            }
            DeviceEvent::Status(s) => {
                if let Some(o) = inner.open.as_mut().filter(|_| mine) {
                    o.status = Some(status_view(&s));
                }
                shared.publish_device(&inner, "status");
            }
            DeviceEvent::Restarted => {
                shared.events.publish(
                    "device",
                    json!({"event": "restarted", "open": mine,
                        "message": "the controller restarted: its position and G92 offset are gone"}),
                );
            }
            DeviceEvent::Progress(p) => {
                let live = job
                    .and_then(|id| inner.jobs.get_mut(&id))
                    .filter(|j| !j.state.ended());
                if let Some(j) = live {
                    j.progress = Some(progress_view(&p, j.wall_per_machine_s));
                    j.state = match (j.state, p.holding, &p.paused_at) {
                        (JobState::Asking, _, _) => JobState::Asking,
                        (_, _, Some(_)) => JobState::Paused,
                        (_, true, _) => JobState::Held,
                        _ => JobState::Running,
                    };
                }
                if let Some(id) = job {
                    shared.publish_job(&inner, id);
                }
            }
            DeviceEvent::Notice(n) => {
                if let Some(j) = job.and_then(|id| inner.jobs.get_mut(&id)) {
                    j.notices.push(n);
                }
                if let Some(id) = job {
                    shared.publish_job(&inner, id);
                }
            }
            DeviceEvent::Paused(l) => {
                if let Some(j) = job.and_then(|id| inner.jobs.get_mut(&id)) {
                    j.state = JobState::Paused;
                    j.message = format!("the job paused itself at {l}: resume or stop it");
                }
                if let Some(id) = job {
                    shared.publish_job(&inner, id);
                }
            }
            DeviceEvent::Question(a) => {
                if let Some(j) = job.and_then(|id| inner.jobs.get_mut(&id)) {
                    j.state = JobState::Asking;
                    j.question = Some(a);
                }
                if let Some(id) = job {
                    shared.publish_job(&inner, id);
                }
            }
            DeviceEvent::Closed(why) => {
                if mine {
                    inner.open = None;
                    shared.events.publish(
                        "device",
                        json!({"event": "closed", "open": false, "message": why}),
                    );
                }
                return;
            }
            // Job starts and ends are the job's waiter's to tell (with the sender's report).
            _ => {}
        }
    }
}

/// Waits for job `id`'s end and records it.
fn wait_for_end(shared: &Shared, id: u64, handle: JobHandle) {
    let r = handle.wait();
    let mut inner = shared.lock();
    if inner.current == Some(id) {
        inner.current = None;
    }
    if let Some(j) = inner.jobs.get_mut(&id) {
        j.question = None;
        match r {
            Ok(o) => {
                j.state = JobState::Done;
                j.message = "complete".into();
                j.report = Some(report_view(&o.report));
            }
            Err(e) => {
                j.state = if j.stop_asked {
                    JobState::Stopped
                } else {
                    JobState::Failed
                };
                j.in_doubt = doubt_view(&e, &j.job);
                j.message = e.to_string();
            }
        }
    }
    shared.publish_job(&inner, id);
    shared.publish_device(&inner, "idle");
}

/// The lines a stopped or refused job leaves to the operator's word, as the page shows them:
/// `{from, to, reason, lines}` (1-based lines of the file) when the sender cannot tell which of
/// them ran (a resume whose journal and machine cannot settle it, a line damaged on the link).
/// `lines` are those lines as sent, each with where it moves the tool (work mm: its start and
/// end, an arc's chord points between) and whether the tool cuts, so the page can show them over
/// the layout while the operator looks at the work; the page then asks for the line to continue
/// from (`resume_from`).
fn doubt_view(e: &SendError, job: &Job) -> Option<Json> {
    let (from, to, reason) = match e {
        SendError::ResumeUncertain { from, to, reason } => (from, to, reason.clone()),
        SendError::OffPath(off) => (
            &off.from,
            &off.to,
            "the machine left the job's path: a line was probably damaged on the link".into(),
        ),
        _ => return None,
    };
    let lines: Vec<Json> = (from.index..=to.index.min(from.index + MAX_DOUBT_LINES - 1))
        .filter_map(|i| job.lines.get(i).map(|l| (i, l)))
        .map(|(i, l)| {
            let path: Vec<[f64; 3]> = match (l.moves && l.length > 0.0, l.arc.is_empty()) {
                (false, _) => Vec::new(),
                (true, true) => vec![job.start_of(i), job.end_of(i)],
                (true, false) => l.arc.clone(),
            };
            json!({ "line": l.source_line, "text": l.text, "cuts": l.tool_on, "path": path })
        })
        .collect();
    Some(json!({
        "from": from.source_line,
        "to": to.source_line,
        "reason": reason,
        "lines": lines,
    }))
}

/// Most lines in doubt the view lists (a damaged line's doubt spans what the controller's buffer
/// held: tens of lines).
const MAX_DOUBT_LINES: usize = 1000;

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_device::grbl::driver::LineRef;

    fn line(job: &Job, index: usize) -> LineRef {
        LineRef {
            index,
            source_line: job.lines[index].source_line,
            text: job.lines[index].text.clone(),
        }
    }

    #[test]
    fn a_refused_resume_names_the_lines_in_doubt_by_the_files_numbers_and_where_they_move() {
        let job = Job::parse(
            "G21 G90\n(the square)\nG0 X10 Y0\nM3 S1000\nG1 X20 F600\nG2 X30 Y10 I0 J10\nM5\n",
        )
        .unwrap();
        let e = SendError::ResumeUncertain {
            from: line(&job, 1),
            to: line(&job, 4),
            reason: "the path passes the machine's position 2 times".into(),
        };
        let d = doubt_view(&e, &job).expect("lines in doubt");
        assert_eq!((d["from"].as_u64(), d["to"].as_u64()), (Some(3), Some(6)));
        assert!(d["reason"].as_str().unwrap().contains("2 times"));
        let lines = d["lines"].as_array().unwrap();
        let numbers: Vec<u64> = lines.iter().map(|l| l["line"].as_u64().unwrap()).collect();
        assert_eq!(numbers, [3, 4, 5, 6]);
        // The rapid to (10, 0) does not cut; the spindle line moves nothing; the feed cuts along
        // X; the arc's chords run from (20, 0) to (30, 10) about its centre (20, 10).
        assert_eq!(lines[0]["path"], json!([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]]));
        assert_eq!(lines[0]["cuts"], false);
        assert_eq!(lines[1]["path"], json!([]));
        assert_eq!(
            lines[2]["path"],
            json!([[10.0, 0.0, 0.0], [20.0, 0.0, 0.0]])
        );
        assert_eq!(lines[2]["cuts"], true);
        let arc = lines[3]["path"].as_array().unwrap();
        assert!(arc.len() > 2, "{arc:?}");
        let xy = |p: &Json| (p[0].as_f64().unwrap(), p[1].as_f64().unwrap());
        // GRBL splits arcs in single precision: the chords' ends are on the circle to 1e-3 mm.
        for p in arc {
            let (x, y) = xy(p);
            assert!(((x - 20.0).hypot(y - 10.0) - 10.0).abs() < 1e-3, "{p}");
        }
        let ((x0, y0), (x1, y1)) = (xy(&arc[0]), xy(&arc[arc.len() - 1]));
        assert!((x0 - 20.0).hypot(y0) < 1e-3 && (x1 - 30.0).hypot(y1 - 10.0) < 1e-3);
        // A stop whose lines all are known needs no line from the operator.
        let stop = SendError::Aborted { last_done: None };
        assert!(doubt_view(&stop, &job).is_none());
    }
}
