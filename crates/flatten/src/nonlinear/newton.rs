//! Flip-free projected Newton for isotropic distortion energies, as an argmin [`Solver`].
//!
//! Each iteration assembles the area-weighted gradient and the per-triangle analytically
//! eigen-projected Hessian (see [`super::kernel`]) into a fixed-pattern sparse matrix, solves the
//! Newton system with a sparse Cholesky whose symbolic factorisation is computed once
//! ([`super::spd`]), bounds the step before the first triangle inverts (smallest positive root
//! of det J(t) = 0 per triangle, Smith & Schaefer 2015) and backtracks to an Armijo decrease.
//! Every iterate is therefore flip-free if the start is. In the tail, where Newton converges
//! fast, or wherever a full step's decrease met its quadratic model closely (`MODEL_FIT`), a
//! chord step (the new gradient solved with the factorisation already made) follows the step,
//! and ends the solve when its decrement is below the tolerance (`CHORD_FAST`).
//! Where edge lengths are held ([`EdgeTerms::hold`]) the chord steps move their multipliers
//! too, and go on while the lengths come closer: once the map has converged only the lengths'
//! last digits are left, and those need no new factorisation (on the bench's 200k toe f1 took
//! 17 factorisations instead of 23).
//!
//! argmin drives the loop (termination, iteration cap, observers); the heavy work is our own on
//! `Vec<f64>` parameters (crates.md §2: argmin has no sparse Hessians).

use argmin::core::{
    Error as ArgminError, Executor, IterState, KV, Problem, Solver, State, TerminationReason,
    TerminationStatus, observers::Observe, observers::ObserverMode,
};
use std::time::{Duration, Instant};

use flatcut_geom::DVec2;
use rayon::prelude::*;

use super::kernel::{
    Projection, RestTri, TriEnergy, TriEval, max_step_corners, max_step_tri, tri_energy,
    tri_eval_projected,
};
use super::spd::{DIRECTION_TOL, SpdSystem};
use crate::FlattenProgress;
pub use crate::budget::Budget;
use crate::sparse::Slots;
use crate::timings::Timings;

/// Fraction of the distance to the first inversion taken as the largest trial step
/// (SLIM uses 0.8; closer than that, the barrier makes the energy explode anyway).
pub(crate) const INVERSION_STEP_FRACTION: f64 = 0.9;
/// Armijo sufficient-decrease constant.
pub(crate) const ARMIJO_C: f64 = 1e-4;
/// Backtracking halvings before the line search gives up (step 2⁻⁶⁰ is below round-off).
pub(crate) const MAX_HALVINGS: usize = 60;
/// Diagonal regularisation relative to the mean Hessian diagonal: removes the rigid-motion null
/// space of the projected Hessian without changing the step measurably.
pub(crate) const REG_REL: f64 = 1e-9;
/// Triangles per block of the parallel passes. Fixed (not derived from the thread count) so that
/// every partial sum, and therefore every bit of the result, is the same with any number of
/// threads.
const BLOCK: usize = 4096;
/// Fewest triangles one parallel task evaluates: below it the threads' hand-over costs more than
/// the work (on a 2k-face patch two threads were slower than one).
const MIN_PER_TASK: usize = 1024;
/// Relative energy decrease of a full step below which the next step tries the unprojected
/// Hessian (the tail of the solve, where it is positive definite on the whole mesh although
/// single triangles are not).
const RAW_BELOW: f64 = 1e-3;

/// Largest chord-step decrement, as a fraction of the Newton step's decrease before it, at which
/// the chord step is taken: Newton is then converging fast and the old Hessian still fits (on
/// the hard bench patches 0.1 saved one or two steps each and cost none; 0.3 cost three on the
/// mannequin).
const CHORD_FAST: f64 = 0.1;
/// Largest relative difference between a full Newton step's decrease and the decrease its
/// quadratic model predicted (its decrement) at which chord steps follow the step before the
/// tail ([`RAW_BELOW`]): where the model holds that closely the Hessian hardly changed along
/// the step, and the factorisation just made still fits the next one. On the bench's
/// million-face saddle and cap the second step's model held to 2.1 % and 1.8 %, and its chord
/// steps converged a hundredfold each, one factorisation fewer; on the toe and the hemisphere
/// the steps before the tail were off by 6–8 %, where chord steps gained only tenfold and a
/// Newton step is cheaper.
const MODEL_FIT: f64 = 0.025;
/// Most chord steps after one Newton step (each is a gradient, two triangular solves and a line
/// search: on the million-face toe four of them cost a fifth of the Newton step they save).
const MAX_CHORDS: usize = 4;
/// Fraction of the tolerance below which the next chord step's decrement, foreseen from the
/// last two, ends the solve without that step. Chord steps converge linearly, each decrement
/// the one before times a nearly steady rate (on the million-face toe 0.024, 0.033, 0.038),
/// at most [`CHORD_FAST`]: the energy left is then below a tenth of the tolerance, as after a
/// last step whose decrement was at the tolerance. On the million-face toe and saddle it saves
/// the last chord step (0.3–0.4 s), which gained 7e-11 and 2e-11 of the energy.
const FORESEEN_BELOW: f64 = 0.1;
/// Most chord steps after one Newton step while held lengths are still off
/// ([`EdgeTerms::hold`]): each must bring them [`HOLD_PROGRESS`] closer.
const MAX_HOLD_CHORDS: usize = 8;

/// Relative rise of a total energy that is within its round-off (a sum of up to millions of
/// terms in double precision).
const ROUND_OFF_REL: f64 = 1e-12;
/// Factor by which one Newton step must shrink the largest error of held lengths to count as
/// progress on them ([`EdgeTerms::hold`]).
const HOLD_PROGRESS: f64 = 0.9;

/// Edge-length terms of an augmented Lagrangian, L²·(λ c + w c²/2) with
/// c = (|x_b − x_a|² − L²)/L²: the boundary-isometric method holds its boundary with them, the
/// darts pull their legs to equal lengths. Also [`DirectionTerm`]s, which turn a vector of the
/// map towards a direction (the darts hold a grain line's direction with them).
#[derive(Clone, Debug, Default)]
pub struct EdgeTerms {
    /// (a, b, rest length L).
    pub edges: Vec<(usize, usize, f64)>,
    /// Lagrange multipliers, one per edge.
    pub lambda: Vec<f64>,
    /// Penalty weight w.
    pub weight: f64,
    /// Lengths held as constraints to this largest relative error |ℓ − L|/L: the multipliers
    /// then move with every Newton step (`EdgeTerms::follow`), and the solve does not stop on
    /// a small decrease while the lengths are further off and still coming closer. `None`: the
    /// multipliers stay as given (a penalty solve).
    pub hold: Option<f64>,
    /// Direction terms.
    pub align: Vec<DirectionTerm>,
    /// Pulls between vertex pairs.
    pub pulls: Vec<Pull>,
}

/// k·|x_b − x_a|²: a spring of zero rest length between two vertices (the darts close a dart
/// with them, drawing the two copies of each cut vertex together). Its vertex pairs join the
/// Hessian's pattern when the problem is built ([`MapProblem::new`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pull {
    /// The first vertex (0-based index into the map's positions).
    pub a: usize,
    /// The second vertex (0-based index into the map's positions).
    pub b: usize,
    /// The spring's stiffness k (energy per mm²).
    pub k: f64,
}

/// k·(v × t)² for the vector v = Σ coef_i x_{verts_i} of a triangle's corners (the image of a
/// direction of its rest frame is one: F a = Σ (g_i·a) x_i): zero when v lies along the unit
/// direction t, k·|v|² sin² of the angle between them otherwise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectionTerm {
    /// The triangle's three corner vertices (0-based indices into the map's positions).
    pub verts: [usize; 3],
    /// The weight coef_i of each corner's position in v (a rest-frame gradient component).
    pub coef: [f64; 3],
    /// The unit target direction t in the plane.
    pub t: DVec2,
    /// The term's weight k (energy per mm²).
    pub k: f64,
}

impl DirectionTerm {
    /// n = t⊥ with v × t = v·n.
    fn normal(&self) -> DVec2 {
        DVec2::new(self.t.y, -self.t.x)
    }

