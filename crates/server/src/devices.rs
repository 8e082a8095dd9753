//! The device panel's state: the devices open, each under a stable id (a serial port's path,
//! `simulator` for the embedded simulator, `simulator:<name>` for another one), with its own link,
//! controller, position and job slot; the jobs streamed to them with their live progress; and the
//! devices' events turned into `/api/events` (`device`, `job`, tagged with the device's id) so
//! every open page sees the same state. The session itself — the link, the sender, the journal,
//! the operator's questions — is the `flatcut-device` library's, as it is for `flatcut send`.
//!
//! An HP-GL plotter or vinyl cutter is a device too: the embedded HP-GL plotter
//! ([`PLOTTER_SIM`]), or a serial port opened with `protocol: "hpgl"` and a profile with an
//! `[hpgl]` section (its flow control and baud rate); its jobs are the sheet's HP-GL (the bytes
//! of `GET /api/job.plt` for its profile), their progress the bytes the link accepted.
//!
//! One job per device at a time (the library refuses a second: 409); two devices run jobs at
//! once. A request that names no device means the default one: the device opened (or connected)
//! last that is still open, else the project's `[device]` (by default the embedded GRBL simulator
//! set up as the project's machine). A job's journal is its file's (`job-N.gcode.journal`), so one
//! sheet's job streams to one device at a time. A stopped server closes every device, which stops
//! each running job with the tool off and its journal written.

use std::path::PathBuf;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use flatcut::gcode::Profile;
use flatcut_device::grbl::hpgl::HpglControl;
use flatcut_device::grbl::{CancelToken, PausePolicy, SendOptions};
use flatcut_device::sim::SimReport;
use flatcut_device::{
    Closed, Device, DeviceError, JobRequest, PlotRequest, PlotterReport, PlotterSimSetup,
    SimMachine, SimSetup, Target,
};
use serde_json::{Value as Json, json};

use crate::device_state::{
    Inner, JobControl, JobRecord, JobState, OpenDevice, PanelError, Shared, closed_view,
};
use crate::device_views::{controller_view, plotter_view, sim_view};
use crate::device_watch::{forward, wait_for_end, wait_for_plot};
use crate::events::Events;
use crate::plotters::{PLOTTER_SIM, PlotterChoice};

/// The device id of the embedded simulator in the API; `simulator:<name>` is another one.
pub const SIMULATOR: &str = "simulator";

/// Whether `id` names an embedded simulator: `simulator`, or `simulator:<name>` with a name of
/// 1 to 32 letters, digits, `-`, `_` or `.`.
pub fn is_simulator(id: &str) -> bool {
    id == SIMULATOR
        || id.strip_prefix("simulator:").is_some_and(|n| {
            (1..=32).contains(&n.len())
                && n.chars()
                    .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'))
        })
}
/// The embedded simulator's default time scale: a sheet of the shoe (about 6 minutes of machine
/// time) streams in seconds while progress, hold and resume stay visible (as `flatcut send`).
pub const DEFAULT_SIM_SPEED: f64 = 50.0;

/// What the page asked to open.
#[derive(Clone, Debug, PartialEq)]
pub struct OpenRequest {
    /// `simulator`, `simulator:<name>` or a serial port's path.
    pub device: String,
    /// Baud rate of the link (GRBL's 115200 when absent); the simulator's link is paced at it.
    pub baud: Option<u32>,
    /// The simulator's time scale (1: real time).
    pub speed: Option<f64>,
    /// The simulator's motion completes at once.
    pub instant: bool,
    /// Open it as an HP-GL plotter with this profile and link (always for [`PLOTTER_SIM`]).
    pub plotter: Option<PlotterChoice>,
}

/// The device panel: see the module docs.
pub struct Devices {
    shared: Arc<Shared>,
}

impl Devices {
    /// The panel with no device open and no job, publishing its changes on `events`.
    pub fn new(events: Events) -> Devices {
        Devices {
            shared: Arc::new(Shared {
                inner: Mutex::new(Inner::default()),
                events,
            }),
        }
    }

