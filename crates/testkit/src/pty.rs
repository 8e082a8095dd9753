//! The sender against firmware-sim over a real pseudo-terminal.

use flatcut_firmware_sim::{PtySim, SimConfig};
use flatcut_grbl::{CancelToken, Job, Progress, SendError, SendOptions, SendReport, open_port};
use std::path::Path;

/// A simulator on its own pseudo-terminal.
pub fn spawn(cfg: SimConfig) -> PtySim {
    PtySim::spawn(cfg).expect("spawn firmware-sim")
}

/// Opens `path` at 115200 baud and sends `job`, calling `observer` with every progress report.
pub fn send_with(
    path: &Path,
    job: &Job,
    opts: &SendOptions,
    cancel: &CancelToken,
    observer: &mut dyn FnMut(&Progress),
) -> Result<SendReport, SendError> {
    let mut port = open_port(path.to_str().expect("a UTF-8 device path"), 115_200)
        .expect("open the pseudo-terminal");
    flatcut_grbl::send_job(&mut port, job, opts, observer, cancel)
}

/// [`send_with`] to the simulator's device, with no observer and no operator.
pub fn send(sim: &PtySim, job: &Job, opts: &SendOptions) -> Result<SendReport, SendError> {
    send_with(sim.path(), job, opts, &CancelToken::new(), &mut |_| {})
}