    /// v × t.
    fn value(&self, x: &[DVec2]) -> f64 {
        let v: DVec2 = (0..3).map(|i| self.coef[i] * x[self.verts[i]]).sum();
        v.dot(self.normal())
    }
}

impl EdgeTerms {
    /// Constraint value c_e.
    pub fn constraint(&self, e: usize, x: &[DVec2]) -> f64 {
        let (a, b, l) = self.edges[e];
        ((x[b] - x[a]).length_squared() - l * l) / (l * l)
    }

    /// Largest relative length error |ℓ − L|/L.
    pub fn max_rel_error(&self, x: &[DVec2]) -> f64 {
        self.edges
            .iter()
            .map(|&(a, b, l)| ((x[b] - x[a]).length() - l).abs() / l)
            .fold(0.0, f64::max)
    }

    /// Moves the multipliers with a Newton step `d` taken with length `t` from `x`. The Newton
    /// step of the augmented Lagrangian solves the equality-constrained problem's KKT system
    /// with the constraint rows regularised by 1/w, whose multipliers are λ + w (c + ∇c·d): the
    /// step of sequential quadratic programming (Nocedal & Wright §17.3, §18.1). Taking them
    /// with the step lets the lengths converge with the map, where a multiplier update per
    /// converged solve needs a tenfold weight or a whole solve for each digit.
    fn follow(&mut self, x: &[DVec2], d: &[DVec2], t: f64) {
        for k in 0..self.edges.len() {
            let (a, b, l) = self.edges[k];
            let linear = 2.0 * (x[b] - x[a]).dot(d[b] - d[a]) / (l * l);
            let target = self.lambda[k] + self.weight * (self.constraint(k, x) + linear);
            self.lambda[k] += t.min(1.0) * (target - self.lambda[k]);
        }
    }
    fn energy(&self, x: &[DVec2]) -> f64 {
        let mut s = 0.0;
        for e in 0..self.edges.len() {
            let l = self.edges[e].2;
            let c = self.constraint(e, x);
            s += l * l * (self.lambda[e] * c + 0.5 * self.weight * c * c);
        }
        for d in &self.align {
            let c = d.value(x);
            s += d.k * c * c;
        }
        for p in &self.pulls {
            s += p.k * (x[p.b] - x[p.a]).length_squared();
        }
        s
    }
}

/// The energy of a map: Σ_t A_t Ψ(σ(J_t)) (+ optional boundary-length terms), with the sparse
/// Newton system.
pub struct MapProblem<'a, E> {
    /// The rest frame of each triangle, in the mesh's triangle order.
    pub rest: &'a [RestTri],
    /// The per-triangle energy density Ψ.
    pub energy: E,
    /// Optional edge-length, pull and direction terms ([`EdgeTerms`]), added to the triangles'
    /// energy.
    pub edges: Option<EdgeTerms>,
    n: usize,
    sys: SpdSystem,
    /// Per triangle, the slots of its dof pairs ([`tri_slots`]), below [`SLOT_TABLE_BELOW`]
    /// triangles; above, they are looked up at each assembly.
    tri_slots: Option<Vec<[u32; 21]>>,
    edge_slots: Vec<[u32; 16]>,
    /// Per pull: the slots of its 4×4 block.
    pull_slots: Vec<[u32; 16]>,
    /// Per direction term: slot of each pair of its 6 dofs (row-major 6×6).
    align_slots: Vec<[u32; 36]>,
    /// Vertices held where they are ([`MapProblem::with_fixed`]).
    fixed: Option<Fixed>,
    /// Triangles of vertices that must not turn over, with no energy of their own
    /// ([`MapProblem::with_guards`]).
    guards: Vec<[usize; 3]>,
    /// Σ A_t, to report mean densities.
    pub total_area: f64,
    /// Time spent assembling gradients and Hessians.
    assembly_time: Duration,
}

/// Vertices a problem holds in place: their dofs, the slots of their diagonal entries, and the
/// slots of every Hessian entry that couples one of them to another dof.
struct Fixed {
    dofs: Vec<u32>,
    diag: Vec<u32>,
    coupling: Vec<u32>,
}

impl Fixed {
    fn new(sys: &SpdSystem, rest: &[RestTri], fixed: &[bool]) -> Self {
        let is_fixed = |v: usize| fixed.get(v).copied().unwrap_or(false);
        let dofs: Vec<u32> = (0..fixed.len())
            .filter(|&v| fixed[v])
            .flat_map(|v| [2 * v as u32, 2 * v as u32 + 1])
            .collect();
        let mut coupling = Vec::new();
        for r in rest.iter().filter(|r| r.v.iter().any(|&v| is_fixed(v))) {
            let dof = |p: u8| 2 * r.v[p as usize / 2] + p as usize % 2;
            for &(p, q) in &PAIRS {
                let (a, b) = (dof(p), dof(q));
                if a != b && (is_fixed(a / 2) || is_fixed(b / 2)) {
                    coupling.extend(sys.slot(a, b).map(|s| s as u32));
                }
            }
        }
        coupling.sort_unstable();
        coupling.dedup();
        let diag = dofs
            .iter()
            .map(|&d| sys.diag_slot(d as usize) as u32)
            .collect();
        Self {
            dofs,
            diag,
            coupling,
        }
    }

    /// Holds the fixed dofs: no gradient, and Hessian rows and columns that couple them to
    /// nothing (their diagonal kept, so the Newton step moves them by zero whatever the
    /// right-hand side's other entries).
    fn hold(&self, g: &mut [f64], sys: Option<&mut SpdSystem>) {
        for &d in &self.dofs {
            g[d as usize] = 0.0;
        }
        let Some(sys) = sys else { return };
        let values = sys.values_mut();
        for &s in &self.coupling {
            values[s as usize] = 0.0;
        }
        for &s in &self.diag {
            let v = values[s as usize].abs();
            values[s as usize] = if v > 0.0 { v } else { 1.0 };
        }
    }
}

/// The 21 local dof pairs (p ≤ q) of a triangle's 6×6 Hessian.
const PAIRS: [(u8, u8); 21] = {
    let mut out = [(0u8, 0u8); 21];
    let (mut p, mut k) = (0u8, 0usize);
    while p < 6 {
        let mut q = p;
        while q < 6 {
            out[k] = (p, q);
            k += 1;
            q += 1;
        }
        p += 1;
    }
    out
};

/// Triangles from which a Newton problem looks its triangles' slots up at each assembly rather
/// than keeping them in a table: the table holds 84 bytes a triangle (84 MB at a million faces,
/// the Newton solve's largest item after the factor and the matrix). The lookups cost 3 % of a
/// million-face solve's time; on the hard patches (2.6k–27k faces) one run had the small solves
/// 10–25 % slower with them and another within the noise, so small problems keep the table.
const SLOT_TABLE_BELOW: usize = 500_000;

/// The slots of a triangle's dof pairs (p ≤ q, in [`PAIRS`] order) in the system's values.
fn tri_slots(slots: Slots<'_>, r: &RestTri) -> [u32; 21] {
    let at = |dof: usize| slots.position(dof).unwrap_or(usize::MAX);
    let pos = r.v.map(|v| [at(2 * v), at(2 * v + 1)]);
    let mut a = [u32::MAX; 21];
    for (k, &(p, q)) in PAIRS.iter().enumerate() {
        let (p, q) = (p as usize, q as usize);
        if let Some(s) = slots.slot_in_order(pos[p / 2][p % 2], pos[q / 2][q % 2]) {
            a[k] = s as u32;
        }
    }
    a
}

/// The slots of each edge term's 4×4 block (both end vertices' u and v).
fn edge_slots(sys: &SpdSystem, edges: Option<&EdgeTerms>) -> Vec<[u32; 16]> {
    edges
        .map(|e| pair_slots(sys, e.edges.iter().map(|&(a, b, _)| (a, b))))
        .unwrap_or_default()
}

/// The slots of each pull's 4×4 block.
fn pull_slots(sys: &SpdSystem, edges: Option<&EdgeTerms>) -> Vec<[u32; 16]> {
    edges
        .map(|e| pair_slots(sys, e.pulls.iter().map(|p| (p.a, p.b))))
        .unwrap_or_default()
}

