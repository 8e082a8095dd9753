//! [`Device`]: one open device — a serial port, or the embedded simulator on its pseudo-terminal —
//! with a worker thread that owns the link. Every request goes to the worker in order; the
//! handle can be shared between threads (a web server's handlers, a terminal's signal thread).
//! One job at a time: while a job runs the device takes nothing else but hold, resume, stop
//! and the operator's answers.
//!
//! The worker touches the link only when asked: a job sent right after opening runs the
//! sender's own handshake (which sees the banner of a controller that resets as the port opens),
//! and only an explicit [`Device::connect`] (or a job) starts the status polling between jobs.

use crate::commands::{Closed, Cmd, Op, Reply, Running, plotter_report};
use crate::embedded::SimSetup;
use crate::error::DeviceError;
use crate::events::{DeviceEvent, Hub, Subscription};
use crate::job::{JobHandle, JobOutcome, JobRequest};
use crate::operator::Questions;
use crate::plot_worker::PlotWorker;
use crate::plotter::{PlotHandle, PlotRequest, PlotterReport, PlotterSimSetup};
use crate::target::Target;
use flatcut_firmware_sim::hpgl::HpglPtySim;
use flatcut_firmware_sim::{PtySim, SimReport};
use flatcut_grbl::hpgl::HpglFlow;
use flatcut_grbl::{
    Console, ControllerInfo, Jog, MachineStatus, Progress, SendError, SendOptions, SerialTransport,
};
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender, channel};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::Duration;

/// How a device works between jobs.
#[derive(Debug, Clone, PartialEq)]
pub struct DeviceOptions {
    /// Waits and timeouts of what is done between jobs: the banner wait when connecting, each
    /// command's timeout, the status interval.
    pub console: SendOptions,
    /// Ask for a status this often between jobs once connected (`None`: only when asked).
    pub poll: Option<Duration>,
}

impl Default for DeviceOptions {
    fn default() -> DeviceOptions {
        DeviceOptions {
            console: SendOptions::default(),
            poll: Some(SendOptions::DEFAULT_STATUS_INTERVAL),
        }
    }
}

/// An open device; see the module docs.
#[derive(Debug)]
pub struct Device {
    target: Target,
    link: String,
    tx: Sender<Cmd>,
    hub: Arc<Hub>,
    questions: Arc<Questions>,
    running: Arc<Mutex<Option<Running>>>,
    worker: Mutex<Option<JoinHandle<Closed>>>,
    /// The embedded HP-GL plotter, shared with the worker.
    plotter_sim: Option<Arc<HpglPtySim>>,
}

impl Device {
    /// Opens `target` with default options; see [`Device::open_with`].
    pub fn open(target: Target) -> Result<Device, DeviceError> {
        Device::open_with(target, DeviceOptions::default())
    }

    /// Opens `target`: checks it (a port that exists, a valid simulator set-up), starts the
    /// embedded simulator if it is one, opens the link and starts the worker. Nothing is sent
    /// to the controller yet.
    pub fn open_with(target: Target, opts: DeviceOptions) -> Result<Device, DeviceError> {
        target.check()?;
        if matches!(target, Target::Plotter { .. } | Target::PlotterSim(_)) {
            return Device::open_plotter(target);
        }
        let (sim, path) = match &target {
            Target::Simulator(s) => {
                let sim = spawn_sim(s)?;
                let p = sim.path().display().to_string();
                (Some(sim), p)
            }
            t => (None, t.path().unwrap_or_default().to_string()),
        };
        let link = open_link(&path, target.baud())?;
        let hub = Arc::new(Hub::default());
        let questions = Arc::new(Questions::default());
        let running = Arc::new(Mutex::new(None));
        let (tx, rx) = channel();
        let worker = Worker {
            console: Console::new(Box::new(link)),
            sim,
            hub: hub.clone(),
            questions: questions.clone(),
            running: running.clone(),
            opts,
            restarted: false,
        };
        let handle = std::thread::Builder::new()
            .name("flatcut-device".into())
            .spawn(move || worker.run(rx))
            .map_err(DeviceError::Simulator)?;
        Ok(Device {
            target,
            link: path,
            tx,
            hub,
            questions,
            running,
            worker: Mutex::new(Some(handle)),
            plotter_sim: None,
        })
    }

