//! Parameters, results and errors of a flattening.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use flatcut_geom::DVec2;
use flatcut_mesh::TopologyError;

use crate::Method;

/// A vertex held at a fixed 2D position (mm) during the flattening.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pin {
    /// The pinned vertex (0-based index into the mesh's positions).
    pub vertex: u32,
    /// Where it is held, in mm.
    pub position: DVec2,
}

/// What to compute. Build with `FlattenParams::new(method)` and the `with_*` builders.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct FlattenParams {
    /// The flattening method.
    pub method: Method,
    /// Largest allowed stretch in percent (principal stretch σ1 ≤ 1 + P/100), if any.
    pub max_stretch_pct: Option<f64>,
    /// Largest allowed compression in percent (σ2 ≥ 1 − P/100), if any; 0 for leather.
    pub max_compress_pct: Option<f64>,
    /// Pinned vertices.
    pub pins: Vec<Pin>,
    /// Iteration cap of every stage of the flattening ([`crate::budget`]) that is one solve (a
    /// method's own, the joint solve's seams): Newton steps (for `minmax`'s descent L-BFGS
    /// steps, for `arap` local-global rounds) over all the solves of the stage.
    pub max_iters: usize,
    /// Iteration cap of the stages of many solves (the material limits, the darts, the split),
    /// over all their solves; each solve also stops at `max_iters`.
    pub stage_iters: usize,
    /// Iteration cap of the split's stage, over all the solves of its candidate cuts.
    pub split_iters: usize,
    /// Relative decrease of the energy below which a nonlinear method stops.
    pub rel_tolerance: f64,
    /// Relative length error below which a developable input counts as developable (`developable`).
    pub developable_tolerance: f64,
    /// Wall-clock budget of every stage of the flattening ([`crate::budget`]): when it runs
    /// out the stage returns the best flip-free map found so far with a warning saying so.
    pub time_limit: Option<Duration>,
    /// Progress callback and cancel flag of the iterative methods.
    pub hooks: FlattenHooks,
    /// The material of the orthotropic method: stiffness, directional limits, grain.
    pub anisotropy: Option<crate::anisotropy::Anisotropy>,
    /// The stage of an enclosing flattening this one runs within (a split flattens its parts
    /// inside its own stage, [`crate::Budget::within`]): every solve draws on it, and `max_iters`
    /// and `time_limit` are its. `None`: the flattening's stages have budgets of their own.
    pub within: Option<crate::Budget>,
}

impl FlattenParams {
    /// The budget of the stage `name` of a flattening that started at `started`: this cap,
    /// time limit (from now), callback and cancel flag.
    pub fn budget(&self, name: &'static str, started: std::time::Instant) -> crate::Budget {
        self.budget_of(name, self.max_iters, started)
    }

    /// The budget of the stage `name` of many solves ([`Self::stage_iters`]).
    pub fn stage_budget(&self, name: &'static str, started: std::time::Instant) -> crate::Budget {
        self.budget_of(name, self.stage_iters, started)
    }

    /// The budget of the split's stage ([`Self::split_iters`]).
    pub fn split_budget(&self, started: std::time::Instant) -> crate::Budget {
        self.budget_of("split", self.split_iters, started)
    }

    /// A stage's budget with `cap` iterations (inside [`Self::within`]: that stage's).
    fn budget_of(
        &self,
        name: &'static str,
        cap: usize,
        started: std::time::Instant,
    ) -> crate::Budget {
        if let Some(b) = &self.within {
            return b.within().labelled(name);
        }
        crate::Budget::stage(name, cap, self.time_limit, self.hooks.clone(), started)
    }

    /// The same parameters for a flattening inside the stage `budget` ([`Self::within`]).
    pub fn with_within(mut self, budget: Option<crate::Budget>) -> Self {
        self.within = budget;
        self
    }

    /// The default iteration cap of a stage that is one solve (every method but `minmax`).
    pub const DEFAULT_MAX_ITERS: usize = 200;
    /// The default cap of the stages of many solves: the darts' search took 318–509 Newton
    /// steps on the bench's 20k hemisphere, toe and cap at ±3 %, the split of the 20k saddle
    /// 577.
    pub const DEFAULT_STAGE_ITERS: usize = 2000;
    /// The default cap of the split's stage: opening a closed surface and ranking every cut's
    /// candidates flattens both halves of each, so a ball split into 9 parts takes some 10,000
    /// Newton steps; the split's own time limit (`--split-time`) is what bounds it in practice.
    pub const DEFAULT_SPLIT_ITERS: usize = 100_000;
    /// `minmax`'s default cap: 200 L-BFGS steps for each of its descent's five sharpness
    /// stages.
    pub const DEFAULT_MINMAX_ITERS: usize = 1000;
    /// The default relative energy decrease below which a nonlinear method stops.
    pub const DEFAULT_REL_TOLERANCE: f64 = 1e-9;
    /// The default relative length error below which `developable` accepts a surface as developable.
    pub const DEFAULT_DEVELOPABLE_TOLERANCE: f64 = 1e-6;