/// The slots of the 4×4 block (both vertices' u and v) of each vertex pair.
fn pair_slots(sys: &SpdSystem, pairs: impl Iterator<Item = (usize, usize)>) -> Vec<[u32; 16]> {
    pairs
        .map(|(a, b)| {
            let s = slots_for(sys, &[2 * a, 2 * a + 1, 2 * b, 2 * b + 1]);
            let mut o = [u32::MAX; 16];
            o.copy_from_slice(&s);
            o
        })
        .collect()
}

/// The slots of each direction term's 6×6 block (its three corners' u and v).
fn align_slots(sys: &SpdSystem, edges: Option<&EdgeTerms>) -> Vec<[u32; 36]> {
    edges
        .map(|e| {
            e.align
                .iter()
                .map(|d| {
                    let dofs = d.verts.map(|v| [2 * v, 2 * v + 1]).concat();
                    let mut o = [u32::MAX; 36];
                    o.copy_from_slice(&slots_for(sys, &dofs));
                    o
                })
                .collect()
        })
        .unwrap_or_default()
}

fn slots_for(sys: &SpdSystem, dofs: &[usize]) -> Vec<u32> {
    let k = dofs.len();
    let mut out = vec![u32::MAX; k * k];
    for p in 0..k {
        for q in 0..k {
            let (r, c) = (dofs[p], dofs[q]);
            // Each unordered pair is added once, from its upper-triangle (row ≤ col) side; the
            // dofs of one element are distinct, so r == c only on the diagonal.
            if let Some(s) = sys.slot(r, c).filter(|_| r <= c) {
                out[p * k + q] = s as u32;
            }
        }
    }
    out
}

/// The Newton system of a map on `n` vertices with these `triangles` (and `edges`' pulls): its
/// pattern, the order and the symbolic factorisation. It depends on the mesh's connectivity
/// alone, so it can be made before the rest frames, and beside the start map.
pub fn analyse(
    triangles: impl ExactSizeIterator<Item = [usize; 3]>,
    n: usize,
    edges: Option<&EdgeTerms>,
) -> Result<SpdSystem, String> {
    // Vertex pairs sharing a triangle (each vertex with itself too): the 2×2 dof blocks of
    // the pattern. Built from the edges rather than from every element entry, which would
    // hold 36 pairs per triangle at once.
    let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(triangles.len() * 3 + n);
    for v in triangles {
        for k in 0..3 {
            let (a, b) = (v[k] as u32, v[(k + 1) % 3] as u32);
            pairs.push((a.min(b), a.max(b)));
        }
    }
    pairs.extend((0..n as u32).map(|v| (v, v)));
    if let Some(e) = edges {
        for p in &e.pulls {
            let (a, b) = (p.a as u32, p.b as u32);
            pairs.push((a.min(b), a.max(b)));
        }
    }
    SpdSystem::from_vertex_pairs(n, pairs)
}

impl<'a, E> MapProblem<'a, E> {
    /// Builds the problem and the symbolic factorisation for `n` vertices.
    pub fn new(
        rest: &'a [RestTri],
        n: usize,
        energy: E,
        edges: Option<EdgeTerms>,
    ) -> Result<Self, String> {
        let sys = analyse(rest.iter().map(|r| r.v), n, edges.as_ref())?;
        Ok(Self::on_system(rest, n, energy, edges, sys))
    }

    /// [`MapProblem::new`] on the system [`analyse`] made of `rest`'s triangles (and `edges`'
    /// pulls).
    pub fn on_system(
        rest: &'a [RestTri],
        n: usize,
        energy: E,
        edges: Option<EdgeTerms>,
        sys: SpdSystem,
    ) -> Self {
        let tri_slots = (rest.len() < SLOT_TABLE_BELOW).then(|| {
            let slots = sys.slots();
            rest.par_iter().map(|r| tri_slots(slots, r)).collect()
        });
        let edge_slots = edge_slots(&sys, edges.as_ref());
        let pull_slots = pull_slots(&sys, edges.as_ref());
        let align_slots = align_slots(&sys, edges.as_ref());
        let total_area = rest.iter().map(|r| r.area).sum();
        Self {
            rest,
            energy,
            edges,
            n,
            sys,
            tri_slots,
            edge_slots,
            pull_slots,
            align_slots,
            fixed: None,
            guards: Vec::new(),
            total_area,
            assembly_time: Duration::ZERO,
        }
    }

    /// The same problem with the triangles `guards` (counter-clockwise in the maps it will be
    /// solved from) kept from turning over, as the mesh's own are: the darts keep a dart's legs
    /// from crossing with them.
    pub fn with_guards(mut self, guards: Vec<[usize; 3]>) -> Self {
        self.guards = guards;
        self
    }

    /// The same problem with the vertices marked in `fixed` held where the map puts them
    /// (a Dirichlet problem): their Newton steps are zero.
    pub fn with_fixed(mut self, fixed: &[bool]) -> Self {
        self.fixed = fixed
            .iter()
            .any(|&f| f)
            .then(|| Fixed::new(&self.sys, self.rest, fixed));
        self
    }

    /// The same problem with another energy. The pattern, its symbolic factorisation and the
    /// scatter slots depend on the mesh alone and are kept: a sequence of solves on one mesh
    /// (the stages of a continuation) analyses it once.
    pub fn with_energy<F>(self, energy: F) -> MapProblem<'a, F> {
        MapProblem {
            rest: self.rest,
            energy,
            edges: self.edges,
            n: self.n,
            sys: self.sys,
            tri_slots: self.tri_slots,
            edge_slots: self.edge_slots,
            pull_slots: self.pull_slots,
            align_slots: self.align_slots,
            fixed: self.fixed,
            guards: self.guards,
            total_area: self.total_area,
            assembly_time: self.assembly_time,
        }
    }

    /// The same problem with other edge terms (`None`: none); as in [`MapProblem::new`], only
    /// the entries of edges in the mesh's pattern enter the Hessian.
    pub fn with_edges(mut self, edges: Option<EdgeTerms>) -> Self {
        self.edge_slots = edge_slots(&self.sys, edges.as_ref());
        self.pull_slots = pull_slots(&self.sys, edges.as_ref());
        self.align_slots = align_slots(&self.sys, edges.as_ref());
        self.edges = edges;
        self
    }
}

impl<'a, E: TriEnergy> MapProblem<'a, E> {
    /// Total energy (+∞ if a barrier energy sees an inverted triangle).
    pub fn total_energy(&self, x: &[DVec2]) -> f64 {
        let energy = &self.energy;
        let partial: Vec<f64> = self
            .rest
            .par_chunks(BLOCK)
            .map(|c| c.iter().map(|r| tri_energy(energy, r, x)).sum())
            .collect();
        let mut s: f64 = partial.iter().sum();
        if let Some(e) = &self.edges {
            s += e.energy(x);
        }
        s
    }

    /// Largest step along `d` before any triangle inverts.
    pub fn max_step(&self, x: &[DVec2], d: &[DVec2]) -> f64 {
        let mesh = self
            .rest
            .par_chunks(BLOCK)
            .map(|c| {
                c.iter()
                    .map(|r| max_step_tri(r, x, d))
                    .fold(f64::INFINITY, f64::min)
            })
            .reduce(|| f64::INFINITY, f64::min);
        self.guards
            .iter()
            .map(|&v| max_step_corners(v, x, d))
            .fold(mesh, f64::min)
    }

    /// Assembles gradient (returned) and the projected Hessian (into the system); returns the
    /// energy too. The triangles are evaluated in parallel, block by block, while the previous
    /// block is scattered in triangle order, so every sum is formed in the same order as by a
    /// sequential loop: the result does not depend on the number of threads.
    ///
    /// With `proj` `None` only the energy and gradient are formed: the system, and the
    /// factorisation of the last Hessian, are left as they are.
    fn assemble(&mut self, x: &[DVec2], proj: Option<Projection>) -> (f64, Vec<f64>) {
        let started = Instant::now();
        let out = self.assemble_untimed(x, proj);
        self.assembly_time += started.elapsed();
        out
    }