    /// Opens an HP-GL plotter: the embedded one started on its pseudo-terminal, the link opened
    /// with the profile's flow control (RTS/CTS set on the port), the worker started.
    fn open_plotter(target: Target) -> Result<Device, DeviceError> {
        let (sim, path, link) = match &target {
            Target::PlotterSim(s) => {
                let sim = Arc::new(spawn_plotter(s)?);
                let p = sim.path().display().to_string();
                (Some(sim), p, s.link)
            }
            Target::Plotter { path, link } => (None, path.clone(), *link),
            _ => unreachable!("a plotter target"),
        };
        let mut port = open_link(&path, link.baud)?;
        if link.flow == HpglFlow::RtsCts {
            port.port_mut()
                .set_flow_control(serialport::FlowControl::Hardware)
                .map_err(|e| DeviceError::Open {
                    path: path.clone(),
                    source: flatcut_grbl::TransportError::Open {
                        path: path.clone(),
                        reason: format!("cannot enable RTS/CTS: {e}"),
                    },
                })?;
        }
        let hub = Arc::new(Hub::default());
        let running = Arc::new(Mutex::new(None));
        let (tx, rx) = channel();
        let worker = PlotWorker {
            port,
            sim: sim.clone(),
            hub: hub.clone(),
            running: running.clone(),
            link,
        };
        let handle = std::thread::Builder::new()
            .name("flatcut-plotter".into())
            .spawn(move || worker.run(rx))
            .map_err(DeviceError::Simulator)?;
        Ok(Device {
            target,
            link: path,
            tx,
            hub,
            questions: Arc::new(Questions::default()),
            running,
            worker: Mutex::new(Some(handle)),
            plotter_sim: sim,
        })
    }

    /// What was opened.
    pub fn target(&self) -> &Target {
        &self.target
    }

    /// The path of the link: the serial port, or the embedded simulator's pseudo-terminal
    /// (which another sender could open while this device is closed).
    pub fn link(&self) -> &str {
        &self.link
    }

    /// Watches the device from now on: every event, in order (see [`DeviceEvent`]).
    pub fn subscribe(&self) -> Subscription {
        self.hub.subscribe()
    }

    fn running(&self) -> MutexGuard<'_, Option<Running>> {
        self.running.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn closed(&self) -> DeviceError {
        DeviceError::Closed {
            device: self.target.describe(),
        }
    }

    /// Asks the worker to do `op` and waits for it; refused while a job runs.
    fn op(&self, op: Op) -> Result<Reply, DeviceError> {
        if let Some(what) = op.grbl_only().filter(|_| self.target.is_plotter()) {
            return Err(DeviceError::NotGrbl {
                device: self.target.describe(),
                what,
            });
        }
        let (tx, rx) = channel();
        {
            let running = self.running();
            if running.is_some() {
                return Err(DeviceError::Busy {
                    device: self.target.describe(),
                });
            }
            self.tx.send(Cmd::Op(op, tx)).map_err(|_| self.closed())?;
        }
        match rx.recv() {
            Ok(r) => Ok(r?),
            Err(_) => Err(self.closed()),
        }
    }

    /// Connects to the controller (its banner, `$I`, `$$`, a status) and starts the status
    /// polling between jobs ([`DeviceEvent::Status`]).
    pub fn connect(&self) -> Result<ControllerInfo, DeviceError> {
        match self.op(Op::Connect)? {
            Reply::Info(i) => Ok(i),
            _ => Err(self.closed()),
        }
    }

