//! The one place this crate drives the flattener's projected Newton solver, and the interface
//! through which dart legs are kept at equal 2D lengths.
//!
//! Dart legs are a mating seam of one piece: the two copies of every cut edge must keep equal
//! 2D lengths, so the legs can be sewn point to point. [`EdgePairs`] names those pairs; until the
//! multi-piece flattening with seam-length equalities is available to call, they are held by
//! the solver's edge-length terms with a common target per pair, renewed from the map between
//! rounds (the targets converge to the pairs' shared length). Swapping in another seam solver
//! changes [`Solves::newton`] only. [`Solves`] keeps one analysed Newton problem per mesh for all
//! the solves on it.

use flatcut_flatten::nonlinear::kernel::{RestTri, TriEnergy};
use flatcut_flatten::nonlinear::newton::{
    self, Budget, DirectionTerm, EdgeTerms, MapProblem, Pull,
};
use flatcut_geom::DVec2;

use crate::sewn::{Closing, EdgePairs};

/// Result of a Newton run.
pub struct Run {
    /// The map: a 2D position (mm) per vertex.
    pub x: Vec<DVec2>,
    /// Newton iterations spent.
    pub iterations: usize,
}

/// Rounds of renewed pair targets.
const PAIR_ROUNDS: usize = 3;
/// The most a dart's two legs may differ in 2D length (mm): the 0.1 mm a sewn seam is held to
/// (the report's seam tolerance, `flatcut_report::DEFAULT_SEAM_TOLERANCE_MM`).
pub const LEG_MATCH_MM: f64 = 0.1;
/// What the solves aim the legs' difference at (mm): half of [`LEG_MATCH_MM`].
const LEG_TOLERANCE_MM: f64 = 0.5 * LEG_MATCH_MM;
/// Most rounds of multiplier updates after the target rounds (each is a Newton run).
const LEG_ROUNDS: usize = 6;
/// Weight of the pair length terms (relative to the faces' densities; see `EdgeTerms`): a pair
/// force of the order of a face's stress moves a target by 10⁻⁴ of its length per round.
const PAIR_WEIGHT: f64 = 1e4;
/// Newton decrement per mm² of surface below which a run has converged (as the flattener's own
/// methods).
const ABS_DECREMENT_PER_AREA: f64 = 1e-15;

/// Projected Newton solves on one mesh that share its analysed problem: the Hessian's pattern,
/// its symbolic factorisation and the scatter slots depend on the mesh alone, so they are built
/// at the first solve and kept for the next (the stages of a limit solve are dozens of solves;
/// the analysis was a sixth of each).
pub struct Solves<'a> {
    rest: &'a [RestTri],
    n: usize,
    /// The stage every solve draws on (the darts' budget).
    budget: Budget,
    problem: Option<MapProblem<'a, ()>>,
    /// Direction terms added to every solve (a grain line held).
    align: Vec<DirectionTerm>,
    /// Pulls added to every solve (darts drawn shut).
    pulls: Vec<Pull>,
    /// Triangles kept from turning over in every solve (a shut dart's legs kept apart).
    guards: Vec<[usize; 3]>,
}

impl<'a> Solves<'a> {
    /// Solves on the mesh of `rest` with `n` vertices, within the stage's `budget`.
    pub fn new(rest: &'a [RestTri], n: usize, budget: &Budget) -> Self {
        Self {
            rest,
            n,
            budget: budget.clone(),
            problem: None,
            align: Vec::new(),
            pulls: Vec::new(),
            guards: Vec::new(),
        }
    }

    /// Solves that draw darts shut (before the first solve: the pulls' vertex pairs join the
    /// Hessian's pattern then), [`Closing`].
    pub fn with_closing(mut self, c: Closing) -> Self {
        self.pulls = c.pulls;
        self.guards = c.guards;
        self
    }

    /// Solves with the direction terms `align` added to every energy.
    pub fn with_align(mut self, align: Vec<DirectionTerm>) -> Self {
        self.align = align;
        self
    }

    /// Runs projected Newton on `energy` from the flip-free map `x0` for at most `max_iters`
    /// iterations (per round when pairs are held), stopping when the energy falls by less than
    /// `rel` of itself in an iteration.
    pub fn newton<E: TriEnergy + Copy>(
        &mut self,
        energy: E,
        x0: &[DVec2],
        max_iters: usize,
        pairs: Option<&EdgePairs>,
        rel: f64,
    ) -> Result<Run, String> {
        let mut problem = match self.problem.take() {
            Some(p) => p.with_energy(energy),
            None => MapProblem::new(
                self.rest,
                self.n,
                energy,
                Some(EdgeTerms {
                    pulls: self.pulls.clone(),
                    ..Default::default()
                }),
            )?
            .with_guards(self.guards.clone()),
        };
        let abs = ABS_DECREMENT_PER_AREA * problem.total_area;
        let pairs = pairs.filter(|p| !p.pairs.is_empty());
        let Some(pairs) = pairs else {
            let (r, p) = newton::run(
                problem.with_edges((!self.align.is_empty() || !self.pulls.is_empty()).then(|| {
                    EdgeTerms {
                        align: self.align.clone(),
                        pulls: self.pulls.clone(),
                        ..Default::default()
                    }
                })),
                x0,
                max_iters,
                rel,
                abs,
                &self.budget,
            )?;
            self.problem = Some(p.with_energy(()));
            return Ok(Run {
                x: r.x,
                iterations: r.iterations,
            });
        };
        let mut x = x0.to_vec();
        let mut iterations = 0;
        for _ in 0..PAIR_ROUNDS {
            if self.budget.spent() {
                break;
            }
            let mut edges = Vec::with_capacity(2 * pairs.pairs.len());
            for [(a, b), (c, d)] in &pairs.pairs {
                let l = 0.5 * (x[*a].distance(x[*b]) + x[*c].distance(x[*d]));
                edges.push((*a, *b, l));
                edges.push((*c, *d, l));
            }
            let terms = EdgeTerms {
                align: self.align.clone(),
                pulls: self.pulls.clone(),
                lambda: vec![0.0; edges.len()],
                edges,
                weight: PAIR_WEIGHT,
                hold: None,
            };
            let (r, p) = newton::run(
                problem.with_edges(Some(terms)),
                &x,
                max_iters,
                rel,
                abs,
                &self.budget,
            )?;
            problem = p;
            iterations += r.iterations;
            x = r.x;
        }
        // A penalty alone leaves each pair apart by the force it carries over its weight: where
        // the limits press hard on a dart's flanks (a fabric at its bias limit) that adds up to
        // more than the legs may differ. The pair terms then take multipliers (an augmented
        // Lagrangian on fixed targets) until the legs meet.
        for _ in 0..LEG_ROUNDS {
            if pairs.worst_leg_mismatch(&x) <= LEG_TOLERANCE_MM || self.budget.spent() {
                break;
            }
            if let Some(t) = problem.edges.as_mut() {
                for k in 0..t.edges.len() {
                    t.lambda[k] += t.weight * t.constraint(k, &x);
                }
            }
            let (r, p) = newton::run(problem, &x, max_iters, rel, abs, &self.budget)?;
            problem = p;
            iterations += r.iterations;
            x = r.x;
        }
        self.problem = Some(problem.with_energy(()));
        Ok(Run { x, iterations })
    }
}