    /// Where this problem's time went: its assemblies and its system's analysis, factorisations
    /// and solves.
    pub fn timings(&self) -> Timings {
        Timings {
            assembly: self.assembly_time,
            ..self.sys.timings()
        }
    }

    /// [`MapProblem::assemble`], untimed.
    fn assemble_untimed(&mut self, x: &[DVec2], proj: Option<Projection>) -> (f64, Vec<f64>) {
        let mut g = vec![0.0; 2 * self.n];
        let hessian = proj.is_some();
        if hessian {
            self.sys.clear();
        }
        let mut en = 0.0;
        let (rest, energy) = (self.rest, &self.energy);
        // Without the Hessian the values are left alone, and with them the factorisation.
        let (slots, values) = if hessian {
            let (s, v) = self.sys.slots_and_values_mut();
            (Some(s), v)
        } else {
            (None, &mut [][..])
        };
        let table = self.tri_slots.as_deref();
        let eval = |b: usize| -> Vec<(TriEval, [u32; 21])> {
            let lo = (b * BLOCK).min(rest.len());
            let hi = ((b + 1) * BLOCK).min(rest.len());
            rest[lo..hi]
                .par_iter()
                .enumerate()
                .with_min_len(MIN_PER_TASK)
                .map(|(k, r)| {
                    let slots = match (table, slots) {
                        (Some(t), Some(_)) => t[lo + k],
                        (None, Some(s)) => tri_slots(s, r),
                        _ => [u32::MAX; 21],
                    };
                    (tri_eval_projected(energy, r, x, proj), slots)
                })
                .collect()
        };
        let blocks = rest.len().div_ceil(BLOCK);
        let mut cur = eval(0);
        for b in 0..blocks {
            let scatter =
                |evs: &[(TriEval, [u32; 21])], g: &mut [f64], en: &mut f64, values: &mut [f64]| {
                    for (k, (ev, slots)) in evs.iter().enumerate() {
                        let r = &rest[b * BLOCK + k];
                        *en += ev.energy;
                        for c in 0..3 {
                            g[2 * r.v[c]] += ev.grad[c].x;
                            g[2 * r.v[c] + 1] += ev.grad[c].y;
                        }
                        if !hessian {
                            continue;
                        }
                        for (s, &(p, q)) in slots.iter().zip(PAIRS.iter()) {
                            if *s != u32::MAX {
                                values[*s as usize] += ev.hess[p as usize][q as usize];
                            }
                        }
                    }
                };
            let (_, next) = rayon::join(
                || scatter(&cur, &mut g, &mut en, values),
                || {
                    if b + 1 < blocks {
                        eval(b + 1)
                    } else {
                        Vec::new()
                    }
                },
            );
            cur = next;
        }
        if let Some(e) = &self.edges {
            for (k, &(a, b, l)) in e.edges.iter().enumerate() {
                let d = x[b] - x[a];
                let c = e.constraint(k, x);
                en += l * l * (e.lambda[k] * c + 0.5 * e.weight * c * c);
                let m = e.lambda[k] + e.weight * c;
                // Hessian w.r.t. d: 4w d dᵀ/L² + 2 max(m, 0) I.
                let h = hessian.then(|| {
                    let dd = [d.x, d.y];
                    let mut h = [[0.0; 2]; 2];
                    for i in 0..2 {
                        for j in 0..2 {
                            h[i][j] = 4.0 * e.weight * dd[i] * dd[j] / (l * l)
                                + if i == j { 2.0 * m.max(0.0) } else { 0.0 };
                        }
                    }
                    (h, &self.edge_slots[k], self.sys.values_mut())
                });
                add_pair_terms(&mut g, (a, b), 2.0 * m * d, h);
            }
            // Direction terms: c = v·n, linear in the corners (∂c/∂x_i = coef_i n); energy
            // k c², gradient 2k c coef_i n, Hessian 2k coef_i coef_j n nᵀ.
            for (j, d) in e.align.iter().enumerate() {
                let n = d.normal();
                let c = d.value(x);
                en += d.k * c * c;
                for i in 0..3 {
                    let gi = 2.0 * d.k * c * d.coef[i] * n;
                    g[2 * d.verts[i]] += gi.x;
                    g[2 * d.verts[i] + 1] += gi.y;
                }
                if !hessian {
                    continue;
                }
                let nn = [n.x, n.y];
                let slots = &self.align_slots[j];
                for p in 0..6 {
                    for q in 0..6 {
                        let s = slots[p * 6 + q];
                        if s != u32::MAX {
                            let h = 2.0 * d.k * d.coef[p / 2] * d.coef[q / 2];
                            self.sys.values_mut()[s as usize] += h * nn[p % 2] * nn[q % 2];
                        }
                    }
                }
            }
            // Pulls: energy k|d|² with d = x_b − x_a; gradient ∓2k d, Hessian 2k [I −I; −I I].
            for (j, p) in e.pulls.iter().enumerate() {
                let d = x[p.b] - x[p.a];
                en += p.k * d.length_squared();
                let h = hessian.then(|| {
                    let k2 = 2.0 * p.k;
                    (
                        [[k2, 0.0], [0.0, k2]],
                        &self.pull_slots[j],
                        self.sys.values_mut(),
                    )
                });
                add_pair_terms(&mut g, (p.a, p.b), 2.0 * p.k * d, h);
            }
        }
        if let Some(f) = &self.fixed {
            f.hold(&mut g, hessian.then_some(&mut self.sys));
        }
        (en, g)
    }
}

/// Adds a term of d = x_b − x_a to the gradient (∂/∂d = `gd`: −gd at a, +gd at b) and, when
/// the Hessian is assembled, its Hessian `h` (2×2 in d) as the block [h −h; −h h] at the pair's
/// `slots` of the system's `values` (taken only then: taking them drops the factor).
fn add_pair_terms(
    g: &mut [f64],
    (a, b): (usize, usize),
    gd: DVec2,
    h: Option<([[f64; 2]; 2], &[u32; 16], &mut [f64])>,
) {
    g[2 * a] -= gd.x;
    g[2 * a + 1] -= gd.y;
    g[2 * b] += gd.x;
    g[2 * b + 1] += gd.y;
    let Some((h, slots, values)) = h else {
        return;
    };
    for p in 0..4 {
        for q in 0..4 {
            let s = slots[p * 4 + q];
            if s != u32::MAX {
                let sign = if (p < 2) == (q < 2) { 1.0 } else { -1.0 };
                values[s as usize] += sign * h[p % 2][q % 2];
            }
        }
    }
}

/// Converts interleaved coordinates to points.
pub fn to_points(p: &[f64]) -> Vec<DVec2> {
    p.chunks_exact(2).map(|c| DVec2::new(c[0], c[1])).collect()
}

/// Converts points to interleaved coordinates.
pub fn to_flat(x: &[DVec2]) -> Vec<f64> {
    x.iter().flat_map(|p| [p.x, p.y]).collect()
}

/// Why a Newton run stopped before convergence, if it did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EarlyStop {
    /// The caller's cancel flag was set.
    Cancelled,
    /// The time limit ran out.
    TimeLimit,
}

/// Projected Newton with the flip-free line search.
#[derive(Clone, Debug)]
pub struct ProjectedNewton {
    /// Stop when the energy decreases by less than this fraction in one iteration.
    pub rel_tolerance: f64,
    /// Stop when the Newton decrement −g·d/2 falls below this (absolute, energy units).
    pub abs_tolerance: f64,
    last_decrease: f64,
    last_decrement: f64,
    stalled: bool,
    /// Set when a chord step showed that a further Newton step would gain less than the
    /// tolerance.
    converged: bool,
    /// How the next step projects the triangles' Hessians.
    projection: Projection,
    budget: Budget,
    max_iters: usize,
    early: Option<EarlyStop>,
    /// False while held edge lengths ([`EdgeTerms::hold`]) are off by more than asked and the
    /// last step brought them closer: the solve may not stop on a small decrease then.
    settled_lengths: bool,
    /// Time spent in line searches.
    line_search_time: Duration,
    /// How closely a full step's decrease must meet its model for chord steps to follow it
    /// before the tail ([`MODEL_FIT`]).
    model_fit: f64,
    /// Whether a chord step foreseen to gain less than the tolerance is left out
    /// ([`FORESEEN_BELOW`]).
    foresee: bool,
    /// How closely each Newton direction is solved ([`Forcing`]).
    forcing: Forcing,
}

