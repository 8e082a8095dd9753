//! flatcut-device: the device session that the command line and the workbench server share —
//! choosing a device, the embedded simulator as a device, streaming jobs from memory with the
//! journal and resume, the operator's questions, and events for whoever watches.
//!
//! * [`list`] names the devices an operator can choose: the serial ports, and the embedded
//!   GRBL simulator, which is always there. A [`Target`] is one of them; [`Target::check`] says
//!   before any work starts whether it can be opened (a port that is not there is found then).
//! * [`Device::open`] opens one (starting the simulator on its own pseudo-terminal, set up as
//!   the machine a profile describes: [`SimSetup`], [`SimMachine`]). A worker thread owns the
//!   link; the handle is shared between threads.
//! * Between jobs: [`Device::connect`], [`Device::status`], [`Device::unlock`],
//!   [`Device::home`], [`Device::jog`] / [`Device::jog_cancel`], [`Device::frame`],
//!   [`Device::command`].
//! * Jobs: [`Device::start`] takes a [`JobRequest`] (a parsed G-code job held in memory and the
//!   sender's options: journal, resume, policies) and returns a [`JobHandle`]; one job at a time
//!   ([`DeviceError::Busy`]). [`Device::hold`], [`Device::resume`], [`Device::stop`] steer it.
//! * Events: [`Device::subscribe`] gives a [`Subscription`] of [`DeviceEvent`]s — progress
//!   (lines, path done, ETA, state, live position), status between jobs, notices, the job's own
//!   pauses, restarts, the job's end. A subscriber that falls behind never holds the device up.
//! * HP-GL plotters and vinyl cutters: [`Target::Plotter`] (a serial port with the profile's
//!   flow control: [`PlotterLink`]) and [`Target::PlotterSim`] (the embedded HP-GL plotter,
//!   which records its pen strokes: [`PlotterReport`]). [`Device::start_plot`] streams HP-GL
//!   bytes ([`PlotRequest`]); [`Device::hold`] pauses at an instruction boundary with the pen
//!   lifted, [`Device::resume`] puts it back, [`Device::stop`] sends `ESC.K` and `PU;`. Progress
//!   is [`DeviceEvent::Plot`]: bytes the link accepted, never what was drawn (HP-GL has no
//!   acknowledgements). GRBL's commands (connect, unlock, home, jog, frame) are refused.
//! * The operator's questions (a resume whose machine position is unknown, a job file edited
//!   since its journal): with [`JobRequest::ask`] they come as [`DeviceEvent::Question`] and the
//!   job waits for [`Device::answer`]; a stop answers no.
//! * Signals are the embedding program's: a terminal's Ctrl-C handler, or a server's stop
//!   button, calls [`Device::hold`] and [`Device::stop`] (or a job's [`JobHandle::control`]).
//!
//! A job on the embedded simulator, watched through events:
//!
//! ```
//! use flatcut_device::{Device, DeviceEvent, JobRequest, SimSetup, Target};
//!
//! let target = Target::Simulator(SimSetup::default().with_instant(true));
//! let device = Device::open(target)?;
//! let events = device.subscribe();
//! let job = JobRequest::parse("square", "G21 G90\nG1 X10 F600\nG1 Y10\nG1 X0\nG1 Y0\n")?;
//! let handle = device.start(job)?;
//! // Another job is refused while this one runs.
//! assert!(device.start(JobRequest::parse("again", "G0 X1\n")?).is_err());
//! let mut ended = false;
//! while let Some(e) = events.recv() {
//!     match e {
//!         DeviceEvent::Progress(p) => assert!(p.fraction() <= 1.0),
//!         DeviceEvent::JobFinished { ok, .. } => {
//!             ended = ok;
//!             break;
//!         }
//!         _ => {}
//!     }
//! }
//! assert!(ended);
//! let outcome = handle.wait()?;
//! assert_eq!(outcome.report.lines_sent, 5);
//! // Closing stops the simulator: its trace is what the machine did.
//! let sim = device.close().sim.expect("the simulator's report");
//! assert_eq!(sim.trace.len(), 4);
//! assert_eq!(sim.trace[3].to, [0.0, 0.0, 0.0]);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! **Architecture invariant:** depends on the sender (`flatcut-grbl`), the simulator and the
//! motion model only — never on the G-code writer: it streams any G-code. It writes no file
//! but the journal the options name, and owns no process-wide state (no signal handler).
#![warn(missing_docs)]

mod commands;
mod device;
mod embedded;
mod error;
mod events;
mod job;
mod operator;
mod plot_worker;
mod plotter;
mod target;

pub use commands::Closed;
pub use device::{Device, DeviceOptions};
pub use embedded::{SimMachine, SimSetup};
pub use error::DeviceError;
pub use events::{Asked, DeviceEvent, Subscription};
pub use job::{JobHandle, JobOutcome, JobRequest};
pub use plotter::{
    PlotHandle, PlotOutcome, PlotProgress, PlotRequest, PlotterLink, PlotterReport, PlotterSimSetup,
};
pub use target::{DeviceInfo, Target, list};

/// The simulator (its trace, counters, configuration and faults).
pub use flatcut_firmware_sim as sim;
/// The sender: jobs, options, progress, the journal, errors.
pub use flatcut_grbl as grbl;