    /// `GET /api/devices`: the devices to choose from (the serial ports, then the simulator, then
    /// the devices open that the system does not list: other simulators, pseudo-terminals), each
    /// saying whether it is open; the project's own; the default device and its job; every device
    /// open and every job running.
    pub fn list(&self, project_device: &flatcut::project::Device) -> Json {
        let inner = self.shared.lock();
        let mut listed: Vec<String> = Vec::new();
        let mut devices: Vec<Json> = flatcut_device::list()
            .into_iter()
            .map(|d| {
                let id = match &d.target {
                    Target::Simulator(_) => SIMULATOR.to_string(),
                    Target::PlotterSim(_) => PLOTTER_SIM.to_string(),
                    t => t.path().unwrap_or_default().to_string(),
                };
                let open = inner.open.contains_key(&id);
                listed.push(id.clone());
                match d.target {
                    Target::Simulator(_) => json!({
                        "id": id, "kind": "simulator", "description": d.description,
                        "speed": DEFAULT_SIM_SPEED, "open": open, "protocol": "grbl",
                    }),
                    t => json!({
                        "id": id, "kind": "port", "baud": t.baud(), "description": d.description,
                        "open": open, "protocol": "grbl",
                    }),
                }
            })
            .collect();
        listed.push(PLOTTER_SIM.to_string());
        devices.push(json!({
            "id": PLOTTER_SIM, "kind": "plotter-simulator", "protocol": "hpgl",
            "description": "the embedded HP-GL plotter simulator", "speed": DEFAULT_SIM_SPEED,
            "open": inner.open.contains_key(PLOTTER_SIM),
        }));
        for o in inner.open.values().filter(|o| !listed.contains(&o.id)) {
            let kind = if is_simulator(&o.id) {
                "simulator"
            } else {
                "port"
            };
            devices.push(json!({
                "id": o.id, "kind": kind, "description": o.device.target().describe(),
                "baud": o.device.target().baud(), "speed": o.speed, "open": true,
                "protocol": if o.plotter.is_some() { "hpgl" } else { "grbl" },
            }));
        }
        let default = inner.default.as_ref().and_then(|d| inner.open.get(d));
        json!({
            "devices": devices,
            "project_device": project_id(project_device),
            "default": default.map(|o| o.id.clone()),
            "open": default.map_or_else(|| json!({"event": "state", "open": false, "job": null}), |o| o.view("state")),
            "job": default.and_then(|o| o.job).and_then(|id| inner.jobs.get(&id)).map(JobRecord::view),
            "opened": inner.open.values().map(|o| o.view("state")).collect::<Vec<_>>(),
            "running": inner.open.values().filter_map(|o| o.job).filter_map(|id| inner.jobs.get(&id)).map(JobRecord::view).collect::<Vec<_>>(),
        })
    }

    /// Opens `req` (beside the devices open already) and connects to it (its banner, `$I`,
    /// `$$`); it becomes the default device; status reports follow as `device` events. Blocking.
    /// An HP-GL plotter has no handshake: it is opened, its link ready.
    pub fn connect(&self, req: &OpenRequest, profile: &Profile) -> Result<Json, PanelError> {
        let device = self.open(req, profile)?;
        let info = match device.target().is_plotter() {
            true => None,
            false => Some(device.connect()?),
        };
        let mut inner = self.shared.lock();
        if let Some((o, info)) = inner.open.get_mut(&req.device).zip(info) {
            o.controller = Some(controller_view(&info));
        }
        inner.default = Some(req.device.clone());
        self.shared.publish_device(&inner, &req.device, "connected");
        Ok(inner.open.get(&req.device).map_or_else(
            || closed_view(&req.device, "closed", None),
            |o| o.view("connected"),
        ))
    }

