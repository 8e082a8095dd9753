//! What a stage of a flattening may spend, and what it spent.
//!
//! `FlattenParams::max_iters` and `FlattenParams::time_limit` cap every *stage* of a flattening,
//! not each solve: a stage is one named part of the work (a piece's own solve, the material
//! limits, the joint solve of pieces sewn together, the darts, the split, and the two parts of
//! `minmax` and `boundary-isometric`), and all the solves a stage runs draw on one
//! [`Budget`]: at most `max_iters` iterations between them, and `time_limit` of wall time from
//! the stage's start. Every stage reports its count ([`StageCount`], in
//! `FlattenInfo::stages`), so the total over a flattening is never above the cap times the
//! number of its stages.
//!
//! A stage's solves run one after the other, so the count, and every result, is the same on
//! every run. Work computed ahead on another core (the dart search's next attempt) draws on a
//! [`Budget::fork`] of the budget: the fork records how close each of its solves came to the
//! cap, so its result is taken only where the iterations spent meanwhile would not have cut any
//! of them short ([`Budget::join`]); otherwise it is computed again in order.
//!
//! A stage's time runs on one of two clocks: wall time (`deadline`, the flattener's
//! `time_limit`), or the process's CPU time (`cpu_deadline`, [`cpu_time`]: all its threads
//! together). A split's `--split-time` is CPU time, and every solve inside it stops on that
//! same clock ([`Budget::until_cpu`]): a solve stopped by the wall clock while the CPU time was
//! not yet spent (a busy machine giving the process less than a core) spent less than the limit
//! on work the limit was meant to pay for, and the merging at the end was what it cut.

use std::sync::Arc;
use std::sync::atomic::{AtomicI64, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use crate::FlattenHooks;

/// The iterations of one stage: its cap and what its solves took so far.
#[derive(Debug)]
struct Count {
    name: &'static str,
    cap: usize,
    used: AtomicUsize,
    /// The least room any solve left under the cap when it asked for its own cap
    /// ([`Budget::allow`]): `left − want`, negative where the stage's cap cut the solve short.
    tightest: AtomicI64,
}

/// What one stage of a flattening may spend (iterations over all its solves, and wall time),
/// with the progress callback and cancel flag of the whole flattening. Clones share the count.
#[derive(Clone, Debug)]
pub struct Budget {
    /// Progress callback and cancel flag.
    pub hooks: FlattenHooks,
    /// Stop after this instant (the best iterate so far is the result).
    pub deadline: Option<Instant>,
    /// Stop once the process has used this much CPU time ([`cpu_time`]), all its threads
    /// together: the clock of a split's time limit.
    pub cpu_deadline: Option<Duration>,
    /// When the whole flattening started (for the progress reports).
    pub started: Instant,
    /// Name of the solve in the progress reports.
    pub stage: &'static str,
    count: Arc<Count>,
    /// Set on a budget that a whole flattening runs within ([`Budget::within`]): its stages
    /// are this one's, not stages of their own.
    nested: bool,
}

/// The iterations one stage took against its cap, and whether the cap or the time limit cut it
/// short.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StageCount {
    /// The stage's name, as reported to the user.
    pub stage: &'static str,
    /// Iterations the stage took, summed over all its solves.
    pub iterations: usize,
    /// The stage's iteration cap.
    pub cap: usize,
    /// True when the stage stopped at its iteration cap or its time limit.
    pub stopped: bool,
}

impl PartialEq for Budget {
    /// Two budgets are equal when they are the same stage's (clones of one budget).
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.count, &other.count)
    }
}

impl std::fmt::Display for StageCount {
    /// "isometric 7/200" (with " (stopped)" when cut short).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} {}/{}", self.stage, self.iterations, self.cap)?;
        if self.stopped {
            f.write_str(" (stopped)")?;
        }
        Ok(())
    }
}

impl Budget {
    /// No callback, no cancel flag, no deadline, no cap beyond each solve's own.
    pub fn none(stage: &'static str) -> Self {
        Self::stage(
            stage,
            usize::MAX,
            None,
            FlattenHooks::default(),
            Instant::now(),
        )
    }

    /// The budget of the stage `name`: `cap` iterations over all its solves, `time` from now.
    /// `started` is when the flattening began (the progress reports count from it).
    pub fn stage(
        name: &'static str,
        cap: usize,
        time: Option<Duration>,
        hooks: FlattenHooks,
        started: Instant,
    ) -> Self {
        Self {
            hooks,
            deadline: time.and_then(|t| Instant::now().checked_add(t)),
            cpu_deadline: None,
            started,
            stage: name,
            count: Arc::new(Count {
                name,
                cap,
                used: AtomicUsize::new(0),
                tightest: AtomicI64::new(i64::MAX),
            }),
            nested: false,
        }
    }

    /// This budget, for a flattening run inside the stage it belongs to (the split flattens
    /// its parts within its own stage): every stage of that flattening draws on this one.
    pub fn within(&self) -> Self {
        Self {
            nested: true,
            ..self.clone()
        }
    }