    /// The controller's state and position now.
    pub fn status(&self) -> Result<Option<MachineStatus>, DeviceError> {
        match self.op(Op::Status)? {
            Reply::Status(s) => Ok(s),
            _ => Err(self.closed()),
        }
    }

    /// Clears an alarm lock (`$X`): only when the machine position is known to be right.
    pub fn unlock(&self) -> Result<(), DeviceError> {
        self.op(Op::Unlock).map(|_| ())
    }

    /// Homes the machine (`$H`, where `$22=1`).
    pub fn home(&self) -> Result<(), DeviceError> {
        self.op(Op::Home).map(|_| ())
    }

    /// Starts a jog; [`Device::jog_cancel`] stops it.
    pub fn jog(&self, jog: Jog) -> Result<(), DeviceError> {
        self.op(Op::Jog(jog)).map(|_| ())
    }

    /// Stops a jog at once.
    pub fn jog_cancel(&self) -> Result<(), DeviceError> {
        self.op(Op::JogCancel).map(|_| ())
    }

    /// Traces the rectangle `lo`..`hi` (work X, Y in mm) with the tool off at `feed` mm/min and
    /// returns to where the machine stood: where a job will cut (see
    /// [`flatcut_grbl::Job::extent`]).
    pub fn frame(&self, lo: [f64; 2], hi: [f64; 2], feed: f64) -> Result<(), DeviceError> {
        self.op(Op::Frame { lo, hi, feed }).map(|_| ())
    }

    /// Sends one line (a `$` command, a G-code line) and waits for its `ok`.
    pub fn command(&self, line: &str) -> Result<(), DeviceError> {
        self.op(Op::Command(line.to_string())).map(|_| ())
    }

    /// What the embedded simulator executed so far (its trace, counters and simulated time)
    /// without closing it, as [`Device::close`] gives it at the end; `None` on a serial port.
    /// Refused while a job runs.
    pub fn sim_report(&self) -> Result<Option<SimReport>, DeviceError> {
        match self.op(Op::SimReport)? {
            Reply::Sim(r) => Ok(r),
            _ => Err(self.closed()),
        }
    }

    /// What the embedded HP-GL plotter drew so far (its strokes, counters, pen), as
    /// [`Device::close`] gives it at the end; `None` on a serial port or a GRBL device. Read from
    /// the simulator itself, so also while a job runs.
    pub fn plotter_report(&self) -> Option<PlotterReport> {
        self.plotter_sim.as_deref().map(plotter_report)
    }

    /// Starts streaming an HP-GL job to a plotter; refused while another runs, and on a GRBL
    /// device. Its progress ([`DeviceEvent::Plot`]: bytes sent, never what was drawn) and its
    /// end come as events; [`PlotHandle::wait`] gives its end. [`Device::hold`] pauses it at an
    /// instruction boundary with the pen lifted, [`Device::resume`] puts the pen back and goes
    /// on, [`Device::stop`] makes the device drop its buffer (`ESC.K`) and lift the pen.
    pub fn start_plot(&self, req: PlotRequest) -> Result<PlotHandle, DeviceError> {
        if !self.target.is_plotter() {
            return Err(DeviceError::NotPlotter {
                device: self.target.describe(),
            });
        }
        let mut running = self.running();
        if running.is_some() {
            return Err(DeviceError::Busy {
                device: self.target.describe(),
            });
        }
        let (tx, rx) = channel();
        let control = req.control.clone();
        self.tx
            .send(Cmd::Plot(Box::new(req), tx))
            .map_err(|_| self.closed())?;
        *running = Some(Running::Plot(control.clone()));
        Ok(PlotHandle { control, done: rx })
    }

