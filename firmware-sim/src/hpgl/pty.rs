//! The HP-GL plotter on a pseudo-terminal, on its own thread: bytes paced at the baud rate in
//! both directions (the same pacing as the GRBL simulator's link), the device clock in real
//! time scaled by `time_scale`.

use std::io;
use std::os::fd::{AsFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use nix::poll::{PollFd, PollFlags, PollTimeout, poll};

use super::interp::PenSegment;
use super::plotter::{Plotter, PlotterConfig, PlotterStats};
use crate::pty::{Pace, open_pty};

/// Poll period of the I/O loop, ms.
const POLL_MS: u8 = 1;
/// Longest real-time step fed to the device in one go, s.
const MAX_TICK_S: f64 = 0.05;
/// Receive credit kept across a late wake-up, s of line time: a UART receives at the line rate
/// however late its reader runs, so the device must not fall behind the sender on average.
const RX_CREDIT_S: f64 = 0.05;

#[derive(Debug, Default)]
struct Shared {
    trace: Vec<PenSegment>,
    stats: PlotterStats,
    idle: bool,
    pen_down: bool,
    clock: f64,
}

/// A running HP-GL plotter on a pseudo-terminal.
#[derive(Debug)]
pub struct HpglPtySim {
    path: PathBuf,
    shared: Arc<Mutex<Shared>>,
    stop: Arc<AtomicBool>,
    handle: Option<JoinHandle<()>>,
}

fn lock(m: &Mutex<Shared>) -> MutexGuard<'_, Shared> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl HpglPtySim {
    /// Starts the plotter at `baud`, its clock running `time_scale` times real time.
    pub fn spawn(config: PlotterConfig, baud: u32, time_scale: f64) -> io::Result<HpglPtySim> {
        if baud == 0 || !(time_scale.is_finite() && time_scale > 0.0) || config.buffer == 0 {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                "baud, time scale and buffer must be positive",
            ));
        }
        let (master, slave, path) = open_pty()?;
        let shared = Arc::new(Mutex::new(Shared::default()));
        let stop = Arc::new(AtomicBool::new(false));
        let (sh, st) = (shared.clone(), stop.clone());
        let handle = std::thread::Builder::new()
            .name("hpgl-sim".into())
            .spawn(move || run(master, slave, config, baud, time_scale, sh, st))?;
        Ok(HpglPtySim {
            path,
            shared,
            stop,
            handle: Some(handle),
        })
    }

    /// Device path to open (e.g. `/dev/pts/5`).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Device counters so far.
    pub fn stats(&self) -> PlotterStats {
        lock(&self.shared).stats.clone()
    }

    /// The pen-down segments drawn so far (mm).
    pub fn trace(&self) -> Vec<PenSegment> {
        lock(&self.shared).trace.clone()
    }

    /// Whether the pen is down now (after the last instruction executed).
    pub fn pen_down(&self) -> bool {
        lock(&self.shared).pen_down
    }

    /// True when every byte received has been executed.
    pub fn idle(&self) -> bool {
        lock(&self.shared).idle
    }

    /// Waits until the device has executed everything it received, at most `timeout`.
    pub fn wait_idle(&self, timeout: Duration) -> bool {
        let t0 = Instant::now();
        while t0.elapsed() < timeout {
            if self.idle() {
                return true;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        false
    }

    /// Stops the device; returns its pen trace and counters.
    pub fn stop(mut self) -> (Vec<PenSegment>, PlotterStats) {
        self.shutdown();
        let sh = lock(&self.shared);
        (sh.trace.clone(), sh.stats.clone())
    }

    fn shutdown(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

impl Drop for HpglPtySim {
    fn drop(&mut self) {
        self.shutdown();
    }
}

fn run(
    master: OwnedFd,
    slave: OwnedFd,
    config: PlotterConfig,
    baud: u32,
    time_scale: f64,
    shared: Arc<Mutex<Shared>>,
    stop: Arc<AtomicBool>,
) {
    let mut dev = Plotter::new(config);
    let bps = f64::from(baud) / 10.0;
    let mut rx_credit = 0.0f64;
    let mut tx = Pace {
        rate: bps,
        credit: 0.0,
    };
    let mut txq: Vec<u8> = Vec::new();
    let mut last = Instant::now();
    let mut buf = [0u8; 256];
    while !stop.load(Ordering::SeqCst) {
        let mut fds = [PollFd::new(master.as_fd(), PollFlags::POLLIN)];
        let _ = poll(&mut fds, PollTimeout::from(POLL_MS));
        let now = Instant::now();
        let dt = now.duration_since(last).as_secs_f64().min(MAX_TICK_S);
        last = now;
        rx_credit = (rx_credit + dt * bps).min(bps * RX_CREDIT_S);
        tx.add(dt);
        let n = (rx_credit.max(0.0) as usize).min(buf.len());
        if n > 0 {
            // EAGAIN (nothing there), EIO (no client) and EINTR leave the credit for later.
            if let Ok(k) = nix::unistd::read(&master, &mut buf[..n]) {
                rx_credit -= k as f64;
                dev.receive(&buf[..k]);
            }
        }
        dev.tick(dt * time_scale);
        txq.extend(dev.take_output());
        let budget = tx.available().min(txq.len());
        if budget > 0
            && let Ok(k) = nix::unistd::write(&master, &txq[..budget])
        {
            tx.take(k);
            txq.drain(..k);
        }
        let mut sh = lock(&shared);
        if dev.interp.trace.len() > sh.trace.len() {
            let from = sh.trace.len();
            sh.trace.extend_from_slice(&dev.interp.trace[from..]);
        }
        sh.stats = dev.stats.clone();
        sh.idle = dev.idle() && txq.is_empty();
        sh.pen_down = dev.interp.pen_down;
        sh.clock = dev.clock();
    }
    drop(slave);
}