    /// The device `req` names, opened (the one open under that id already when it is the same
    /// device; one set up otherwise is closed and opened anew, unless it runs a job).
    fn open(&self, req: &OpenRequest, profile: &Profile) -> Result<Arc<Device>, PanelError> {
        let (target, plotter) = target(req, profile)?;
        {
            let inner = self.shared.lock();
            if let Some(o) = inner.open.get(&req.device) {
                if o.device.target() == &target {
                    return Ok(o.device.clone());
                }
                if o.job.is_some() {
                    return Err(PanelError::Busy(format!(
                        "a job is running on {}: stop it before opening it anew",
                        o.device.target().describe()
                    )));
                }
            }
        }
        if self.shared.lock().open.contains_key(&req.device) {
            self.close(Some(&req.device))?;
        }
        let speed = match &target {
            Target::Simulator(s) => Some(s.speed),
            Target::PlotterSim(s) => Some(s.speed),
            _ => None,
        };
        let device = Arc::new(Device::open(target)?);
        let sub = device.subscribe();
        let mut inner = self.shared.lock();
        inner.generations += 1;
        let generation = inner.generations;
        inner.open.insert(
            req.device.clone(),
            OpenDevice {
                id: req.device.clone(),
                generation,
                device: device.clone(),
                controller: None,
                status: None,
                speed,
                job: None,
                plotter,
            },
        );
        inner.default = Some(req.device.clone());
        self.shared.publish_device(&inner, &req.device, "opened");
        drop(inner);
        let shared = self.shared.clone();
        let id = req.device.clone();
        std::thread::Builder::new()
            .name("flatcut-serve-device".into())
            .spawn(move || forward(&shared, &id, generation, &sub))
            .map_err(|e| PanelError::Bad(format!("cannot watch the device: {e}")))?;
        Ok(device)
    }

    /// The device a job goes to: the one named (opened if it is not), else the default device,
    /// else the project's device opened (by default the embedded simulator as the project's
    /// machine). Its id and handle.
    fn open_for_job(
        &self,
        named: Option<&str>,
        project_device: &flatcut::project::Device,
        profile: &Profile,
    ) -> Result<(String, Arc<Device>), PanelError> {
        {
            let inner = self.shared.lock();
            if let Ok(o) = inner.resolve(named) {
                return Ok((o.id.clone(), o.device.clone()));
            }
        }
        let id = named.map_or_else(|| project_id(project_device), str::to_string);
        let req = OpenRequest {
            baud: if is_simulator(&id) {
                None
            } else {
                project_device.baud
            },
            device: id.clone(),
            speed: None,
            instant: false,
            plotter: None,
        };
        let device = self.open(&req, profile)?;
        Ok((id, device))
    }

    /// The plotter a job for `named` (the default device when `None`) goes to: the open device's
    /// profile and link when it is a plotter; [`PLOTTER_SIM`] not open yet: `None` too (the
    /// route opens it with the default plotter profile).
    pub fn plotter_of(&self, named: Option<&str>) -> Option<PlotterChoice> {
        let inner = self.shared.lock();
        inner.resolve(named).ok().and_then(|o| o.plotter.clone())
    }

    /// Closes device `id` (the default one when `None`): a running job is stopped with the tool
    /// off first; says what an embedded simulator executed. Blocking.
    pub fn close(&self, id: Option<&str>) -> Result<Json, PanelError> {
        let (open, job) = {
            let mut inner = self.shared.lock();
            let id = inner.resolve(id)?.id.clone();
            let o = inner.forget(&id);
            let job = o.as_ref().and_then(|o| o.job);
            if let Some(j) = job.and_then(|j| inner.jobs.get_mut(&j)) {
                j.stop_asked = true;
            }
            (o, job)
        };
        let Some(o) = open else {
            return Err(PanelError::NotOpen);
        };
        let closed = close_device(o.device);
        let plotted = closed.plotter;
        let closed = closed.sim;
        // The job's end is recorded by its waiter as soon as the closed worker gives it.
        let t0 = Instant::now();
        let running = |inner: &Inner| {
            job.and_then(|j| inner.jobs.get(&j))
                .is_some_and(|j| !j.state.ended())
        };
        while running(&self.shared.lock()) && t0.elapsed() < Duration::from_secs(5) {
            std::thread::sleep(Duration::from_millis(10));
        }
        let mut inner = self.shared.lock();
        let view = closed
            .as_ref()
            .map(sim_view)
            .or_else(|| plotted.as_ref().map(plotter_view));
        if let Some(r) = closed {
            inner.last_sim.insert(o.id.clone(), r);
            inner.last_closed = Some(o.id.clone());
        }
        if let Some(r) = plotted {
            inner.last_plotter.insert(o.id.clone(), r);
        }
        self.shared.publish_device(&inner, &o.id, "closed");
        Ok(json!({ "closed": o.id, "sim": view }))
    }