/// Largest relative residual of an inexact Newton direction ([`Forcing`]). One refinement
/// step of a single-precision factor gets there on the million-face bench meshes; Eisenstat and
/// Walker allow up to 0.9, which a line search bounded by inversions would pay for in steps.
const FORCING_MAX: f64 = 0.1;
/// γ of the forcing term ([`Forcing`]), Eisenstat and Walker's choice 2.
const FORCING_GAMMA: f64 = 0.9;
/// α of the forcing term ([`Forcing`]), Eisenstat and Walker's choice 2.
const FORCING_ALPHA: f64 = 2.0;
/// Forcing terms whose safeguard applies ([`Forcing`]): above it, η may fall no faster than
/// γ times the one before squared.
const FORCING_SAFEGUARD: f64 = 0.1;

/// The relative residual each Newton direction is solved to: inexact Newton, with Eisenstat
/// and Walker's (1996) choice 2 of the forcing term and its safeguard,
/// η_k = max(γ (‖g_k‖/‖g_{k−1}‖)^α, γ η_{k−1}^α where that is above [`FORCING_SAFEGUARD`]),
/// within [[`DIRECTION_TOL`], [`FORCING_MAX`]], the first at [`FORCING_MAX`]. Far from the
/// minimum the gradient falls slowly and a step needs a digit of its direction, not four; as
/// Newton converges the gradient falls fast and η with it, to the full tolerance in the tail,
/// where the chord steps that decide convergence are solved to it too. Only refined solves
/// (single-precision factors, million-face maps) heed it: an exact solve costs the same at any
/// residual. On the million-face toe it saved 4 of 11 refinement steps (one single-precision
/// triangular solve pair each), to the same energy within 2e-12.
#[derive(Clone, Debug)]
struct Forcing {
    /// ‖g‖ of the last direction, and the η it was solved to.
    last: Option<(f64, f64)>,
    /// Largest η ([`DIRECTION_TOL`] or less: every direction to [`DIRECTION_TOL`]).
    max: f64,
}

impl Forcing {
    fn new(max: f64) -> Self {
        Self { last: None, max }
    }

    /// The relative residual of the direction at a gradient of norm `g`; the same again at the
    /// same gradient, where a direction is solved again with another projection (the
    /// unprojected Hessian indefinite: clamped instead), so the fallback is not taken as a
    /// gradient that did not fall and solved to [`FORCING_MAX`].
    fn next(&mut self, g: f64) -> f64 {
        let eta = match self.last {
            None => self.max,
            Some((g0, eta0)) if g0 == g => return eta0,
            Some((g0, eta0)) => {
                let eta = FORCING_GAMMA * (g / g0).powf(FORCING_ALPHA);
                let safeguard = FORCING_GAMMA * eta0.powf(FORCING_ALPHA);
                if safeguard > FORCING_SAFEGUARD {
                    eta.max(safeguard)
                } else {
                    eta
                }
            }
        };
        let eta = if eta.is_nan() {
            self.max
        } else {
            eta.min(self.max)
        }
        .max(DIRECTION_TOL);
        self.last = Some((g, eta));
        eta
    }
}

impl ProjectedNewton {
    /// A solver stopping at relative decrease `rel_tolerance` or Newton decrement `abs_tolerance` (energy units), capped at `max_iters` iterations within `budget`.
    pub fn new(rel_tolerance: f64, abs_tolerance: f64, budget: Budget, max_iters: usize) -> Self {
        Self {
            rel_tolerance,
            abs_tolerance,
            last_decrease: f64::INFINITY,
            last_decrement: f64::INFINITY,
            stalled: false,
            converged: false,
            projection: Projection::Abs,
            budget,
            max_iters,
            early: None,
            settled_lengths: true,
            line_search_time: Duration::ZERO,
            model_fit: MODEL_FIT,
            foresee: true,
            forcing: Forcing::new(FORCING_MAX),
        }
    }

    /// The step taken where the line search saw no decrease while held lengths are off by more
    /// than asked: once the map has converged, the energy the lengths still change is below the
    /// round-off of the total, and no decrease can be seen. The full step (short of an
    /// inversion) is taken if it brings the lengths closer without a rise beyond that round-off.
    fn round_off_step<E: TriEnergy>(
        &self,
        p: &MapProblem<'_, E>,
        x: &[DVec2],
        d: &[DVec2],
        e0: f64,
        tmax: f64,
    ) -> Option<(f64, Vec<DVec2>, f64)> {
        let e = p.edges.as_ref()?;
        let hold = e.hold?;
        let before = e.max_rel_error(x);
        if before <= hold {
            return None;
        }
        let t = (INVERSION_STEP_FRACTION * tmax).min(1.0);
        let xn: Vec<DVec2> = x.iter().zip(d).map(|(a, b)| *a + t * *b).collect();
        let en = p.total_energy(&xn);
        let flat = en.is_finite() && en - e0 <= ROUND_OFF_REL * e0.abs();
        (flat && e.max_rel_error(&xn) < before).then_some((t, xn, en))
    }
}

type NState = IterState<Vec<f64>, (), (), (), (), f64>;

