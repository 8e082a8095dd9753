//! The split's clock: the CPU time the process has used, so that the split's time limit
//! (`--split-time`) measures the work done rather than the wall time, and a busy machine (other
//! builds, other jobs) does not change how far a split gets.
//!
//! It is [`flatcut_flatten::budget::cpu_time`], the clock the split's solves stop on too
//! ([`flatcut_flatten::Budget::until_cpu`]): the limit and the deadlines of the solves inside
//! it are one clock. The clock counts every thread of the process: the split's candidates are
//! judged side by side on the rayon pool, so two cores busy for a second spend two seconds of
//! it; and work the same process does beside the split (a second job of the workbench's
//! server) counts too. Where the clock cannot be read (a system without it), the clock falls
//! back to wall time.

pub use flatcut_flatten::budget::cpu_time;
use std::time::{Duration, Instant};

/// A stopwatch of the process's CPU time.
#[derive(Clone, Copy, Debug)]
pub struct CpuClock {
    /// The CPU time used when the clock started; `None` where it cannot be read.
    cpu: Option<Duration>,
    /// The wall time it started at, for the fallback.
    wall: Instant,
}

impl CpuClock {
    /// A stopwatch started now.
    pub fn start() -> Self {
        Self {
            cpu: cpu_time(),
            wall: Instant::now(),
        }
    }

    /// The process's CPU time at which `limit` from the clock's start is spent; `None` where
    /// the CPU time cannot be read.
    pub fn at(&self, limit: Duration) -> Option<Duration> {
        self.cpu.map(|c| c.saturating_add(limit))
    }

    /// The CPU time the process has used since the clock started (all its threads); the wall
    /// time where the CPU time cannot be read.
    pub fn elapsed(&self) -> Duration {
        match (self.cpu, cpu_time()) {
            (Some(a), Some(b)) => b.saturating_sub(a),
            _ => self.wall.elapsed(),
        }
    }
}

/// Test support for measuring the CPU clock: busy work, and a test run alone in a child
/// process (the tests beside it in one process spend CPU time while it sleeps).
#[cfg(test)]
pub(crate) mod alone {
    /// Spins one thread on arithmetic until `done` says so.
    pub(crate) fn busy_until(mut done: impl FnMut() -> bool) {
        let mut x = 1u64;
        while !done() {
            for _ in 0..1000 {
                x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
            }
        }
    }

    /// Runs the test `name` of this test binary alone in a child process with `env` set, and
    /// panics with its output unless it passes and prints `marker`.
    #[cfg(unix)]
    pub(crate) fn run_alone(name: &str, env: &str, marker: &str) {
        let out = std::process::Command::new(std::env::current_exe().unwrap())
            .args([name, "--exact", "--nocapture"])
            .env(env, "1")
            .output()
            .unwrap();
        let said = String::from_utf8_lossy(&out.stdout).into_owned()
            + &String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success() && said.contains(marker), "{said}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Environment variable that makes [`clock_child`] measure.
    const CHILD_ENV: &str = "FLATCUT_CPU_CLOCK_CHILD";

    /// The measuring half of [`the_clock_counts_work_and_not_sleep`], run alone in a child
    /// process: the tests beside it in this one would spend CPU time while it sleeps. Without
    /// the variable set it does nothing.
    #[test]
    fn clock_child() {
        if std::env::var_os(CHILD_ENV).is_none() {
            return;
        }
        // Asleep for 300 ms: the clock stands (a wall clock would read 300 ms).
        let c = CpuClock::start();
        std::thread::sleep(Duration::from_millis(300));
        let asleep = c.elapsed();
        assert!(asleep < Duration::from_millis(60), "asleep: {asleep:?}");
        // Busy on one thread until the clock reads 100 ms: it runs with work, however long a
        // loaded machine makes that take (a clock that did not would still stand after a
        // minute of wall time, and fail), and never ahead of the wall (one thread cannot spend
        // more than the wall time it took).
        let (c, t0) = (CpuClock::start(), Instant::now());
        let counted = Duration::from_millis(100);
        alone::busy_until(|| c.elapsed() >= counted || t0.elapsed() >= Duration::from_secs(60));
        let (busy, wall) = (c.elapsed(), t0.elapsed());
        assert!(
            busy >= counted,
            "busy: the clock stood at {busy:?} after {wall:?}"
        );
        assert!(
            busy <= wall + Duration::from_millis(5),
            "busy: {busy:?} in {wall:?}"
        );
        println!("CPU-CLOCK-CHECKED");
    }

    /// The clock advances with busy work and stands still while the process sleeps: measured
    /// in a child process running [`clock_child`] alone.
    #[test]
    #[cfg(unix)]
    fn the_clock_counts_work_and_not_sleep() {
        alone::run_alone("clock::tests::clock_child", CHILD_ENV, "CPU-CLOCK-CHECKED");
    }
}