    /// Closes every device open (each running job stopped with the tool off first). Blocking.
    pub fn close_all(&self) {
        let ids: Vec<String> = self.shared.lock().open.keys().cloned().collect();
        for id in ids {
            let _ = self.close(Some(&id));
        }
    }

    /// What the embedded simulator closed last had executed (`None`: none was closed).
    pub fn last_sim(&self) -> Option<SimReport> {
        let inner = self.shared.lock();
        inner
            .last_closed
            .as_ref()
            .and_then(|id| inner.last_sim.get(id))
            .cloned()
    }

    /// What the embedded simulator `id` had executed when it was closed last.
    pub fn last_sim_of(&self, id: &str) -> Option<SimReport> {
        self.shared.lock().last_sim.get(id).cloned()
    }

    /// What the embedded HP-GL plotter `id` had drawn when it was closed last.
    pub fn last_plotter_of(&self, id: &str) -> Option<PlotterReport> {
        self.shared.lock().last_plotter.get(id).cloned()
    }

    /// What the embedded simulator `id` (the default device when `None`) executed so far
    /// (between jobs); for the embedded HP-GL plotter, its strokes so far.
    pub fn sim(&self, id: Option<&str>) -> Result<Json, PanelError> {
        let device = self.device(id)?;
        if device.target().is_plotter() {
            return match device.plotter_report() {
                Some(r) => Ok(plotter_view(&r)),
                None => Err(PanelError::Bad(format!(
                    "{} is a serial port, not the simulator",
                    device.target().describe()
                ))),
            };
        }
        match device.sim_report()? {
            Some(r) => Ok(sim_view(&r)),
            None => Err(PanelError::Bad(format!(
                "{} is a serial port, not the simulator",
                device.target().describe()
            ))),
        }
    }

    fn device(&self, id: Option<&str>) -> Result<Arc<Device>, PanelError> {
        Ok(self.shared.lock().resolve(id)?.device.clone())
    }

    /// Runs `f` on device `id` (the default device when `None`): unlock, home, jog, frame,
    /// status. Blocking.
    pub fn with_device<T>(
        &self,
        id: Option<&str>,
        f: impl FnOnce(&Device) -> Result<T, DeviceError>,
    ) -> Result<T, PanelError> {
        let d = self.device(id)?;
        Ok(f(&d)?)
    }

    /// Starts streaming `gcode` (sheet `sheet` of revision `revision`, `name` as `flatcut run`
    /// names its file) to the device the job names, or the default device, or the project's
    /// device. Blocking (it may open the device).
    pub fn start(
        &self,
        job: StartJob,
        project_device: &flatcut::project::Device,
        profile: &Profile,
    ) -> Result<Json, PanelError> {
        let (device_id, device) =
            self.open_for_job(job.device.as_deref(), project_device, profile)?;
        let journal = journal_path(&job.dir, &job.name, &device_id, &project_id(project_device));
        let parsed = JobRequest::parse(job.name.clone(), &job.gcode)
            .map_err(|e| PanelError::Bad(format!("cannot prepare {}: {e}", job.name)))?;
        let lines = Arc::new(parsed.job.clone());
        let opts = SendOptions::default()
            .with_journal(&journal)
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
        let inner = self.shared.lock();
        match inner.open.get(&device_id) {
            Some(o) if Arc::ptr_eq(&o.device, &device) => {
                if o.job.is_some() {
                    return Err(PanelError::Busy(format!(
                        "a job is running on {describe}: it takes one job at a time"
                    )));
                }
            }
            _ => {
                return Err(PanelError::Busy(format!(
                    "{describe} was closed meanwhile: open it again"
                )));
            }
        }
        if let Some(other) = inner
            .jobs
            .values()
            .find(|j| !j.state.ended() && j.journal.as_ref() == Some(&journal))
        {
            return Err(PanelError::Busy(format!(
                "{} is streaming to {} (job {}): its journal {} is that job's, so one device at a \
                 time streams it",
                job.name,
                other.device_id,
                other.id,
                journal.display()
            )));
        }
        let id = inner.jobs.keys().next_back().map_or(1, |k| k + 1);
        let handle = device.start(req).map_err(|e| match e {
            DeviceError::Busy { .. } => PanelError::Busy(e.to_string()),
            e => PanelError::Device(e),
        })?;
        self.launch(
            inner,
            JobRecord {
                id,
                name: job.name,
                sheet: job.sheet,
                revision: job.revision,
                device: describe,
                device_id: device_id.clone(),
                journal: Some(journal),
                protocol: "grbl",
                resume: job.resume || job.resume_from.is_some(),
                resume_from: job.resume_from,
                state: JobState::Running,
                progress: None,
                notices: Vec::new(),
                question: None,
                message: String::new(),
                report: None,
                in_doubt: None,
                job: Some(lines),
                wall_per_machine_s: wall,
                control: JobControl::Grbl(control),
                stop_asked: false,
            },
            "flatcut-serve-job",
            move |shared, id, device| wait_for_end(shared, id, device, handle),
        )
    }