impl<E: TriEnergy> Solver<MapProblem<'_, E>, NState> for ProjectedNewton {
    fn name(&self) -> &str {
        "flip-free projected Newton"
    }

    fn init(
        &mut self,
        problem: &mut Problem<MapProblem<'_, E>>,
        state: NState,
    ) -> Result<(NState, Option<KV>), ArgminError> {
        let p = problem
            .problem
            .as_ref()
            .ok_or_else(|| argmin::core::Error::msg("no problem"))?;
        let x0 = state
            .get_param()
            .ok_or_else(|| argmin::core::Error::msg("no initial map"))?;
        let e = p.total_energy(&to_points(x0));
        if !e.is_finite() {
            return Err(argmin::core::Error::msg(
                "the initial map has an inverted or degenerate triangle",
            ));
        }
        Ok((state.cost(e), None))
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<MapProblem<'_, E>>,
        mut state: NState,
    ) -> Result<(NState, Option<KV>), ArgminError> {
        let p = problem
            .problem
            .as_mut()
            .ok_or_else(|| argmin::core::Error::msg("no problem"))?;
        let xf = state
            .take_param()
            .ok_or_else(|| argmin::core::Error::msg("no parameter"))?;
        let x = to_points(&xf);
        // Near convergence the unprojected Hessian, if positive definite, gives Newton's
        // quadratic convergence where the projected one (stiffer than the energy wherever it
        // clamped a mode) converges only linearly; where it is indefinite, clamp.
        let mut step = newton_direction(p, &x, self.projection, &mut self.forcing);
        if self.projection == Projection::Raw && step.2.is_none() {
            step = newton_direction(p, &x, Projection::Clamp, &mut self.forcing);
        }
        let (e0, g, dir) = step;
        let (mut dir, mut gd) = match dir {
            Some(d) => {
                let gd: f64 = g.iter().zip(&d).map(|(a, b)| a * b).sum();
                (d, gd)
            }
            None => (Vec::new(), 0.0),
        };
        if dir.is_empty() || gd.is_nan() || gd >= 0.0 {
            // Fall back to steepest descent (should not happen with a PSD Hessian).
            dir = g.iter().map(|v| -v).collect();
            gd = -g.iter().map(|v| v * v).sum::<f64>();
        }
        let d = to_points(&dir);
        let searching = Instant::now();
        let tmax = p.max_step(&x, &d);
        let found = line_search(p, &x, &d, e0, gd, tmax)
            .filter(|f| f.2 < e0)
            .or_else(|| self.round_off_step(p, &x, &d, e0, tmax));
        self.line_search_time += searching.elapsed();
        self.last_decrement = -0.5 * gd;
        let Some((t, mut xn, mut en)) = found else {
            self.stalled = true;
            return Ok((state.param(xf).cost(e0), None));
        };
        tracing::trace!(
            step = t,
            tmax,
            projection = ?self.projection,
            decrease = e0 - en,
            predicted = -t * gd * (1.0 - 0.5 * t),
            "newton step"
        );
        self.last_decrease = e0 - en;
        let held_before = p
            .edges
            .as_ref()
            .and_then(|e| e.hold.map(|_| e.max_rel_error(&x)));
        if let Some(e) = p.edges.as_mut().filter(|e| e.hold.is_some()) {
            // The decrease above was measured with the old multipliers; the energy carried on
            // is the new ones'.
            e.follow(&x, &d, t);
            en = p.total_energy(&xn);
        }
        // In the tail, and after a full step whose quadratic model held closely
        // ([`MODEL_FIT`]), the factorisation just used still inverts the Hessian well: the
        // chord step it gives (gradient at the new map, old factor) is nearly a Newton
        // step for the price of a gradient. It is taken where its decrement, which predicts the
        // next Newton step's gain, shows fast convergence (at most [`CHORD_FAST`] of this step's
        // decrease); where it is below the tolerance the solve ends without another
        // factorisation.
        let tail = self.last_decrease < RAW_BELOW * en.abs();
        // Not while lengths are held: their chord steps follow the multipliers (below).
        let model_fits = p.edges.as_ref().is_none_or(|e| e.hold.is_none())
            && (self.last_decrease / self.last_decrement - 1.0).abs() <= self.model_fit;
        if t == 1.0 && (tail || model_fits) {
            let tolerance = self.abs_tolerance.max(self.rel_tolerance * en.abs());
            // While the chord steps keep converging fast (each gaining at most CHORD_FAST of
            // the step before), the next one too reuses the factorisation: a few of them cost
            // less than one more Newton step's assembly and factorisation. While held lengths
            // are still off, the chord steps move the multipliers too and go on while they
            // bring the lengths closer (the map has converged; what is left is the lengths').
            let mut gained = self.last_decrease;
            let mut held = held_error(p, &xn);
            let most = if held.is_some() {
                MAX_HOLD_CHORDS
            } else {
                MAX_CHORDS
            };
            // The decrement of the chord step before.
            let mut before: Option<f64> = None;
            for _ in 0..most {
                let take = tolerance.max(CHORD_FAST * gained);
                let Some(c) =
                    chord_step(p, &xn, en, take, held.is_some(), &mut self.line_search_time)
                else {
                    break;
                };
                gained = en - c.energy;
                (xn, en) = (c.x, c.energy);
                self.last_decrease = e0 - en;
                // Foreseen: this decrement times the rate of the last two.
                let next = before.map_or(f64::INFINITY, |b| c.decrement * (c.decrement / b));
                self.converged = c.decrement <= tolerance
                    || (self.foresee
                        && held.is_none()
                        && gained > 0.0
                        && next <= FORESEEN_BELOW * tolerance);
                before = Some(c.decrement);
                if let Some(before) = held {
                    held = held_error(p, &xn).filter(|&now| now <= HOLD_PROGRESS * before);
                    if held.is_some() {
                        continue;
                    }
                    break;
                }
                if self.converged || gained <= 0.0 {
                    break;
                }
            }
        }
        if let (Some(e), Some(before)) = (&p.edges, held_before) {
            let now = e.max_rel_error(&xn);
            self.settled_lengths = e.hold.is_none_or(|h| now <= h) || now > HOLD_PROGRESS * before;
        }
        // The quadratic model predicts a decrease of −t g·d (1 − t/2) along the Newton step
        // (dᵀHd = −g·d); where it is met, the model is trusted and the next step clamps.
        self.projection = if t < 1.0 {
            // Bounded by an inversion or cut back: the model does not see the barrier.
            Projection::Abs
        } else if self.last_decrease < RAW_BELOW * en.abs() {
            Projection::Raw
        } else {
            Projection::Clamp
        };
        self.budget.hooks.report(&FlattenProgress {
            stage: self.budget.stage,
            iteration: state.get_iter() as usize + 1,
            max_iterations: self.max_iters,
            energy: en,
            elapsed: self.budget.started.elapsed(),
        });
        // argmin's key-value record is a HashMap inside argmin; only observers read it, never
        // the iterates, so its order cannot reach any output.
        #[allow(clippy::disallowed_types)]
        let kv = argmin::kv!("step" => t; "tmax" => tmax; "decrement" => self.last_decrement;);
        Ok((state.param(to_flat(&xn)).cost(en), Some(kv)))
    }

    fn terminate(&mut self, state: &NState) -> TerminationStatus {
        if self.stalled || (self.converged && self.settled_lengths) {
            return TerminationStatus::Terminated(TerminationReason::SolverConverged);
        }
        if self.budget.hooks.cancelled() {
            self.early = Some(EarlyStop::Cancelled);
            return TerminationStatus::Terminated(TerminationReason::SolverExit(
                "cancelled".into(),
            ));
        }
        if self.budget.expired() {
            self.early = Some(EarlyStop::TimeLimit);
            return TerminationStatus::Terminated(TerminationReason::SolverExit(
                "time limit".into(),
            ));
        }
        let e = state.get_cost();
        if state.get_iter() > 0
            && self.settled_lengths
            && (self.last_decrease <= self.rel_tolerance * e.abs()
                || self.last_decrement <= self.abs_tolerance)
        {
            return TerminationStatus::Terminated(TerminationReason::SolverConverged);
        }
        TerminationStatus::NotTerminated
    }
}

/// Assembles at `x` with `proj` and solves for the Newton direction to the relative residual
/// `forcing` gives (where solves are refined): energy, gradient and the direction (`None` if
/// the system could not be solved). A projected Hessian is only positive
/// semi-definite (rigid motions), so a small diagonal shift is added and raised until the
/// factorisation succeeds; the unprojected one gets one try.
fn newton_direction<E: TriEnergy>(
    p: &mut MapProblem<'_, E>,
    x: &[DVec2],
    proj: Projection,
    forcing: &mut Forcing,
) -> (f64, Vec<f64>, Option<Vec<f64>>) {
    let (e0, g) = p.assemble(x, Some(proj));
    let tol = forcing.next(norm(&g));
    p.sys.set_direction_tol(tol);
    let ndof = g.len();
    let mean_diag = (0..ndof)
        .map(|i| p.sys.values()[p.sys.diag_slot(i)])
        .sum::<f64>()
        / ndof as f64;
    let tries = if proj == Projection::Raw { 1 } else { 8 };
    let reg = REG_REL * mean_diag.max(f64::MIN_POSITIVE);
    let minus_g: Vec<f64> = g.iter().map(|v| -v).collect();
    let dir = p.sys.solve_shifted(&minus_g, reg, tries);
    // Chord steps, made with this factorisation, decide convergence: to the full tolerance.
    p.sys.set_direction_tol(DIRECTION_TOL);
    (e0, g, dir)
}

/// The Euclidean norm of `v`.
fn norm(v: &[f64]) -> f64 {
    v.iter().map(|a| a * a).sum::<f64>().sqrt()
}

/// A chord step: the map after it and its decrement.
struct Chord {
    x: Vec<DVec2>,
    energy: f64,
    /// −g·d/2 at the start of the step.
    decrement: f64,
}

/// The largest relative error of the lengths a problem holds ([`EdgeTerms::hold`]) while it is
/// above what is asked; `None` when no lengths are held or they are held closely enough.
fn held_error<E>(p: &MapProblem<'_, E>, x: &[DVec2]) -> Option<f64> {
    let e = p.edges.as_ref()?;
    let hold = e.hold?;
    Some(e.max_rel_error(x)).filter(|&now| now > hold)
}

