//! The simulator on a pseudo-terminal: a thread that paces bytes at the baud rate in both directions, feeds the
//! [`Grbl`] core and runs its clock in (scaled) real time.
//!
//! The thread keeps its own descriptor of the slave end open, so that reads on the master never fail with EIO
//! when a client closes the port; a later client simply opens the same path again (the device "stays plugged in").
//! Opening the port resets the board as the DTR line does on an Uno: an inotify watch on the device sees each
//! client open, stale bytes in the pseudo-terminal are flushed, and the controller restarts with its banner —
//! after its bootloader's delay ([`SimConfig::boot_ms`]), during which input is lost. The watch also sees a
//! client close: what the controller says while no client has the port open is lost, as on the wire, so a
//! power cycle then ([`PtySim::power_cycle`]) leaves no banner for the next client to find.

use crate::files::write_atomic;
use crate::machine::{Grbl, SimEvent};
use crate::{RxOverflow, SimConfig, SimReport, SimStats, TraceSegment};
use nix::errno::Errno;
use nix::fcntl::{FcntlArg, OFlag, fcntl};
use nix::poll::{PollFd, PollFlags, PollTimeout, poll};
use nix::sys::inotify::{AddWatchFlags, InitFlags, Inotify};
use nix::sys::termios::{FlushArg, SetArg, cfmakeraw, tcflush, tcgetattr, tcsetattr};
use std::collections::VecDeque;
use std::io;
use std::os::fd::{AsFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Poll period of the I/O loop, ms: 1 ms is about 11 bytes at 115200 baud.
const POLL_MS: u8 = 1;
/// Longest burst the pacing lets through after a late wake-up, seconds of link time (a UART FIFO's worth).
const MAX_BURST_S: f64 = 0.005;
/// Longest real-time step fed to the core in one go, s (a descheduled thread does not teleport the machine).
const MAX_TICK_S: f64 = 0.05;
/// After a hang-up the device comes back (like a USB adapter re-enumerating) after this long, s.
const REPLUG_DELAY_S: f64 = 1.0;

#[derive(Debug, Default)]
struct Shared {
    trace: Vec<TraceSegment>,
    stats: SimStats,
    lines: u32,
    sim_time: f64,
    hung_up: bool,
    path: PathBuf,
    links: Vec<PathBuf>,
    replugs: u32,
    connects: u32,
    /// A power cycle was asked for and not done yet.
    power_cycle: bool,
}

/// A running simulator on a pseudo-terminal, on its own thread.
#[derive(Debug)]
pub struct PtySim {
    path: PathBuf,
    shared: Arc<Mutex<Shared>>,
    stop: Arc<AtomicBool>,
    handle: Option<JoinHandle<()>>,
    config: SimConfig,
}

fn lock(m: &Mutex<Shared>) -> MutexGuard<'_, Shared> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

fn io_err(e: Errno) -> io::Error {
    io::Error::from_raw_os_error(e as i32)
}

impl PtySim {
    /// Creates the pseudo-terminal pair and starts the simulator thread. The banner is already waiting when a
    /// client opens [`PtySim::path`].
    /// Whether opening the port resets the controller is [`SimConfig::dtr_reset`].
    pub fn spawn(config: SimConfig) -> io::Result<PtySim> {
        let dtr_reset = config.dtr_reset;
        PtySim::spawn_with_dtr_reset(config, dtr_reset)
    }

    /// [`PtySim::spawn`], choosing whether opening the port resets the controller. `true` is an Uno, whose DTR
    /// pulse resets the board on every open (and a hang-up power-cycles it). `false` is a board with auto-reset
    /// disabled and its own supply: the controller keeps running its planner through a hang-up and a reconnect,
    /// and keeps its position, so a sender that reconnects finds it where the job left it.
    pub fn spawn_with_dtr_reset(config: SimConfig, dtr_reset: bool) -> io::Result<PtySim> {
        config
            .validate()
            .map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, e.to_string()))?;
        let (master, slave, path) = open_pty()?;
        let shared = Arc::new(Mutex::new(Shared {
            path: path.clone(),
            ..Shared::default()
        }));
        // Watch for client opens before anyone can open the device.
        let opens = watch_opens(&path);
        let stop = Arc::new(AtomicBool::new(false));
        let (sh, st, cfg) = (shared.clone(), stop.clone(), config.clone());
        let handle = std::thread::Builder::new()
            .name("firmware-sim".into())
            .spawn(move || run(master, slave, opens, cfg, dtr_reset, sh, st))?;
        Ok(PtySim {
            path,
            shared,
            stop,
            handle: Some(handle),
            config,
        })
    }

    /// Device path to open with `serialport` (e.g. `/dev/pts/5`).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Makes a symlink `path` → the device (`--link PATH`); an existing symlink there is replaced. Removed at stop.
    pub fn link(&self, path: &Path) -> io::Result<()> {
        if let Ok(meta) = std::fs::symlink_metadata(path)
            && meta.file_type().is_symlink()
        {
            std::fs::remove_file(path)?;
        }
        let mut sh = lock(&self.shared);
        std::os::unix::fs::symlink(&sh.path, path)?;
        sh.links.push(path.to_path_buf());
        Ok(())
    }

    /// Snapshot of the executed segments so far.
    pub fn trace(&self) -> Vec<TraceSegment> {
        lock(&self.shared).trace.clone()
    }

    /// Lines received so far (every line terminator counts).
    pub fn lines_received(&self) -> u32 {
        lock(&self.shared).lines
    }

    /// Counters so far.
    pub fn stats(&self) -> SimStats {
        lock(&self.shared).stats.clone()
    }

    /// Simulated time so far, s.
    pub fn sim_time(&self) -> f64 {
        lock(&self.shared).sim_time
    }

    /// True while a hang-up fault has the device closed.
    pub fn hung_up(&self) -> bool {
        lock(&self.shared).hung_up
    }

    /// The device path now: after a hang-up the device comes back on a new pseudo-terminal (the links follow it).
    pub fn current_path(&self) -> PathBuf {
        lock(&self.shared).path.clone()
    }

    /// How many times the device came back after a hang-up.
    pub fn replugs(&self) -> u32 {
        lock(&self.shared).replugs
    }

    /// How many times a client opened the device (each open resets the controller, like DTR on an Uno).
    pub fn connects(&self) -> u32 {
        lock(&self.shared).connects
    }

    /// Cuts the controller's power and restores it, as unplugging a board powered over USB (or a reset button)
    /// does: motion stops, the position is zero, G92 and the tool length offset are gone, settings and stored
    /// offsets stay, and the banner comes after the bootloader's delay — lost if no client has the port open.
    pub fn power_cycle(&self) {
        lock(&self.shared).power_cycle = true;
    }

    /// Stops the thread, writes the trace files of the configuration and returns trace and counters.
    pub fn stop(mut self) -> SimReport {
        self.shutdown();
        let sh = lock(&self.shared);
        let report = SimReport {
            trace: sh.trace.clone(),
            stats: sh.stats.clone(),
            sim_time: sh.sim_time,
        };
        drop(sh);
        if let Some(p) = &self.config.trace_jsonl {
            let mut s = String::new();
            for seg in &report.trace {
                if let Ok(j) = serde_json::to_string(seg) {
                    s.push_str(&j);
                    s.push('\n');
                }
            }
            if let Err(e) = write_atomic(p, s.as_bytes()) {
                eprintln!("firmware-sim: cannot write trace {}: {e}", p.display());
            }
        }
        if let Some(p) = &self.config.trace_svg
            && let Err(e) = write_atomic(p, crate::svg::trace_svg(&report.trace).as_bytes())
        {
            eprintln!("firmware-sim: cannot write SVG {}: {e}", p.display());
        }
        report
    }

    fn shutdown(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
        let links: Vec<PathBuf> = lock(&self.shared).links.drain(..).collect();
        for l in links {
            let _ = std::fs::remove_file(l);
        }
    }
}

