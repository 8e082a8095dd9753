//! flatcut-testkit: the test fixtures the sender's tests and the end-to-end tests share — jobs
//! with unique line texts ([`jobs`]), the sender on a real pseudo-terminal against firmware-sim
//! ([`pty`]), and the checks that a simulator's trace is the job's motion exactly once, in order
//! ([`trace`]).
//!
//! **Architecture invariant:** only ever a dev-dependency (tests/tidy.rs checks it), so it may
//! depend on the simulator and the sender both.
#![warn(missing_docs)]

pub mod jobs;
pub mod pty;
pub mod trace;