/// A chord step from `x` (energy `e`): the direction from the last factorised Hessian and the
/// gradient at `x`, taken when its decrement −g·d/2 is at most `take` (the map stays `x` where no
/// step along it decreases the energy any more); `None` when the decrement is larger or the
/// factorisation cannot be reused. With `follow` the held lengths' multipliers move with the
/// step ([`EdgeTerms::follow`]), and a step whose energy is level with `e` within its round-off
/// is taken (near the constrained optimum what the lengths still change is below it).
fn chord_step<E: TriEnergy>(
    p: &mut MapProblem<'_, E>,
    x: &[DVec2],
    e: f64,
    take: f64,
    follow: bool,
    line_search_time: &mut Duration,
) -> Option<Chord> {
    let (_, g) = p.assemble(x, None);
    let mut dir: Vec<f64> = g.iter().map(|v| -v).collect();
    p.sys.solve_factored(&mut dir).ok()?;
    let gd: f64 = g.iter().zip(&dir).map(|(a, b)| a * b).sum();
    let decrement = -0.5 * gd;
    if !(gd < 0.0 && decrement <= take) {
        return None;
    }
    let d = to_points(&dir);
    let searching = Instant::now();
    let tmax = p.max_step(x, &d);
    let found = match line_search(p, x, &d, e, gd, tmax) {
        Some((t, xc, ec)) if ec < e => Some((t, xc, ec)),
        _ if follow => {
            let t = (INVERSION_STEP_FRACTION * tmax).min(1.0);
            let xc: Vec<DVec2> = x.iter().zip(&d).map(|(a, b)| *a + t * *b).collect();
            let ec = p.total_energy(&xc);
            (ec.is_finite() && ec - e <= ROUND_OFF_REL * e.abs()).then_some((t, xc, ec))
        }
        _ => None,
    };
    *line_search_time += searching.elapsed();
    let (x, energy) = match found {
        Some((t, xc, ec)) => match p.edges.as_mut().filter(|_| follow) {
            Some(edges) => {
                edges.follow(x, &d, t);
                let ec = p.total_energy(&xc);
                (xc, ec)
            }
            None => (xc, ec),
        },
        None => (x.to_vec(), e),
    };
    Some(Chord {
        x,
        energy,
        decrement,
    })
}

/// Largest number of step doublings past the Newton step.
const MAX_DOUBLINGS: usize = 30;

/// The flip-free line search along `d` from `x` (energy `e0`, slope `gd` < 0): the Newton step
/// (t = 1), or 90 % of the way to the first inversion if that is shorter, halved until the
/// Armijo condition holds. Where the full step was accepted and the first inversion is farther,
/// the step is doubled while the energy keeps falling: far from the optimum a barrier term 1/σ²
/// lets Newton grow a crushed triangle by only a third per step (the model underestimates the
/// decrease), and doubling covers in one step what would otherwise take many (not while held
/// lengths' multipliers follow the step, [`EdgeTerms::hold`]). Returns the step,
/// the new map and its energy, or `None` if no step decreases the energy enough.
fn line_search<E: TriEnergy>(
    p: &MapProblem<'_, E>,
    x: &[DVec2],
    d: &[DVec2],
    e0: f64,
    gd: f64,
    tmax: f64,
) -> Option<(f64, Vec<DVec2>, f64)> {
    let limit = INVERSION_STEP_FRACTION * tmax;
    let step = |t: f64| -> Vec<DVec2> { x.iter().zip(d).map(|(a, b)| *a + t * *b).collect() };
    let armijo = |t: f64, e: f64| e.is_finite() && e <= e0 + ARMIJO_C * t * gd;
    let mut t = limit.min(1.0);
    for _ in 0..MAX_HALVINGS {
        let xn = step(t);
        let en = p.total_energy(&xn);
        if armijo(t, en) {
            let mut best = (t, xn, en);
            // Not while lengths are held: their multipliers follow the Newton step, which a
            // longer one overshoots.
            let holding = p.edges.as_ref().is_some_and(|e| e.hold.is_some());
            if t == 1.0 && !holding {
                for _ in 0..MAX_DOUBLINGS {
                    let t2 = (2.0 * best.0).min(limit);
                    if t2 <= best.0 {
                        break;
                    }
                    let x2 = step(t2);
                    let e2 = p.total_energy(&x2);
                    if !(armijo(t2, e2) && e2 < best.2) {
                        break;
                    }
                    best = (t2, x2, e2);
                }
            }
            return Some(best);
        }
        t *= 0.5;
    }
    None
}

/// Logs the progress of a solve through `tracing` (debug level).
#[derive(Clone, Copy, Debug, Default)]
pub struct TraceObserver;

impl Observe<NState> for TraceObserver {
    fn observe_iter(&mut self, state: &NState, kv: &KV) -> Result<(), ArgminError> {
        tracing::debug!(
            iter = state.get_iter(),
            energy = state.get_cost(),
            ?kv,
            "newton"
        );
        Ok(())
    }
}

/// Result of a Newton run.
pub struct NewtonRun {
    /// The final map: one 2D position (mm) per vertex, indexed like the start map.
    pub x: Vec<DVec2>,
    /// The energy of the final map.
    pub energy: f64,
    /// Newton iterations taken.
    pub iterations: usize,
    /// Set when the run stopped at the caller's request rather than by convergence.
    pub early: Option<EarlyStop>,
    /// Where the run's time went (with the problem's analysis when the run was its first).
    pub timings: Timings,
}

/// Runs projected Newton from the flip-free map `x0`, for at most `max_iters` iterations and
/// what the stage's `budget` has left.
pub fn run<'a, E: TriEnergy>(
    problem: MapProblem<'a, E>,
    x0: &[DVec2],
    max_iters: usize,
    rel_tolerance: f64,
    abs_tolerance: f64,
    budget: &Budget,
) -> Result<(NewtonRun, MapProblem<'a, E>), String> {
    run_flat(
        problem,
        to_flat(x0),
        max_iters,
        rel_tolerance,
        abs_tolerance,
        budget,
    )
}

/// [`run`] from the start given as `[u₀, v₀, u₁, v₁, …]` ([`to_flat`]), taken over: a caller
/// done with its start map frees it before the solve (8 MB at a million faces).
pub fn run_flat<'a, E: TriEnergy>(
    problem: MapProblem<'a, E>,
    x0: Vec<f64>,
    max_iters: usize,
    rel_tolerance: f64,
    abs_tolerance: f64,
    budget: &Budget,
) -> Result<(NewtonRun, MapProblem<'a, E>), String> {
    let max_iters = budget.allow(max_iters);
    let solver = ProjectedNewton::new(rel_tolerance, abs_tolerance, budget.clone(), max_iters);
    run_solver(problem, x0, solver, budget)
}