    /// The budget of the next stage `name` of the same flattening: the same cap, time limit
    /// (from now), callback and cancel flag; inside another stage ([`Budget::within`]), that
    /// stage's budget itself.
    pub fn next(&self, name: &'static str, time: Option<Duration>) -> Self {
        self.next_capped(name, self.count.cap, time)
    }

    /// [`Budget::next`] with a cap of its own.
    pub fn next_capped(&self, name: &'static str, cap: usize, time: Option<Duration>) -> Self {
        if self.nested {
            return self.labelled(name);
        }
        Self::stage(name, cap, time, self.hooks.clone(), self.started)
    }

    /// The same budget shown under another name in the progress reports.
    pub fn labelled(&self, stage: &'static str) -> Self {
        Self {
            stage,
            ..self.clone()
        }
    }

    /// This budget stopping, besides its own deadlines, once the process has used `cpu` of
    /// CPU time ([`cpu_time`]; where it cannot be read, `left` from now on the wall clock).
    pub fn until_cpu(mut self, cpu: Option<Duration>, left: Duration) -> Self {
        match cpu {
            Some(c) => self.cpu_deadline = Some(self.cpu_deadline.map_or(c, |d| d.min(c))),
            None => {
                let until = Instant::now().checked_add(left);
                self.deadline = match (self.deadline, until) {
                    (Some(d), Some(u)) => Some(d.min(u)),
                    (d, u) => d.or(u),
                };
            }
        }
        self
    }

    /// The time the stage has left, the less of its two clocks' (`None`: no time limit).
    pub fn time_left(&self) -> Option<Duration> {
        let wall = self
            .deadline
            .map(|d| d.saturating_duration_since(Instant::now()));
        let cpu = self
            .cpu_deadline
            .map(|d| cpu_time().map_or(Duration::ZERO, |now| d.saturating_sub(now)));
        match (wall, cpu) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// True when either deadline has passed.
    pub fn expired(&self) -> bool {
        self.deadline.is_some_and(|d| Instant::now() >= d)
            || self
                .cpu_deadline
                .is_some_and(|d| cpu_time().is_none_or(|now| now >= d))
    }

    /// Iterations the stage may still take.
    pub fn left(&self) -> usize {
        self.count
            .cap
            .saturating_sub(self.count.used.load(Ordering::Relaxed))
    }

    /// The cap of a solve that would take at most `want` iterations on its own: what the stage
    /// has left, if less.
    pub fn allow(&self, want: usize) -> usize {
        let left = self.left();
        let slack = i64::try_from(left)
            .unwrap_or(i64::MAX)
            .saturating_sub(i64::try_from(want).unwrap_or(i64::MAX));
        self.count.tightest.fetch_min(slack, Ordering::Relaxed);
        want.min(left)
    }

    /// True when the stage can take no further iteration, or its time is up: a search of
    /// several solves stops there.
    pub fn spent(&self) -> bool {
        self.allow(1) == 0 || self.expired()
    }

    /// Counts `n` iterations taken.
    pub fn spend(&self, n: usize) {
        self.count.used.fetch_add(n, Ordering::Relaxed);
    }

    /// Iterations taken so far.
    pub fn used(&self) -> usize {
        self.count.used.load(Ordering::Relaxed)
    }

    /// The stage's cap.
    pub fn cap(&self) -> usize {
        self.count.cap
    }

    /// The stage's count so far.
    pub fn count(&self) -> StageCount {
        let used = self.used();
        StageCount {
            stage: self.count.name,
            iterations: used,
            cap: self.count.cap,
            stopped: used >= self.count.cap || self.expired(),
        }
    }

    /// A budget for work computed ahead, to be [`Budget::join`]ed back: it starts where this one
    /// is now, with a count of its own.
    pub fn fork(&self) -> Self {
        Self {
            count: Arc::new(Count {
                name: self.count.name,
                cap: self.count.cap,
                used: AtomicUsize::new(self.used()),
                tightest: AtomicI64::new(i64::MAX),
            }),
            ..self.clone()
        }
    }

    /// Takes the work done on `fork` (forked from this budget when it had used `at_fork`) as if
    /// it had been done now, on this budget, and returns true, when the iterations spent here
    /// since the fork would have cut none of its solves shorter; returns false (and counts
    /// nothing) otherwise, for the work to be done again on this budget.
    pub fn join(&self, fork: &Budget, at_fork: usize) -> bool {
        let since = self.used().saturating_sub(at_fork);
        let room = fork.count.tightest.load(Ordering::Relaxed);
        if room < i64::try_from(since).unwrap_or(i64::MAX) {
            return false;
        }
        self.spend(fork.used().saturating_sub(at_fork));
        true
    }
}

impl Budget {
    /// `f` of each of `items`, computed side by side on forks of this budget and taken in
    /// order as if computed one after the other on it: a result whose solves the iterations
    /// taken before it in that order would have cut short is computed again, in order. The
    /// results, and the count, are those of the sequential computation.
    pub fn map_in_order<I: Sync, T: Send>(
        &self,
        items: &[I],
        f: impl Fn(&I, &Budget) -> T + Sync,
    ) -> Vec<T> {
        use rayon::prelude::*;
        let at = self.used();
        let ahead: Vec<(T, Budget)> = items
            .par_iter()
            .map(|item| {
                let fork = self.fork();
                (f(item, &fork), fork)
            })
            .collect();
        ahead
            .into_iter()
            .zip(items)
            .map(|((out, fork), item)| {
                if self.join(&fork, at) {
                    out
                } else {
                    f(item, self)
                }
            })
            .collect()
    }
}

/// The CPU time the process has used so far, all its threads together
/// (`clock_gettime(CLOCK_PROCESS_CPUTIME_ID)`, read through `nix`, a maintained safe wrapper:
/// the `cpu-time` crate wraps the same call but has had no release since 2019, and calling
/// `libc` directly needs `unsafe`, which the workspace denies); `None` where it cannot be read.
#[cfg(unix)]
pub fn cpu_time() -> Option<Duration> {
    nix::time::ClockId::CLOCK_PROCESS_CPUTIME_ID
        .now()
        .ok()
        .map(Duration::from)
}

/// The CPU time the process has used so far: not read on this system.
#[cfg(not(unix))]
pub fn cpu_time() -> Option<Duration> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_share_the_stage_cap_and_report_it() {
        let b = Budget::stage("s", 10, None, FlattenHooks::default(), Instant::now());
        assert_eq!(b.allow(6), 6);
        b.spend(6);
        let c = b.clone();
        assert_eq!(c.allow(6), 4, "a clone draws on the same count");
        c.spend(4);
        assert!(b.spent());
        let count = b.count();
        assert_eq!((count.iterations, count.cap, count.stopped), (10, 10, true));
        assert_eq!(count.to_string(), "s 10/10 (stopped)");
        let next = b.next("t", None);
        assert_eq!(
            (next.used(), next.cap(), next.count().stopped),
            (0, 10, false)
        );
    }