    /// Starts a job; refused while another runs. Its progress, notices, pauses and questions
    /// come as events; [`JobHandle::wait`] gives its end.
    pub fn start(&self, req: JobRequest) -> Result<JobHandle, DeviceError> {
        if self.target.is_plotter() {
            return Err(DeviceError::NotGrbl {
                device: self.target.describe(),
                what: "G-code job",
            });
        }
        let mut running = self.running();
        if running.is_some() {
            return Err(DeviceError::Busy {
                device: self.target.describe(),
            });
        }
        let (tx, rx) = channel();
        let control = req.control.clone();
        self.tx
            .send(Cmd::Job(Box::new(req), tx))
            .map_err(|_| self.closed())?;
        *running = Some(Running::Grbl(control.clone()));
        Ok(JobHandle { control, done: rx })
    }

    /// Whether a job is running.
    pub fn is_busy(&self) -> bool {
        self.running().is_some()
    }

    fn with_job(&self, f: impl FnOnce(&Running)) -> Result<(), DeviceError> {
        match self.running().as_ref() {
            Some(c) => {
                f(c);
                Ok(())
            }
            None => Err(DeviceError::NoJob {
                device: self.target.describe(),
            }),
        }
    }

    /// Holds the running job's feed (`!`); a plot pauses at an instruction boundary, pen up.
    pub fn hold(&self) -> Result<(), DeviceError> {
        self.with_job(Running::hold)
    }

    /// Resumes the running job after a hold or its own pause (`~`); a plot's pen goes back
    /// down if it was.
    pub fn resume(&self) -> Result<(), DeviceError> {
        self.with_job(Running::resume)
    }

    /// Stops the running job: feed hold, soft reset, tool off; the journal says what ran. An
    /// open question is answered no. A plot: `ESC.K` (the device drops its buffer) and `PU;`.
    pub fn stop(&self) -> Result<(), DeviceError> {
        self.with_job(Running::abort)
    }

    /// Answers the question numbered `id` ([`DeviceEvent::Question`]).
    pub fn answer(&self, id: u64, yes: bool) -> Result<(), DeviceError> {
        if self.questions.answer(id, yes) {
            Ok(())
        } else {
            Err(DeviceError::NoQuestion(id))
        }
    }

    /// Closes the device: stops a running job (its questions answered no), closes the link,
    /// stops the embedded simulator and returns what it recorded.
    pub fn close(self) -> Closed {
        self.shutdown()
    }

    fn shutdown(&self) -> Closed {
        if let Some(c) = self.running().as_ref() {
            c.abort();
        }
        self.questions.withdraw_all();
        let _ = self.tx.send(Cmd::Close);
        let handle = self.worker.lock().unwrap_or_else(|p| p.into_inner()).take();
        let Some(handle) = handle else {
            return Closed::default();
        };
        let closed = handle.join().unwrap_or_default();
        self.hub.close("the device was closed");
        closed
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        self.shutdown();
    }
}

fn spawn_sim(s: &SimSetup) -> Result<PtySim, DeviceError> {
    PtySim::spawn(s.config()?).map_err(DeviceError::Simulator)
}

fn spawn_plotter(s: &PlotterSimSetup) -> Result<HpglPtySim, DeviceError> {
    HpglPtySim::spawn(s.config(), s.link.baud, s.speed).map_err(DeviceError::Simulator)
}

fn open_link(path: &str, baud: u32) -> Result<SerialTransport, DeviceError> {
    flatcut_grbl::open_port(path, baud).map_err(|source| DeviceError::Open {
        path: path.to_string(),
        source,
    })
}

/// The thread that owns the link.
struct Worker {
    console: Console,
    sim: Option<PtySim>,
    hub: Arc<Hub>,
    questions: Arc<Questions>,
    running: Arc<Mutex<Option<Running>>>,
    opts: DeviceOptions,
    /// A restart was already published.
    restarted: bool,
}