/// [`run_flat`] with `solver`, made for `budget`.
fn run_solver<'a, E: TriEnergy>(
    problem: MapProblem<'a, E>,
    x0: Vec<f64>,
    solver: ProjectedNewton,
    budget: &Budget,
) -> Result<(NewtonRun, MapProblem<'a, E>), String> {
    let max_iters = solver.max_iters;
    let mut before = problem.timings();
    if before.factorisations == 0 {
        // The problem's first run: its analysis is this run's.
        before.ordering = Duration::ZERO;
    }
    let res = Executor::new(problem, solver)
        .configure(|s| s.param(x0).max_iters(max_iters as u64))
        .add_observer(TraceObserver, ObserverMode::Always)
        .timer(false)
        .run()
        .map_err(|e| e.to_string())?;
    let early = res.solver.early;
    let line_search = res.solver.line_search_time;
    let state = res.state();
    let iterations = state.get_iter() as usize;
    budget.spend(iterations);
    let energy = state.get_cost();
    let x = state
        .get_param()
        .map(|p| to_points(p))
        .ok_or_else(|| "no result".to_string())?;
    let mut res = res;
    let problem = res
        .problem
        .take_problem()
        .ok_or_else(|| "problem lost".to_string())?;
    let timings = Timings {
        line_search,
        ..problem.timings().since(&before)
    };
    Ok((
        NewtonRun {
            x,
            energy,
            iterations,
            early,
            timings,
        },
        problem,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nonlinear::kernel::SymDirichlet;
    use crate::nonlinear::{ABS_DECREMENT_PER_AREA, init, rest_frames};
    use crate::testmesh::{saddle_of_radius, slivered, spherical_cap};
    use crate::{FlattenParams, Method};
    use flatcut_mesh::TriMesh;

    /// The isometric Newton run from the mesh's start map, with chord steps after a full step
    /// whose model held within `model_fit` (0: only in the tail).
    fn isometric_run(mesh: &TriMesh, model_fit: f64) -> NewtonRun {
        isometric_run_with(mesh, model_fit, true)
    }

    /// [`isometric_run`], leaving out the chord step foreseen below the tolerance if `foresee`.
    fn isometric_run_with(mesh: &TriMesh, model_fit: f64, foresee: bool) -> NewtonRun {
        let topo = flatcut_mesh::check_disk(mesh).unwrap();
        let x0 = init::lscm_or_tutte(mesh, &topo).unwrap();
        let rest = rest_frames(mesh).unwrap();
        let params = FlattenParams::new(Method::Isometric);
        let budget = params.budget("isometric", Instant::now());
        let problem = MapProblem::new(&rest, x0.len(), SymDirichlet, None).unwrap();
        let abs = ABS_DECREMENT_PER_AREA * problem.total_area;
        let mut solver =
            ProjectedNewton::new(params.rel_tolerance, abs, budget.clone(), params.max_iters);
        solver.model_fit = model_fit;
        solver.foresee = foresee;
        run_solver(problem, to_flat(&x0), solver, &budget)
            .unwrap()
            .0
    }

    /// The isometric run on a system whose factors are single precision and whose solves are
    /// refined whatever its size (as a million-face map's), its directions solved to at most
    /// `forcing_max` ([`Forcing`]; [`DIRECTION_TOL`]: all of them to it).
    fn refined_run(mesh: &TriMesh, forcing_max: f64) -> NewtonRun {
        let topo = flatcut_mesh::check_disk(mesh).unwrap();
        let x0 = init::lscm_or_tutte(mesh, &topo).unwrap();
        let rest = rest_frames(mesh).unwrap();
        let sys = analyse(rest.iter().map(|r| r.v), x0.len(), None)
            .unwrap()
            .refined_always();
        let problem = MapProblem::on_system(&rest, x0.len(), SymDirichlet, None, sys);
        let params = FlattenParams::new(Method::Isometric);
        let budget = params.budget("isometric", Instant::now());
        let abs = ABS_DECREMENT_PER_AREA * problem.total_area;
        let mut solver =
            ProjectedNewton::new(params.rel_tolerance, abs, budget.clone(), params.max_iters);
        solver.forcing = Forcing::new(forcing_max);
        run_solver(problem, to_flat(&x0), solver, &budget)
            .unwrap()
            .0
    }

    /// Inexact Newton directions far from the minimum reach the minimiser of the run that
    /// solves every direction to the full tolerance, with fewer refinement steps (single-
    /// precision triangular solves).
    #[test]
    fn inexact_directions_reach_the_same_minimiser_with_fewer_refinement_steps() {
        let meshes = [
            // Slivers (as on scanned meshes) make the Hessian ill-conditioned enough for its
            // single-precision factor to need more than one refinement step to the tolerance,
            // as a million-face map's does.
            (
                "slivered cap",
                slivered(&spherical_cap(50.0, 1.5, 60), 3, 0.02),
            ),
            (
                "slivered cap, wider",
                slivered(&spherical_cap(50.0, 1.2, 60), 3, 0.02),
            ),
        ];
        let mut saved = 0;
        for (name, mesh) in &meshes {
            let inexact = refined_run(mesh, FORCING_MAX);
            let exact = refined_run(mesh, DIRECTION_TOL);
            eprintln!(
                "{name}: {} refinement steps against {}, {} iterations against {}, energy {} against {}",
                inexact.timings.refinements,
                exact.timings.refinements,
                inexact.iterations,
                exact.iterations,
                inexact.energy,
                exact.energy
            );
            assert!(inexact.early.is_none() && exact.early.is_none());
            assert!(exact.timings.refinements > 0, "{name}: no refined solve");
            assert!(
                inexact.timings.refinements <= exact.timings.refinements,
                "{name}"
            );
            saved += exact.timings.refinements - inexact.timings.refinements;
            let rel = (inexact.energy - exact.energy).abs() / exact.energy;
            assert!(
                rel <= 1e-10,
                "{name}: energies {} and {} differ by {rel:e}",
                inexact.energy,
                exact.energy
            );
        }
        assert!(saved > 0, "no refinement step saved");
    }

    /// The forcing term starts loose, follows the square of the gradient's fall, and is never
    /// below the full tolerance nor above its largest value; its safeguard keeps it from
    /// falling faster than its own square while it is large; a retried direction keeps its η.
    #[test]
    fn the_forcing_term_follows_the_gradient_within_its_bounds() {
        let mut f = Forcing::new(FORCING_MAX);
        assert_eq!(f.next(1.0), FORCING_MAX);
        // The gradient barely fell: η stays at its largest.
        assert_eq!(f.next(0.99), FORCING_MAX);
        // Fallen tenfold: γ/100.
        let eta = f.next(0.099);
        assert!((eta - FORCING_GAMMA * 0.01).abs() < 1e-15);
        // The same direction solved again with another projection: the same η, not the
        // largest (as for a gradient that did not fall).
        assert_eq!(f.next(0.099), eta);
        // Fallen a millionfold: the full tolerance.
        assert_eq!(f.next(1e-7), DIRECTION_TOL);
        // A rise: back to the largest.
        assert_eq!(f.next(1.0), FORCING_MAX);
        let mut loose = Forcing::new(0.9);
        assert_eq!(loose.next(1.0), 0.9);
        // γ 0.9² = 0.729 > 0.1: the safeguard holds η there however fast the gradient fell.
        assert!((loose.next(1e-6) - FORCING_GAMMA * 0.81).abs() < 1e-15);
        assert_eq!(Forcing::new(0.0).next(1.0), DIRECTION_TOL);
    }

    /// Chord steps after a step whose model held closely save factorisations and reach the
    /// energy of the run that waits for the tail, to the solve's tolerance.
    #[test]
    fn chord_steps_where_the_model_held_save_factorisations_at_the_same_energy() {
        let meshes = [
            ("saddle", saddle_of_radius(100.0, 50.0, 60)),
            ("cap", spherical_cap(50.0, 1.0, 40)),
        ];
        let mut saved = 0;
        for (name, mesh) in &meshes {
            let early = isometric_run(mesh, MODEL_FIT);
            let tail = isometric_run(mesh, 0.0);
            eprintln!(
                "{name}: {} factorisations against {}, energy {} against {}",
                early.timings.factorisations,
                tail.timings.factorisations,
                early.energy,
                tail.energy
            );
            assert!(early.early.is_none() && tail.early.is_none());
            assert!(early.timings.factorisations <= tail.timings.factorisations);
            saved += tail.timings.factorisations - early.timings.factorisations;
            let rel = (early.energy - tail.energy).abs() / tail.energy;
            assert!(
                rel <= FlattenParams::DEFAULT_REL_TOLERANCE,
                "{name}: energies {} and {} differ by {rel:e}",
                early.energy,
                tail.energy
            );
        }
        assert!(saved > 0, "no factorisation saved");
    }

    /// A chord step foreseen to gain less than a tenth of the tolerance is left out: the run
    /// that takes it ends lower by less than that, and the one without it stopped earlier.
    #[test]
    fn a_chord_step_foreseen_below_the_tolerance_is_left_out() {
        let meshes = [
            ("saddle", saddle_of_radius(100.0, 50.0, 60)),
            ("cap", spherical_cap(50.0, 1.0, 40)),
            ("tight cap", spherical_cap(50.0, 1.5, 40)),
            ("wide saddle", saddle_of_radius(100.0, 30.0, 60)),
        ];
        let mut left_out = 0;
        for (name, mesh) in &meshes {
            let foreseen = isometric_run_with(mesh, MODEL_FIT, true);
            let taken = isometric_run_with(mesh, MODEL_FIT, false);
            let tolerance = FlattenParams::DEFAULT_REL_TOLERANCE * taken.energy;
            eprintln!(
                "{name}: energy {} against {} ({:e} of the tolerance)",
                foreseen.energy,
                taken.energy,
                (foreseen.energy - taken.energy) / tolerance
            );
            assert_eq!(foreseen.iterations, taken.iterations);
            assert!(foreseen.energy >= taken.energy, "{name}");
            assert!(
                foreseen.energy - taken.energy <= FORESEEN_BELOW * tolerance,
                "{name}: {} against {}",
                foreseen.energy,
                taken.energy
            );
            left_out += usize::from(foreseen.energy > taken.energy);
        }
        assert!(left_out > 0, "no chord step was left out");
    }
}