    /// Starts plotting `job.hpgl` (sheet `sheet` of revision `revision`) on the HP-GL plotter
    /// the job names, or the default device: the one open, or the embedded plotter opened with
    /// `job.plotter`. Blocking (it may open the device).
    pub fn start_plot(&self, job: PlotJob, profile: &Profile) -> Result<Json, PanelError> {
        let found = {
            let inner = self.shared.lock();
            inner
                .resolve(job.device.as_deref())
                .ok()
                .map(|o| (o.id.clone(), o.device.clone()))
        };
        let (device_id, device) = match found {
            Some(d) => d,
            None => {
                let id = job
                    .device
                    .clone()
                    .unwrap_or_else(|| PLOTTER_SIM.to_string());
                let req = OpenRequest {
                    device: id.clone(),
                    baud: None,
                    speed: None,
                    instant: false,
                    plotter: Some(job.plotter.clone()),
                };
                (id, self.open(&req, profile)?)
            }
        };
        let control = HpglControl::new();
        let mut req = PlotRequest::new(job.name.clone(), job.hpgl.into_bytes());
        req.control = control.clone();
        let describe = device.target().describe();
        let inner = self.shared.lock();
        match inner.open.get(&device_id) {
            Some(o) if Arc::ptr_eq(&o.device, &device) => {
                if o.job.is_some() {
                    return Err(PanelError::Busy(format!(
                        "a job is running on {describe}: it takes one job at a time"
                    )));
                }
            }
            _ => {
                return Err(PanelError::Busy(format!(
                    "{describe} was closed meanwhile: open it again"
                )));
            }
        }
        let id = inner.jobs.keys().next_back().map_or(1, |k| k + 1);
        let handle = device.start_plot(req).map_err(|e| match e {
            DeviceError::Busy { .. } => PanelError::Busy(e.to_string()),
            e => PanelError::Device(e),
        })?;
        self.launch(
            inner,
            JobRecord {
                id,
                name: job.name,
                sheet: job.sheet,
                revision: job.revision,
                device: describe,
                device_id: device_id.clone(),
                journal: None,
                protocol: "hpgl",
                resume: false,
                resume_from: None,
                state: JobState::Running,
                progress: None,
                notices: Vec::new(),
                question: None,
                message: String::new(),
                report: None,
                in_doubt: None,
                job: None,
                wall_per_machine_s: None,
                control: JobControl::Plot(control),
                stop_asked: false,
            },
            "flatcut-serve-plot",
            move |shared, id, device| wait_for_plot(shared, id, device, handle),
        )
    }