impl Drop for PtySim {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// Token bucket pacing bytes at `rate` bytes/s.
pub(crate) struct Pace {
    pub(crate) rate: f64,
    pub(crate) credit: f64,
}

impl Pace {
    pub(crate) fn add(&mut self, dt: f64) {
        self.credit = (self.credit + dt * self.rate).min((self.rate * MAX_BURST_S).max(1.0));
    }
    pub(crate) fn available(&self) -> usize {
        self.credit.max(0.0).floor() as usize
    }
    pub(crate) fn take(&mut self, n: usize) {
        self.credit -= n as f64;
    }
}

/// Opens a pseudo-terminal pair in raw mode with a non-blocking master; returns (master, slave, slave path).
pub(crate) fn open_pty() -> io::Result<(OwnedFd, OwnedFd, PathBuf)> {
    let pty = nix::pty::openpty(None, None).map_err(io_err)?;
    let (master, slave) = (pty.master, pty.slave);
    let mut t = tcgetattr(&slave).map_err(io_err)?;
    cfmakeraw(&mut t);
    tcsetattr(&slave, SetArg::TCSANOW, &t).map_err(io_err)?;
    let path = nix::unistd::ttyname(&slave).map_err(io_err)?;
    let flags = OFlag::from_bits_truncate(fcntl(&master, FcntlArg::F_GETFL).map_err(io_err)?);
    fcntl(&master, FcntlArg::F_SETFL(flags | OFlag::O_NONBLOCK)).map_err(io_err)?;
    Ok((master, slave, path))
}

/// A non-blocking watch for opens of the device node (a client connecting).
fn watch_opens(path: &Path) -> Option<Inotify> {
    let ino = Inotify::init(InitFlags::IN_NONBLOCK | InitFlags::IN_CLOEXEC).ok()?;
    ino.add_watch(
        path,
        AddWatchFlags::IN_OPEN | AddWatchFlags::IN_CLOSE_WRITE | AddWatchFlags::IN_CLOSE_NOWRITE,
    )
    .ok()?;
    Some(ino)
}

/// A hardware reset of the controller: off now, on again after the bootloader's delay.
fn hard_reset(core: &mut Grbl, boot: Duration, booting: &mut Option<Instant>) {
    core.power_off();
    *booting = Some(Instant::now() + boot);
}

/// Brings the device back on a fresh pseudo-terminal and re-points the links.
fn replug(shared: &Mutex<Shared>) -> Option<(OwnedFd, OwnedFd, Option<Inotify>)> {
    let (master, slave, path) = open_pty().ok()?;
    // Watch before the links point at the new device, so that no client open is missed.
    let opens = watch_opens(&path);
    let mut sh = lock(shared);
    for l in &sh.links {
        let _ = std::fs::remove_file(l);
        let _ = std::os::unix::fs::symlink(&path, l);
    }
    sh.path = path;
    sh.hung_up = false;
    sh.replugs += 1;
    Some((master, slave, opens))
}

fn run(
    master: OwnedFd,
    slave: OwnedFd,
    mut opens: Option<Inotify>,
    config: SimConfig,
    dtr_reset: bool,
    shared: Arc<Mutex<Shared>>,
    stop: Arc<AtomicBool>,
) {
    let mut core = Grbl::new(&config);
    let bps = f64::from(config.baud) / 10.0;
    let mut rx_pace = Pace {
        rate: bps,
        credit: 0.0,
    };
    let mut tx_pace = Pace {
        rate: bps,
        credit: 0.0,
    };
    let delay = Duration::from_millis(config.faults.response_delay_ms);
    let mut txq: VecDeque<(Instant, u8)> = VecDeque::new();
    let mut master = Some(master);
    let mut slave = Some(slave);
    let mut last = Instant::now();
    let mut buf = [0u8; 512];
    let mut pushed_trace = 0;
    let mut unplugged_at: Option<Instant> = None;
    let boot = Duration::from_millis(config.boot_ms);
    // The controller is in its bootloader until then (it powered up as the thread started).
    let mut booting: Option<Instant> = None;
    if !boot.is_zero() {
        hard_reset(&mut core, boot, &mut booting);
    }
    // Clients with the device open; without a watch, one is taken to be there all along.
    let mut clients: i64 = i64::from(opens.is_none());
    while !stop.load(Ordering::SeqCst) {
        if let Some(t) = unplugged_at
            && t.elapsed().as_secs_f64() >= REPLUG_DELAY_S
            && let Some((m, s, o)) = replug(&shared)
        {
            master = Some(m);
            slave = Some(s);
            unplugged_at = None;
            if dtr_reset {
                hard_reset(&mut core, boot, &mut booting);
            }
            opens = o;
            clients = i64::from(opens.is_none());
        }
        if std::mem::take(&mut lock(&shared).power_cycle) {
            hard_reset(&mut core, boot, &mut booting);
        }
        if booting.is_some_and(|t| Instant::now() >= t) {
            booting = None;
            core.power_on();
        }
        if let Some(m) = &master {
            let mut fds = vec![PollFd::new(m.as_fd(), PollFlags::POLLIN)];
            if let Some(ino) = &opens {
                fds.push(PollFd::new(ino.as_fd(), PollFlags::POLLIN));
            }
            let _ = poll(&mut fds, PollTimeout::from(POLL_MS));
        } else {
            std::thread::sleep(Duration::from_millis(u64::from(POLL_MS)));
        }
        let now = Instant::now();
        let dt = now.duration_since(last).as_secs_f64().min(MAX_TICK_S);
        last = now;
        rx_pace.add(dt);
        tx_pace.add(dt);
        // Receive, paced. The bytes are read before the watch's events and fed to the core after them: a client's
        // open is queued on the watch before its first byte can be read, so bytes are never answered into a
        // connection the loop has not seen yet (the answer would be dropped as said to nobody).
        let mut received = 0;
        if let Some(m) = &master {
            let mut n = rx_pace.available().min(buf.len());
            if config.rx_overflow == RxOverflow::Block {
                n = n.min(core.rx_free());
            }
            if n > 0 {
                match nix::unistd::read(m, &mut buf[..n]) {
                    Ok(k) => {
                        rx_pace.take(k);
                        received = k;
                    }
                    Err(Errno::EAGAIN) | Err(Errno::EIO) | Err(Errno::EINTR) => {}
                    Err(_) => {}
                }
            }
        }
        // A client opened the device: reset like the DTR pulse of an Uno, with the stale bytes flushed. The last
        // client closed it: what is still on its way to it is lost (the bytes it sent before closing were on the
        // wire and are not).
        if let (Some(ino), Some(s)) = (&opens, &slave)
            && let Ok(events) = ino.read_events()
        {
            for ev in events {
                if ev.mask.contains(AddWatchFlags::IN_OPEN) {
                    if dtr_reset {
                        let _ = tcflush(s, FlushArg::TCIOFLUSH);
                        txq.clear();
                        // Bytes read just now went to the board being reset: the bootloader drops them.
                        received = 0;
                        hard_reset(&mut core, boot, &mut booting);
                        if boot.is_zero() {
                            booting = None;
                            core.power_on();
                        }
                    }
                    clients += 1;
                    lock(&shared).connects += 1;
                } else {
                    clients = (clients - 1).max(0);
                    if clients == 0 {
                        // TCIFLUSH on the slave drops what the controller wrote and no client read.
                        let _ = tcflush(s, FlushArg::TCIFLUSH);
                        txq.clear();
                    }
                }
            }
        }
        core.receive_all(&buf[..received]);
        core.tick(dt * config.time_scale);
        for ev in core.take_events() {
            match ev {
                SimEvent::Hangup => {
                    publish(&core, &shared, &mut pushed_trace);
                    lock(&shared).hung_up = true;
                    master = None;
                    slave = None;
                    txq.clear();
                    unplugged_at = Some(Instant::now());
                }
            }
        }
        let connected = clients > 0;
        let out = core.take_output();
        // Until a client connects (and resets the board) nothing is listening: output is lost, as on the wire.
        if master.is_some() && connected {
            let ready = now + delay;
            txq.extend(out.into_iter().map(|b| (ready, b)));
        }
        // Transmit, paced.
        if let Some(m) = &master {
            let mut chunk = Vec::new();
            let budget = tx_pace.available();
            for &(t, b) in txq.iter() {
                if chunk.len() >= budget || t > now {
                    break;
                }
                chunk.push(b);
            }
            if !chunk.is_empty() {
                match nix::unistd::write(m, &chunk) {
                    Ok(k) => {
                        tx_pace.take(k);
                        txq.drain(..k);
                    }
                    Err(_) => {
                        // EAGAIN: nobody reads and the pty buffer is full; EIO: no client. Keep the bytes.
                    }
                }
            }
        }
        publish(&core, &shared, &mut pushed_trace);
    }
    drop(slave);
    drop(master);
}

/// Copies the core's counters and new trace segments to the shared snapshot.
fn publish(core: &Grbl, shared: &Mutex<Shared>, pushed_trace: &mut usize) {
    let mut sh = lock(shared);
    let tr = core.trace();
    if tr.len() > *pushed_trace {
        sh.trace.extend_from_slice(&tr[*pushed_trace..]);
        *pushed_trace = tr.len();
    }
    sh.stats = core.stats();
    sh.lines = core.lines_received();
    sh.sim_time = core.clock();
}