impl Worker {
    fn run(mut self, rx: Receiver<Cmd>) -> Closed {
        loop {
            let wait = self.opts.poll.unwrap_or(Duration::from_secs(3600));
            match rx.recv_timeout(wait) {
                Ok(Cmd::Op(op, reply)) => {
                    let r = self.op(op);
                    let _ = reply.send(r);
                }
                Ok(Cmd::Job(req, done)) => {
                    let r = self.job(*req);
                    let _ = done.send(r);
                }
                // A plot is refused before it reaches a GRBL device's worker.
                Ok(Cmd::Plot(..)) => {}
                Ok(Cmd::Close) | Err(RecvTimeoutError::Disconnected) => break,
                Err(RecvTimeoutError::Timeout) => self.poll(),
            }
            self.tell_restart();
        }
        let Worker { console, sim, .. } = self;
        // The link closes first: a simulator stopped under an open port looks unplugged.
        drop(console);
        Closed {
            sim: sim.map(PtySim::stop),
            plotter: None,
        }
    }

    fn poll(&mut self) {
        if self.opts.poll.is_none() || !self.console.is_connected() {
            return;
        }
        if let Ok(Some(s)) = self.console.status(self.opts.console.command_timeout) {
            self.hub.publish(DeviceEvent::Status(s));
        }
    }

    /// Publishes a restart the console noticed, once.
    fn tell_restart(&mut self) {
        let now = self.console.restarted();
        if now && !self.restarted {
            self.hub.publish(DeviceEvent::Restarted);
        }
        self.restarted = now;
    }

    fn op(&mut self, op: Op) -> Result<Reply, SendError> {
        let o = &self.opts.console;
        let c = &mut self.console;
        Ok(match op {
            Op::Connect => {
                let info = c.connect(o)?;
                self.hub.publish(DeviceEvent::Connected(info.clone()));
                Reply::Info(info)
            }
            Op::Status => Reply::Status(c.status(o.command_timeout)?),
            Op::Unlock => {
                c.unlock(o)?;
                Reply::Done
            }
            Op::Home => {
                c.home()?;
                Reply::Done
            }
            Op::Jog(j) => {
                c.jog(&j, o)?;
                Reply::Done
            }
            Op::JogCancel => {
                c.jog_cancel()?;
                Reply::Done
            }
            Op::Frame { lo, hi, feed } => {
                c.frame(lo, hi, feed, o)?;
                Reply::Done
            }
            Op::Command(line) => {
                c.command(&line, o.command_timeout)?;
                Reply::Done
            }
            Op::SimReport => Reply::Sim(self.sim.as_ref().map(|s| SimReport {
                trace: s.trace(),
                stats: s.stats(),
                sim_time: s.sim_time(),
            })),
        })
    }

    fn job(&mut self, req: JobRequest) -> Result<JobOutcome, SendError> {
        let hub = self.hub.clone();
        hub.publish(DeviceEvent::JobStarted {
            name: req.name.clone(),
        });
        let mut opts = req.options.clone();
        if req.ask {
            let o = self.questions.operator(hub.clone(), req.control.clone());
            opts = opts.with_operator(Some(o));
        }
        let mut told = 0;
        let mut paused: Option<usize> = None;
        let mut observer = |p: &Progress| {
            for n in p.notices.iter().skip(told) {
                hub.publish(DeviceEvent::Notice(n.clone()));
            }
            told = told.max(p.notices.len());
            match &p.paused_at {
                Some(l) if paused != Some(l.index) => {
                    paused = Some(l.index);
                    hub.publish(DeviceEvent::Paused(l.clone()));
                }
                None => paused = None,
                Some(_) => {}
            }
            hub.publish(DeviceEvent::Progress(Box::new(p.clone())));
        };
        let r = self
            .console
            .run_job(&req.job, &opts, &mut observer, &req.control);
        *self.running.lock().unwrap_or_else(|p| p.into_inner()) = None;
        self.hub.publish(DeviceEvent::JobFinished {
            name: req.name.clone(),
            ok: r.is_ok(),
            message: match &r {
                Ok(_) => "complete".into(),
                Err(e) => e.to_string(),
            },
        });
        r.map(|report| JobOutcome {
            name: req.name,
            report,
        })
    }
}