    /// Files a job its device has started as `record`, tells every tab, and watches it to its
    /// end on a thread of its own named `thread` (`watch`: the protocol's wait for the end).
    fn launch(
        &self,
        mut inner: MutexGuard<'_, Inner>,
        record: JobRecord,
        thread: &str,
        watch: impl FnOnce(&Shared, u64, &str) + Send + 'static,
    ) -> Result<Json, PanelError> {
        let (id, device_id) = (record.id, record.device_id.clone());
        inner.jobs.insert(id, record);
        if let Some(o) = inner.open.get_mut(&device_id) {
            o.job = Some(id);
        }
        self.shared.publish_job(&inner, id);
        self.shared.publish_device(&inner, &device_id, "busy");
        let view = inner.jobs[&id].view();
        drop(inner);
        let shared = self.shared.clone();
        std::thread::Builder::new()
            .name(thread.into())
            .spawn(move || watch(&shared, id, &device_id))
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

    /// Answers the question job `id` asks (on the job's own device).
    pub fn answer(&self, id: u64, question: u64, yes: bool) -> Result<Json, PanelError> {
        let device = {
            let inner = self.shared.lock();
            let j = inner.jobs.get(&id).ok_or(PanelError::NoJob(id))?;
            inner.resolve(Some(&j.device_id))?.device.clone()
        };
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
    /// The job file's name as `flatcut run` writes it (`job-1.gcode`).
    pub name: String,
    /// The sheet it cuts (1-based).
    pub sheet: usize,
    /// The design revision the G-code was made from.
    pub revision: u64,
    /// The G-code text, streamed from memory.
    pub gcode: String,
    /// Where its journal goes (beside the design): see [`journal_path`].
    pub dir: PathBuf,
    /// Resume from the journal where the last attempt stopped.
    pub resume: bool,
    /// Send `$X` first if the controller is alarm-locked.
    pub unlock: bool,
    /// Resume from this line of the file (1-based), whatever the journal says.
    pub resume_from: Option<usize>,
    /// The device's id (`None`: the default device, else the project's).
    pub device: Option<String>,
}

/// An HP-GL job to plot.
pub struct PlotJob {
    /// Its file name (`job-1.plt`).
    pub name: String,
    /// The sheet it plots (1-based).
    pub sheet: usize,
    /// The design revision the HP-GL was made from.
    pub revision: u64,
    /// The HP-GL, streamed from memory: `GET /api/job.plt`'s bytes for the plotter's profile.
    pub hpgl: String,
    /// The device's id (`None`: the default device, else the embedded plotter).
    pub device: Option<String>,
    /// The plotter to open when the device is not open.
    pub plotter: PlotterChoice,
}

/// What the page asks of a running job.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Steer {
    /// Feed hold (`!`): the machine decelerates and waits.
    Hold,
    /// Cycle start (`~`) after a hold or a pause.
    Resume,
    /// Stop the job: tool off, journal written.
    Stop,
}

/// The journal of job file `name` (`job-1.gcode`) streamed to device `device`, in `dir`:
/// `job-1.gcode.journal` on the project's own device (`project`; the name `flatcut send` and
/// `flatcut run` use), `job-1.gcode@<device>.journal` on another one (its id with every character
/// but letters, digits, `.`, `_` and `-` made `-`: `job-1.gcode@simulator-2.journal`), so the same
/// sheet cut on two machines keeps one journal per machine, and each resumes from its own.
pub fn journal_path(dir: &std::path::Path, name: &str, device: &str, project: &str) -> PathBuf {
    if device == project {
        return dir.join(format!("{name}.journal"));
    }
    let slug: String = device
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-') {
                c
            } else {
                '-'
            }
        })
        .collect();
    dir.join(format!("{name}@{}.journal", slug.trim_matches('-')))
}

