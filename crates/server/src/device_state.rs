//! The device panel's shared state: the devices open (by id) with their link, controller, status
//! and job slot, the jobs with their live state, the default device, what closed simulators
//! executed; behind one lock, with the events every page hears. `devices` changes it on the
//! pages' requests, `device_watch` on the devices' events.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, MutexGuard};

use flatcut_device::grbl::hpgl::HpglControl;
use flatcut_device::grbl::{CancelToken, Job};
use flatcut_device::sim::SimReport;
use flatcut_device::{Asked, Device, DeviceError, PlotterReport};
use serde_json::{Value as Json, json};

use crate::device_views::question_view;
use crate::events::Events;
use crate::plotters::PlotterChoice;

/// The controls of a job: a G-code job's (feed hold, cycle start, stop with the tool off) or a
/// plot's (pause at an instruction boundary with the pen up, resume, `ESC.K` and pen up).
#[derive(Clone, Debug)]
pub(crate) enum JobControl {
    Grbl(CancelToken),
    Plot(HpglControl),
}

impl JobControl {
    pub(crate) fn hold(&self) {
        match self {
            JobControl::Grbl(c) => c.hold(),
            JobControl::Plot(c) => c.pause(),
        }
    }
    pub(crate) fn resume(&self) {
        match self {
            JobControl::Grbl(c) => c.resume(),
            JobControl::Plot(c) => c.resume(),
        }
    }
    pub(crate) fn abort(&self) {
        match self {
            JobControl::Grbl(c) => c.abort(),
            JobControl::Plot(c) => c.abort(),
        }
    }
    /// A plot whose pause is asked for (and not yet resumed).
    pub(crate) fn pause_asked(&self) -> bool {
        matches!(self, JobControl::Plot(c) if c.is_paused())
    }
}

/// What a job is doing, as the page shows it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JobState {
    /// Lines are streaming.
    Running,
    /// Feed hold asked for by the operator.
    Held,
    /// The job paused itself (`M0`) and waits.
    Paused,
    /// A question waits for the operator's answer.
    Asking,
    /// Every line ran; the job ended well.
    Done,
    /// The job ended on an error (the record's `message` says which).
    Failed,
    /// Stopped by the operator (or the server stopping): tool off, journal written.
    Stopped,
}

impl JobState {
    /// The state's lowercase name in the JSON (`running`, `held`, …).
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

    /// True for the final states: done, failed, stopped.
    pub fn ended(self) -> bool {
        matches!(self, JobState::Done | JobState::Failed | JobState::Stopped)
    }
}