    /// The defaults for `method`: no limits, no pins, no time limit, the default caps and tolerances.
    pub fn new(method: Method) -> Self {
        Self {
            method,
            max_stretch_pct: None,
            max_compress_pct: None,
            pins: Vec::new(),
            max_iters: Self::default_max_iters(method),
            stage_iters: Self::DEFAULT_STAGE_ITERS,
            split_iters: Self::DEFAULT_SPLIT_ITERS,
            rel_tolerance: Self::DEFAULT_REL_TOLERANCE,
            developable_tolerance: Self::DEFAULT_DEVELOPABLE_TOLERANCE,
            time_limit: None,
            hooks: FlattenHooks::default(),
            anisotropy: None,
            within: None,
        }
    }

    /// The iteration cap of `method`'s stages when none is given.
    pub fn default_max_iters(method: Method) -> usize {
        match method {
            Method::Minmax => Self::DEFAULT_MINMAX_ITERS,
            _ => Self::DEFAULT_MAX_ITERS,
        }
    }

    /// Sets the largest allowed stretch in percent (σ1 ≤ 1 + p/100); `None` for no limit.
    pub fn with_max_stretch_pct(mut self, p: Option<f64>) -> Self {
        self.max_stretch_pct = p;
        self
    }

    /// Sets the largest allowed compression in percent (σ2 ≥ 1 − p/100); `None` for no limit.
    pub fn with_max_compress_pct(mut self, p: Option<f64>) -> Self {
        self.max_compress_pct = p;
        self
    }

    /// Sets the pinned vertices (replacing any set before).
    pub fn with_pins(mut self, pins: Vec<Pin>) -> Self {
        self.pins = pins;
        self
    }

    /// Caps every stage at `n` iterations (the stages of one solve and of many alike).
    pub fn with_max_iters(mut self, n: usize) -> Self {
        self.max_iters = n;
        self.stage_iters = n;
        self.split_iters = n;
        self
    }

    /// Sets the wall-clock limit of every stage; `None` for no limit.
    pub fn with_time_limit(mut self, t: Option<Duration>) -> Self {
        self.time_limit = t;
        self
    }

    /// Sets the progress and cancel hooks.
    pub fn with_hooks(mut self, hooks: FlattenHooks) -> Self {
        self.hooks = hooks;
        self
    }

    /// Sets the material of the orthotropic method; `None` for none.
    pub fn with_anisotropy(mut self, a: Option<crate::anisotropy::Anisotropy>) -> Self {
        self.anisotropy = a;
        self
    }
}

/// Where an iterative flattening is, reported after every iteration.
#[derive(Clone, Debug, PartialEq)]
pub struct FlattenProgress {
    /// What is being solved ("isometric", "boundary lengths", "min-max", ...).
    pub stage: &'static str,
    /// Iterations done so far in this stage.
    pub iteration: usize,
    /// The stage's iteration cap.
    pub max_iterations: usize,
    /// The stage's objective after this iteration.
    pub energy: f64,
    /// Time since the flattening started.
    pub elapsed: Duration,
}

/// The callback type of [`FlattenHooks::with_progress`].
pub type ProgressFn = dyn Fn(&FlattenProgress) + Send + Sync;

/// A progress callback and a cancel flag for the iterative methods. Clones share both. Two hooks
/// compare equal when they share the same callback and flag (or both have none).
#[derive(Clone, Default)]
pub struct FlattenHooks {
    progress: Option<Arc<ProgressFn>>,
    cancel: Option<Arc<AtomicBool>>,
}

impl FlattenHooks {
    /// Calls `f` after every iteration of an iterative method.
    pub fn with_progress(mut self, f: Arc<ProgressFn>) -> Self {
        self.progress = Some(f);
        self
    }

    /// Stops the flattening with [`FlattenError::Cancelled`] once `flag` is set.
    pub fn with_cancel(mut self, flag: Arc<AtomicBool>) -> Self {
        self.cancel = Some(flag);
        self
    }