/// The API's id of a project's `[device]`.
pub fn project_id(d: &flatcut::project::Device) -> String {
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

/// The device a request names, and the plotter's profile and link when it is one.
fn target(
    req: &OpenRequest,
    profile: &Profile,
) -> Result<(Target, Option<PlotterChoice>), PanelError> {
    if req.device == PLOTTER_SIM || req.plotter.is_some() {
        return plotter_target(req, profile);
    }
    grbl_target(req, profile).map(|t| (t, None))
}

/// A GRBL device: the embedded simulator set up as the profile's machine, or a serial port.
fn grbl_target(req: &OpenRequest, profile: &Profile) -> Result<Target, PanelError> {
    if is_simulator(&req.device) {
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
            "name a device: `simulator`, `simulator:<name>` or a serial port".into(),
        ));
    }
    if req.device.starts_with("simulator:") {
        return Err(PanelError::Bad(format!(
            "{}: another simulator is `simulator:<name>`, a name of 1 to 32 letters, digits, \
             `-`, `_` or `.`",
            req.device
        )));
    }
    Ok(Target::Port {
        path: req.device.clone(),
        baud: req.baud.unwrap_or(SimSetup::default().baud),
    })
}

/// An HP-GL plotter: the embedded one at the speed asked for, or a serial port, with the
/// request's plotter profile (the default plotter profile when it names none).
fn plotter_target(
    req: &OpenRequest,
    profile: &Profile,
) -> Result<(Target, Option<PlotterChoice>), PanelError> {
    let choice = match &req.plotter {
        Some(c) => c.clone(),
        None => PlotterChoice::new(None, profile, req.baud).map_err(PanelError::Bad)?,
    };
    if req.device == PLOTTER_SIM {
        let speed = req.speed.unwrap_or(DEFAULT_SIM_SPEED);
        if !(speed.is_finite() && speed > 0.0 && speed <= 1000.0) {
            return Err(PanelError::Bad(format!(
                "speed {speed}: the simulator's time scale is a number in (0, 1000]"
            )));
        }
        let t = Target::PlotterSim(PlotterSimSetup {
            link: choice.link,
            speed,
        });
        return Ok((t, Some(choice)));
    }
    if req.device.is_empty() || is_simulator(&req.device) {
        return Err(PanelError::Bad(format!(
            "{:?}: an HP-GL plotter is `{PLOTTER_SIM}` or a serial port",
            req.device
        )));
    }
    let t = Target::Plotter {
        path: req.device.clone(),
        link: choice.link,
    };
    Ok((t, Some(choice)))
}

/// Longest wait for a request that still uses a device being closed (a command's own timeout
/// bounds it) before the device is left to close when that request ends.
const CLOSE_WAIT: Duration = Duration::from_secs(30);

/// Closes a device no longer listed as open: a running job is stopped first (feed hold, soft
/// reset, tool off, journal written; a plot: `ESC.K`, pen up), then the link and the simulator,
/// whose record comes back. A request still using the device (a command under way) is waited
/// for up to [`CLOSE_WAIT`]; beyond, the device closes when that request lets go of it.
fn close_device(mut device: Arc<Device>) -> Closed {
    if device.is_busy() {
        let _ = device.stop();
    }
    let t0 = Instant::now();
    loop {
        match Arc::try_unwrap(device) {
            Ok(d) => return d.close(),
            Err(d) if t0.elapsed() < CLOSE_WAIT => {
                device = d;
                std::thread::sleep(Duration::from_millis(20));
            }
            Err(_) => return Closed::default(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_simulators_id_is_simulator_or_simulator_and_a_short_name() {
        for ok in [
            "simulator",
            "simulator:2",
            "simulator:knife_1",
            "simulator:a.b-c",
        ] {
            assert!(is_simulator(ok), "{ok}");
        }
        let long = format!("simulator:{}", "x".repeat(33));
        for no in [
            "simulator:",
            "simulator:a b",
            "/dev/ttyUSB0",
            "sim",
            long.as_str(),
        ] {
            assert!(!is_simulator(no), "{no}");
        }
        let dir = std::path::Path::new("/shop");
        let j = |d: &str| journal_path(dir, "job-2.gcode", d, "simulator");
        assert_eq!(j("simulator"), dir.join("job-2.gcode.journal"));
        assert_eq!(
            j("simulator:2"),
            dir.join("job-2.gcode@simulator-2.journal")
        );
        assert_eq!(
            j("/dev/ttyUSB0"),
            dir.join("job-2.gcode@dev-ttyUSB0.journal")
        );
    }
}
