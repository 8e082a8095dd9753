//! Where a flattening's wall time goes: the start map, the analysis of the sparse pattern (its
//! fill-reducing ordering and symbolic factorisation), and per Newton step the assembly of the
//! gradient and Hessian, the numeric factorisation, the triangular solves (with their
//! refinement) and the line search. Measured as the solve runs, summed over its steps; what a
//! user of a large mesh, and a benchmark, reads to see which part to look at.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Wall time per part of a solve, summed over its steps.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timings {
    /// The start map (LSCM or Tutte, with their own factorisations).
    pub start: Duration,
    /// Fill-reducing orderings and symbolic factorisations (of an isometric map's Newton
    /// system, made beside its start map, only the time it took beyond the start).
    pub ordering: Duration,
    /// Gradients, Hessians and the scatter into the sparse matrix.
    pub assembly: Duration,
    /// Numeric factorisations.
    pub factorisation: Duration,
    /// Triangular solves and their refinement.
    pub solve: Duration,
    /// Line searches (the energy along the step, the bound before the first inversion).
    pub line_search: Duration,
    /// Numeric factorisations made.
    pub factorisations: usize,
    /// Single-precision triangular solves made to refine solutions (conjugate-gradient steps,
    /// `crate::refine`; none where factors are double precision).
    pub refinements: usize,
}

impl Timings {
    /// The sum of the parts.
    pub fn total(&self) -> Duration {
        self.start
            + self.ordering
            + self.assembly
            + self.factorisation
            + self.solve
            + self.line_search
    }

    /// The time spent since `earlier` (a reading of the same clock before).
    pub fn since(&self, earlier: &Timings) -> Timings {
        Timings {
            start: self.start.saturating_sub(earlier.start),
            ordering: self.ordering.saturating_sub(earlier.ordering),
            assembly: self.assembly.saturating_sub(earlier.assembly),
            factorisation: self.factorisation.saturating_sub(earlier.factorisation),
            solve: self.solve.saturating_sub(earlier.solve),
            line_search: self.line_search.saturating_sub(earlier.line_search),
            factorisations: self.factorisations.saturating_sub(earlier.factorisations),
            refinements: self.refinements.saturating_sub(earlier.refinements),
        }
    }

    /// Adds `other`'s parts to these.
    pub fn add(&mut self, other: &Timings) {
        self.start += other.start;
        self.ordering += other.ordering;
        self.assembly += other.assembly;
        self.factorisation += other.factorisation;
        self.solve += other.solve;
        self.line_search += other.line_search;
        self.factorisations += other.factorisations;
        self.refinements += other.refinements;
    }
}

impl std::fmt::Display for Timings {
    /// "start 1.20 s, ordering 0.80 s, assembly …": the parts in the order a solve runs them
    /// (with the refinement steps of the solves where there were any).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "start {:.2} s, ordering {:.2} s, assembly {:.2} s, factorisation {:.2} s ({}), solves {:.2} s",
            self.start.as_secs_f64(),
            self.ordering.as_secs_f64(),
            self.assembly.as_secs_f64(),
            self.factorisation.as_secs_f64(),
            self.factorisations,
            self.solve.as_secs_f64(),
        )?;
        if self.refinements > 0 {
            write!(f, " ({} refinement steps)", self.refinements)?;
        }
        write!(f, ", line search {:.2} s", self.line_search.as_secs_f64())
    }
}

/// A duration that `&self` methods add to (the solves of a factor read it shared).
#[derive(Debug, Default)]
pub(crate) struct SharedDuration(AtomicU64);

impl SharedDuration {
    /// Adds the time since `since`.
    pub fn add_since(&self, since: Instant) {
        let ns = u64::try_from(since.elapsed().as_nanos()).unwrap_or(u64::MAX);
        self.0.fetch_add(ns, Ordering::Relaxed);
    }

    pub fn get(&self) -> Duration {
        Duration::from_nanos(self.0.load(Ordering::Relaxed))
    }
}