    /// Reports `p` to the callback, if any.
    pub fn report(&self, p: &FlattenProgress) {
        if let Some(f) = &self.progress {
            f(p);
        }
    }

    /// True once the cancel flag is set.
    pub fn cancelled(&self) -> bool {
        self.cancel
            .as_ref()
            .is_some_and(|c| c.load(Ordering::Relaxed))
    }
}

impl std::fmt::Debug for FlattenHooks {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FlattenHooks")
            .field("progress", &self.progress.is_some())
            .field(
                "cancel",
                &self.cancel.as_ref().map(|c| c.load(Ordering::Relaxed)),
            )
            .finish()
    }
}

impl PartialEq for FlattenHooks {
    fn eq(&self, other: &Self) -> bool {
        let same = |a: Option<&Arc<ProgressFn>>, b: Option<&Arc<ProgressFn>>| match (a, b) {
            (None, None) => true,
            (Some(a), Some(b)) => Arc::ptr_eq(a, b),
            _ => false,
        };
        same(self.progress.as_ref(), other.progress.as_ref())
            && match (&self.cancel, &other.cancel) {
                (None, None) => true,
                (Some(a), Some(b)) => Arc::ptr_eq(a, b),
                _ => false,
            }
    }
}

/// How the solve went.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FlattenInfo {
    /// Iterations of the method's main solve (1 for the direct methods: LSCM, conformal-boundary,
    /// developable).
    pub iterations: usize,
    /// Final value of the method's energy (area-weighted mean density where that applies).
    pub final_energy: f64,
    /// Messages for the user: constraints that could not be met, fallbacks taken (with where).
    pub warnings: Vec<String>,
    /// The iterations of each stage of the flattening against its cap, in the order they ran
    /// ([`crate::budget`]); empty for the direct methods (LSCM, conformal-boundary,
    /// developable).
    pub stages: Vec<crate::StageCount>,
    /// Where the solve's wall time went (the Newton methods; zero where not measured).
    pub timings: crate::Timings,
}

/// A flattening: one 2D position per vertex of the input mesh, in mm at true scale.
#[derive(Clone, Debug, PartialEq)]
pub struct Flattening {
    /// One 2D position in mm per vertex of the input mesh, indexed like `mesh.positions`.
    pub uv: Vec<DVec2>,
    /// How the solve went.
    pub info: FlattenInfo,
}

/// Why a flattening failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum FlattenError {
    /// The mesh is not a single manifold disk (or has bad elements).
    #[error(transparent)]
    Topology(#[from] TopologyError),
    /// `developable` was asked for a surface that is not developable.
    #[error(
        "the surface is not developable: largest |K| = {max_abs_k:.3e} /mm² (angle defect {angle_defect:.3e} rad) at vertex {vertex} ({x:.3}, {y:.3}, {z:.3}); the isometric method flattens it with the least distortion"
    )]
    NotDevelopable {
        /// Largest |Gaussian curvature| in 1/mm².
        max_abs_k: f64,
        /// The angle defect at that vertex, radians.
        angle_defect: f64,
        /// The vertex (0-based).
        vertex: u32,
        /// Its x in mm.
        x: f64,
        /// Its y in mm.
        y: f64,
        /// Its z in mm.
        z: f64,
    },
    /// A pin refers to a vertex that does not exist, or pins contradict each other.
    #[error("pin {index}: {reason}")]
    BadPin {
        /// The pin's 0-based index in `FlattenParams::pins`.
        index: usize,
        /// What is wrong with it.
        reason: String,
    },
    /// The linear solver failed (the system was singular or not positive definite).
    #[error("linear solve failed in {stage}: {reason}")]
    Solver {
        /// The solver stage (a static name of the step that failed).
        stage: &'static str,
        /// The solver's message.
        reason: String,
    },
    /// The caller's cancel flag was set ([`FlattenHooks::with_cancel`]).
    #[error("{method} was cancelled")]
    Cancelled {
        /// The method that was cancelled.
        method: Method,
    },
    /// The method did not reach a valid (finite, flip-free) result.
    #[error("{method} did not converge: {reason}")]
    NoConvergence {
        /// The method.
        method: Method,
        /// Why its result is not valid.
        reason: String,
    },
    /// The orthotropic method's material or grain cannot be used.
    #[error("orthotropic: {0}")]
    Anisotropy(String),
    /// A bug in flatcut: please report it.
    #[error("internal error (please report): {0}")]
    Internal(#[from] crate::internal::InternalError),
}