    #[test]
    fn side_by_side_work_counts_as_in_order() {
        // Each item asks for 30 iterations and takes them: with a cap of 100 the fourth is cut
        // to 10 and the fifth gets none, exactly as one after the other.
        let run = |cap: usize| {
            let b = Budget::stage("s", cap, None, FlattenHooks::default(), Instant::now());
            let got = b.map_in_order(&[0, 1, 2, 3, 4], |_, b| {
                let n = b.allow(30);
                b.spend(n);
                n
            });
            (got, b.used())
        };
        assert_eq!(run(100), (vec![30, 30, 30, 10, 0], 100));
        assert_eq!(run(1000), (vec![30; 5], 150));
    }

    #[test]
    fn work_done_ahead_is_taken_only_where_the_cap_would_not_have_bitten() {
        let b = Budget::stage("s", 100, None, FlattenHooks::default(), Instant::now());
        b.spend(10);
        let at = b.used();
        let ahead = b.fork();
        assert_eq!(ahead.allow(20), 20);
        ahead.spend(20);
        // Meanwhile 50 more are spent: 40 left, the fork's solve asked for 20: still room.
        b.spend(50);
        assert!(b.join(&ahead, at));
        assert_eq!(b.used(), 80);
        // A fork whose solve would have been cut short is refused.
        let at = b.used();
        let ahead = b.fork();
        assert_eq!(ahead.allow(15), 15);
        ahead.spend(15);
        b.spend(10);
        assert!(!b.join(&ahead, at), "10 left, the solve wanted 15");
        assert_eq!(b.used(), 90);
    }

    #[test]
    #[cfg(unix)]
    fn a_cpu_deadline_is_read_on_the_process_cpu_clock() {
        let stage = || Budget::stage("s", 10, None, FlattenHooks::default(), Instant::now());
        let now = cpu_time().expect("the CPU clock is read on unix");
        // An hour of CPU time ahead: not expired, and the time left is about that hour, the
        // less of the two clocks' where the wall clock has a deadline too.
        let ahead = stage().until_cpu(Some(now + Duration::from_secs(3600)), Duration::ZERO);
        assert!(!ahead.expired() && !ahead.spent());
        let left = ahead.time_left().unwrap();
        assert!(left > Duration::from_secs(3590) && left <= Duration::from_secs(3600));
        let mut both = ahead.clone();
        both.deadline = Instant::now().checked_add(Duration::from_secs(60));
        assert!(both.time_left().unwrap() <= Duration::from_secs(60));
        // A CPU time already spent: expired at once, whatever the wall clock says, and a later
        // CPU deadline does not lift it.
        let mut spent = stage().until_cpu(Some(now), Duration::from_secs(3600));
        spent.deadline = Instant::now().checked_add(Duration::from_secs(3600));
        assert!(spent.expired() && spent.spent());
        assert_eq!(spent.time_left(), Some(Duration::ZERO));
        assert!(
            spent
                .until_cpu(Some(now + Duration::from_secs(3600)), Duration::ZERO)
                .expired()
        );
        // Where the CPU clock cannot be read, the time left runs on the wall clock.
        let wall = stage().until_cpu(None, Duration::ZERO);
        assert!(wall.cpu_deadline.is_none() && wall.expired());
    }
}