/// One job streamed from the workbench.
pub struct JobRecord {
    /// The job's number: 1 for the first, one more than the last job's for each next.
    pub id: u64,
    /// Its file name as `flatcut run` writes it (`job-1.gcode`).
    pub name: String,
    /// The sheet it cuts (1-based).
    pub sheet: usize,
    /// The design revision its G-code was made from.
    pub revision: u64,
    /// How messages name its device (`the embedded simulator (…)`, `/dev/ttyUSB0 at 115200 baud`).
    pub device: String,
    /// Its device's id (`simulator`, a port's path).
    pub device_id: String,
    /// The journal file the job writes (and resumes from); `None` for a plot (HP-GL has no
    /// acknowledgements to journal).
    pub journal: Option<PathBuf>,
    /// `grbl` (G-code) or `hpgl` (a plot).
    pub protocol: &'static str,
    /// Whether the job was started as a resume (from its journal, or from `resume_from`).
    pub resume: bool,
    /// The line of the file the operator resumed from (1-based).
    pub resume_from: Option<usize>,
    /// What the job is doing.
    pub state: JobState,
    /// The latest progress event's JSON (lines, path, ETA, position); `None` before the first.
    pub progress: Option<Json>,
    /// The controller's and sender's notices so far, in order.
    pub notices: Vec<String>,
    /// The question waiting for the operator's answer, if any.
    pub question: Option<Asked>,
    /// The latest word for the page: why it paused, `complete`, or the error that ended it.
    pub message: String,
    /// The send report's JSON once the job has ended well.
    pub report: Option<Json>,
    /// The lines a refused resume could not tell ran or not: the page
    /// asks for the line to continue from.
    pub in_doubt: Option<Json>,
    /// The job as parsed (what the lines in doubt are, and where); `None` for a plot.
    pub(crate) job: Option<Arc<Job>>,
    /// Wall-clock seconds per second of machine time (for the ETA), `None`: instant motion.
    pub(crate) wall_per_machine_s: Option<f64>,
    pub(crate) control: JobControl,
    pub(crate) stop_asked: bool,
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
            "device_id": self.device_id,
            "journal": self.journal.as_ref().map(|j| j.display().to_string()),
            "protocol": self.protocol,
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

/// One device open.
pub(crate) struct OpenDevice {
    /// Its id: `simulator`, `simulator:<name>` or the port's path.
    pub(crate) id: String,
    /// Which opening this is (its watcher's events belong to it).
    pub(crate) generation: u64,
    pub(crate) device: Arc<Device>,
    pub(crate) controller: Option<Json>,
    pub(crate) status: Option<Json>,
    /// The simulator's time scale (`None` on a port).
    pub(crate) speed: Option<f64>,
    /// The job running on it.
    pub(crate) job: Option<u64>,
    /// An HP-GL plotter's profile and link (`None`: a GRBL device).
    pub(crate) plotter: Option<PlotterChoice>,
}

impl OpenDevice {
    /// The device as `/api/devices` and the `device` event give it.
    pub(crate) fn view(&self, what: &str) -> Json {
        json!({
            "event": what,
            "open": true,
            "id": self.id,
            "description": self.device.target().describe(),
            "link": self.device.link(),
            "busy": self.job.is_some(),
            "job": self.job,
            "speed": self.speed,
            "controller": self.controller,
            "status": self.status,
            "protocol": if self.plotter.is_some() { "hpgl" } else { "grbl" },
            "plotter": self.plotter.as_ref().map(PlotterChoice::view),
        })
    }
}

#[derive(Default)]
pub(crate) struct Inner {
    /// The devices open, by id.
    pub(crate) open: BTreeMap<String, OpenDevice>,
    /// The default device: opened or connected last (and still open).
    pub(crate) default: Option<String>,
    pub(crate) jobs: BTreeMap<u64, JobRecord>,
    /// What each embedded simulator closed had executed, by id, and which closed last.
    pub(crate) last_sim: BTreeMap<String, SimReport>,
    /// What each embedded HP-GL plotter closed had drawn, by id.
    pub(crate) last_plotter: BTreeMap<String, PlotterReport>,
    pub(crate) last_closed: Option<String>,
    /// Openings so far.
    pub(crate) generations: u64,
}

impl Inner {
    /// A device that is gone from the list: the default moves to the device opened last.
    pub(crate) fn forget(&mut self, id: &str) -> Option<OpenDevice> {
        let o = self.open.remove(id);
        if self.default.as_deref() == Some(id) {
            self.default = self
                .open
                .values()
                .max_by_key(|o| o.generation)
                .map(|o| o.id.clone());
        }
        o
    }

    /// The open device a request names, or the default one.
    pub(crate) fn resolve(&self, id: Option<&str>) -> Result<&OpenDevice, PanelError> {
        match id {
            Some(id) => self
                .open
                .get(id)
                .ok_or_else(|| PanelError::NotOpenId(id.to_string())),
            None => self
                .default
                .as_ref()
                .and_then(|d| self.open.get(d))
                .ok_or(PanelError::NotOpen),
        }
    }
}

/// The shared state: behind a lock, and the events every page hears.
pub(crate) struct Shared {
    pub(crate) inner: Mutex<Inner>,
    pub(crate) events: Events,
}

impl Shared {
    pub(crate) fn lock(&self) -> MutexGuard<'_, Inner> {
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }

    pub(crate) fn publish_job(&self, inner: &Inner, id: u64) {
        if let Some(j) = inner.jobs.get(&id) {
            self.events.publish("job", j.view());
        }
    }

    /// Tells every page of device `id`'s state (`what` happened).
    pub(crate) fn publish_device(&self, inner: &Inner, id: &str, what: &str) {
        let v = match inner.open.get(id) {
            Some(o) => o.view(what),
            None => closed_view(id, what, None),
        };
        self.events.publish("device", v);
    }
}

/// A device that is not open, as the `device` event tells it.
pub(crate) fn closed_view(id: &str, what: &str, message: Option<&str>) -> Json {
    json!({ "event": what, "open": false, "id": id, "job": Json::Null, "message": message })
}

/// Why the device panel could not do what it was asked.
#[derive(Debug, thiserror::Error)]
pub enum PanelError {
    /// The device session refused or failed.
    #[error(transparent)]
    Device(#[from] DeviceError),
    /// A job is running: nothing else but hold, resume, stop and answers.
    #[error("{0}")]
    Busy(String),
    /// The request is wrong (an unknown device, a missing job file); the message says how.
    #[error("{0}")]
    Bad(String),
    /// No device is open and the request needs one.
    #[error("no device is open: connect one first")]
    NotOpen,
    /// The device named by its id is not open.
    #[error("the device {0} is not open: connect it first")]
    NotOpenId(String),
    /// No job has this number.
    #[error("no job {0}")]
    NoJob(u64),
}
