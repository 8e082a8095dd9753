//! The thread that owns an HP-GL device's link: it streams one plot at a time
//! ([`flatcut_grbl::hpgl::stream_hpgl_steered`]), publishes its progress (at most every
//! [`TICK`], and at once when it pauses, holds or ends), and on the embedded plotter waits for
//! the pen to finish what it received before the job ends.

use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use flatcut_firmware_sim::hpgl::HpglPtySim;
use flatcut_grbl::SerialTransport;
use flatcut_grbl::hpgl::{ABORT, HpglError, HpglProgress, stream_hpgl_steered};
use flatcut_grbl::{Transport, TransportError};

use crate::commands::{Closed, Cmd, Op, Reply, Running, plotter_report};
use crate::events::{DeviceEvent, Hub};
use crate::plotter::{PlotOutcome, PlotProgress, PlotRequest, PlotterLink};

/// Shortest interval between two progress events of a plot.
const TICK: Duration = Duration::from_millis(50);
/// Longest wait for the embedded plotter to draw what it received.
const DRAIN_LIMIT: Duration = Duration::from_secs(600);

pub(crate) struct PlotWorker {
    pub(crate) port: SerialTransport,
    pub(crate) sim: Option<Arc<HpglPtySim>>,
    pub(crate) hub: Arc<Hub>,
    pub(crate) running: Arc<Mutex<Option<Running>>>,
    pub(crate) link: PlotterLink,
}

impl PlotWorker {
    pub(crate) fn run(mut self, rx: Receiver<Cmd>) -> Closed {
        loop {
            match rx.recv_timeout(Duration::from_secs(3600)) {
                Ok(Cmd::Op(op, reply)) => {
                    // The device refuses GRBL's commands before they reach a plotter's worker.
                    let r = match op {
                        Op::SimReport => Ok(Reply::Sim(None)),
                        _ => Ok(Reply::Done),
                    };
                    let _ = reply.send(r);
                }
                Ok(Cmd::Plot(req, done)) => {
                    let r = self.plot(*req);
                    let _ = done.send(r);
                }
                // A G-code job is refused before it reaches a plotter's worker.
                Ok(Cmd::Job(..)) => {}
                Ok(Cmd::Close) | Err(RecvTimeoutError::Disconnected) => break,
                Err(RecvTimeoutError::Timeout) => {}
            }
        }
        let PlotWorker { port, sim, .. } = self;
        // The link closes first, then the plotter's last word is taken (the device's handle
        // stops it when dropped).
        drop(port);
        Closed {
            sim: None,
            plotter: sim.as_deref().map(plotter_report),
        }
    }

    fn plot(&mut self, req: PlotRequest) -> Result<PlotOutcome, HpglError> {
        let hub = self.hub.clone();
        hub.publish(DeviceEvent::JobStarted {
            name: req.name.clone(),
        });
        let mut clock = Clock::new();
        let mut observer = |p: HpglProgress| {
            if let Some(e) = clock.tick(&p) {
                hub.publish(DeviceEvent::Plot(e));
            }
        };
        let opts = self.link.stream_options();
        let streamed = stream_hpgl_steered(
            &mut self.port,
            &req.bytes,
            &opts,
            &req.control,
            &mut observer,
        );
        let r = match streamed {
            Ok(report) => {
                let last = HpglProgress {
                    sent: req.bytes.len(),
                    total: req.bytes.len(),
                    held: false,
                    paused: false,
                    pen_down: false,
                    device_free: None,
                };
                clock.last = None;
                if let Some(e) = clock.tick(&last) {
                    hub.publish(DeviceEvent::Plot(e));
                }
                self.drain(&req).map(|()| report)
            }
            Err(e) => Err(e),
        };
        *self.running.lock().unwrap_or_else(|p| p.into_inner()) = None;
        hub.publish(DeviceEvent::JobFinished {
            name: req.name.clone(),
            ok: r.is_ok(),
            message: match &r {
                Ok(_) => "complete".into(),
                Err(e) => e.to_string(),
            },
        });
        r.map(|report| PlotOutcome {
            name: req.name,
            report,
        })
    }

    /// On the embedded plotter: waits until it has drawn everything it received, so that the
    /// job ends when the pen does; a stop meanwhile aborts as during the stream (`ESC.K`, `PU;`).
    fn drain(&mut self, req: &PlotRequest) -> Result<(), HpglError> {
        let Some(sim) = &self.sim else {
            return Ok(());
        };
        let t0 = Instant::now();
        while !sim.idle() {
            if req.control.is_aborted() {
                self.port.write_all(ABORT)?;
                self.port.write_all(b"PU;")?;
                return Err(HpglError::Aborted(req.bytes.len(), req.bytes.len()));
            }
            if t0.elapsed() > DRAIN_LIMIT {
                let why = format!(
                    "the embedded plotter had not drawn its buffer after {} s",
                    DRAIN_LIMIT.as_secs()
                );
                return Err(HpglError::Transport(TransportError::Io(
                    std::io::Error::new(std::io::ErrorKind::TimedOut, why),
                )));
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        Ok(())
    }
}

/// A plot's clock: elapsed time, time paused, and when progress was told last.
struct Clock {
    t0: Instant,
    paused_since: Option<Instant>,
    paused_total: Duration,
    last: Option<(Instant, bool, bool)>,
}

impl Clock {
    fn new() -> Clock {
        Clock {
            t0: Instant::now(),
            paused_since: None,
            paused_total: Duration::ZERO,
            last: None,
        }
    }

    /// The progress to publish for `p`: at most every [`TICK`], and at once on a change of
    /// pause or hold.
    fn tick(&mut self, p: &HpglProgress) -> Option<PlotProgress> {
        let now = Instant::now();
        match (p.paused, self.paused_since) {
            (true, None) => self.paused_since = Some(now),
            (false, Some(s)) => {
                self.paused_total += now - s;
                self.paused_since = None;
            }
            _ => {}
        }
        let changed = self.last.is_none_or(|(t, held, paused)| {
            held != p.held || paused != p.paused || now - t >= TICK
        });
        if !changed {
            return None;
        }
        self.last = Some((now, p.held, p.paused));
        let elapsed = now - self.t0;
        let active = elapsed.saturating_sub(self.paused_total).as_secs_f64();
        let eta = (p.sent > 0 && !p.paused && active > 0.0)
            .then(|| Duration::from_secs_f64((p.total - p.sent) as f64 * active / p.sent as f64));
        Some(PlotProgress {
            bytes_sent: p.sent,
            bytes_total: p.total,
            held: p.held,
            paused: p.paused,
            pen_down: p.pen_down,
            device_free: p.device_free,
            elapsed,
            eta,
        })
    }
}
