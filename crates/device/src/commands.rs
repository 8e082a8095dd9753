//! What a device's handle and its worker say to each other: the requests (`Cmd`, `Op`), the
//! answers (`Reply`), the controls of the job running (`Running`), and what a closed device
//! leaves (`Closed`); shared by the GRBL worker (`device`) and the plotter's (`plot_worker`).

use crate::job::{JobOutcome, JobRequest};
use crate::plotter::{PlotOutcome, PlotRequest, PlotterReport};
use flatcut_firmware_sim::SimReport;
use flatcut_firmware_sim::hpgl::HpglPtySim;
use flatcut_grbl::hpgl::{HpglControl, HpglError};
use flatcut_grbl::{CancelToken, ControllerInfo, Jog, MachineStatus, SendError};
use std::sync::mpsc::Sender;

/// What a closed device leaves: the embedded simulator's trace, counters and simulated time,
/// or the embedded HP-GL plotter's strokes (`None` on a serial port).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Closed {
    /// The GRBL simulator's report.
    pub sim: Option<SimReport>,
    /// The HP-GL plotter simulator's report.
    pub plotter: Option<PlotterReport>,
}

/// Something asked of the controller between jobs.
pub(crate) enum Op {
    Connect,
    Status,
    Unlock,
    Home,
    Jog(Jog),
    JogCancel,
    Frame {
        lo: [f64; 2],
        hi: [f64; 2],
        feed: f64,
    },
    Command(String),
    SimReport,
}

impl Op {
    /// What the op is, for a plotter's refusal; `None` for what a plotter does too.
    pub(crate) fn grbl_only(&self) -> Option<&'static str> {
        Some(match self {
            Op::Connect => "connect handshake",
            Op::Status => "status report",
            Op::Unlock => "unlock ($X)",
            Op::Home => "homing ($H)",
            Op::Jog(_) | Op::JogCancel => "jog",
            Op::Frame { .. } => "frame",
            Op::Command(_) => "GRBL command",
            Op::SimReport => return None,
        })
    }
}

pub(crate) enum Reply {
    Info(ControllerInfo),
    Status(Option<MachineStatus>),
    Sim(Option<SimReport>),
    Done,
}

type JobDone = Sender<Result<JobOutcome, SendError>>;
type PlotDone = Sender<Result<PlotOutcome, HpglError>>;

pub(crate) enum Cmd {
    Op(Op, Sender<Result<Reply, SendError>>),
    Job(Box<JobRequest>, JobDone),
    Plot(Box<PlotRequest>, PlotDone),
    Close,
}

/// The controls of the job running: a G-code job's or a plot's.
#[derive(Debug, Clone)]
pub(crate) enum Running {
    Grbl(CancelToken),
    Plot(HpglControl),
}

impl Running {
    pub(crate) fn hold(&self) {
        match self {
            Running::Grbl(c) => c.hold(),
            Running::Plot(c) => c.pause(),
        }
    }
    pub(crate) fn resume(&self) {
        match self {
            Running::Grbl(c) => c.resume(),
            Running::Plot(c) => c.resume(),
        }
    }
    pub(crate) fn abort(&self) {
        match self {
            Running::Grbl(c) => c.abort(),
            Running::Plot(c) => c.abort(),
        }
    }
}

/// What the embedded HP-GL plotter drew so far.
pub(crate) fn plotter_report(s: &HpglPtySim) -> PlotterReport {
    PlotterReport {
        strokes: s.trace(),
        stats: s.stats(),
        pen_down: s.pen_down(),
        idle: s.idle(),
    }
}
