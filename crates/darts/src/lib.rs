//! Darts and splitting seams that bring a piece within its material's stretch and compression
//! limits.
//!
//! A doubly curved piece cannot lie flat within a few percent of stretch; pattern makers cut
//! darts (wedges from the outline to a point inside, sewn shut) or split the piece. [`place()`]
//! finds the fewest darts that let every face of the piece flatten within the limits, as short
//! as the search resolves, and returns the cut piece flattened with the limits held as hard
//! constraints ([`limits`]) and the two legs of every dart kept at equal 2D length edge by edge
//! ([`solve`]).
//!
//! A dart is the geodesic that leaves the outline at right angles, cut along the mesh edges next
//! to it ([`trace`]); darts never touch each other, the outline (except at their mouths), a seam,
//! a mark or a `no_cut` region ([`keepout`]). How the count, the starts and the lengths are chosen
//! is in [`mod@place`].
//!
//! **Architecture invariant:** the flattening itself is the flattener's (its kernel and its
//! Newton solver); this crate decides where to cut and proves the limits with that solver.
//!
//! ## How it works
//!
//! (The crate's map is in ARCHITECTURE.md; this is the detail behind it.)
//!
//! `place(mesh, uv, DartOptions) -> Darted`: the fewest darts that let every face of a piece
//! flatten within its limits, and the cut piece flattened with the limits held. The limits
//! (`Limits`) are a stretch/compression band on the principal stretches, or per thread of a
//! material (`threads`: warp, weft and both biases along a pattern grain fixed in the plane, ℓ = ln
//! det F − ½ ln|adj(F)d|², the report's measure); demand and reach are estimated with a band either
//! way (the tightest thread's), the count with the band or the loosest thread's, and the search
//! goes down from that count while fewer darts hold, or up until one does. Demand and reach come
//! from the piece flattened as if it could yield everywhere (`relaxed`); a dart is the geodesic
//! leaving the outline at right angles (`trace`), made part of the mesh (its edge crossings become
//! vertices, `embed`) and cut open (`cut`); `keepout` masks the vertices of `no_cut` regions, marks
//! and seams. The limits are held as hard constraints (`limits`: p-norm continuation, the method of
//! centres, then an interior-point δ2 solve) with each dart's legs kept at equal 2D length edge by
//! edge (`solve`: penalty terms on renewed targets, then multipliers while a dart's legs differ by
//! more than half of `LEG_MATCH_MM`, 0.1 mm; on the flattener's projected Newton, one analysed
//! problem per cut piece for all its solves). The method of centres ends where the best recent gain
//! per stage, kept for every stage left, cannot reach the band: such a cut fails whatever follows.
//! `place` starts from the count the dart-point angles ask for and searches down while the limits
//! hold (up when they do not), computing the attempt it will most likely ask for next on the other
//! core (`Lookahead`; the search asks for the same attempts in the same order, so the darts are the
//! same bits with any number of threads); when none holds it says by how much and where
//! (`DartError::Infeasible`). Of the counts that held, the shortest whose final map keeps every
//! dart's legs within `LEG_MATCH_MM` and whose flat outline is simple is the answer; a dart the
//! limits hardly need can close past its mouth, and a dart whose flanks the limits press along
//! different threads can part its legs; when every count that held does, the search goes on to up
//! to three more darts, then refuses the piece (`DartError::Overlap`, `DartError::LegsApart`)
//! rather than write it. The final map is the least-strained one within the limits, or with
//! `DartFit::Tight` (`fit`) each dart drawn shut by a pull between its mouth's corners, guard
//! triangles (point and two leg copies, no energy, only kept from turning over by the line search)
//! keeping its legs from crossing. Where a guard next to a dart's point is on its boundary the dart
//! is shut there (`fit::shut_points`): it ends there, the piece is cut again with the map's shut
//! copies merged (`CutMesh::merge_from`), brought within the limits and drawn tight again, so a
//! tight fit's darts are never longer; a dart that cannot end there without breaking the limits is
//! let go (`fit::jammed`, its pull dropped). A tight map whose legs still part or cross is tried at
//! weaker pulls (`CLOSE_WEIGHTS`), then gives way to the least-strained one. `split` is the other
//! cut, for where no dart can help (a saddle's flat piece is too short, not too long): chords of
//! the flat piece through the worst face and the middle, traced on the surface as style lines
//! (`flatcut_mesh::lines`), the one whose two halves flatten with the least excess cut, then all
//! parts flattened together with their seams' edges equal and the limits held
//! (`flatcut_flatten::assembly`), the worst part split again until every face is within the limits
//! or `max_pieces` is reached (the chords judged side by side, a tie broken by the seam's cost,
//! `seam_cost`: length weighted by visibility from curvature, a hidden side or region, and turning;
//! a time limit, of the process's CPU time (`clock`), returns the best split so far). A part whose flat outline crosses itself
//! (`crossing`) is cut again, by chords and by its necks, and a split that cannot undo the overlap
//! is an error, never a result; an unsplit piece whose outline crosses itself is refused the same
//! way (`flatcut::darting::no_crossing`). A surface that is not a disk (`split_surface`) is first
//! opened (`open`): refused if it passes through itself or is not manifold, each component cut
//! along its cut graph (`flatcut_mesh::cut_graph`: the greedy system of loops from the most hidden
//! vertex, tree–cotree, joined to the boundary, each path tightened toward a geodesic), a sphere
//! slit from its most hidden vertex to the farthest.
//! Cuts no longer needed are sewn back (`resew`): a slit ending inside a part is closed, and parts
//! whose union lies within the limits are merged (the fewest pieces), kept only if their joint solve
//! holds.
#![warn(missing_docs)]

pub mod band;
pub mod clock;
pub mod cone;
pub mod crossing;
pub mod cut;
pub mod embed;
pub mod fewest;
pub mod fit;
pub mod keepout;
pub mod limits;
pub mod mirror;
pub mod open;
pub mod place;
pub mod relaxed;
pub mod resew;
pub mod seam_cost;
pub mod sewn;
pub mod solve;
pub mod split;
pub mod threads;
pub mod trace;

use flatcut_geom::{DVec2, DVec3};
use flatcut_mesh::{TopologyError, TriMesh};

pub use cut::{CutMesh, Legs};
pub use fit::DartFit;
pub use keepout::KeepOut;
pub use limits::{Band, Limits};
pub use place::place;
pub use solve::LEG_MATCH_MM;
pub use threads::Threads;

/// What to place darts for.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct DartOptions {
    /// The material limits every face must meet.
    pub limits: Limits,
    /// Most darts allowed.
    pub max_darts: usize,
    /// Least distance between the mouths of two darts and between a dart's point and another
    /// dart (mm).
    pub min_spacing_mm: f64,
    /// How far short of the dart's point its drill mark sits (mm, along the dart).
    pub drill_offset_mm: f64,
    /// Vertices no dart may use (no_cut regions, marks); `None`: none.
    pub keep_out: Option<KeepOut>,
    /// How the final map uses the material's give ([`DartFit`]).
    pub fit: DartFit,
    /// The stage every solve of the search and of the final map draws on: its iteration cap and
    /// time limit ([`flatcut_flatten::budget`]); none by default.
    pub budget: flatcut_flatten::Budget,
}

impl DartOptions {
    /// Default [`DartOptions::max_darts`].
    pub const DEFAULT_MAX_DARTS: usize = 24;
    /// Default [`DartOptions::min_spacing_mm`] (mm).
    pub const DEFAULT_MIN_SPACING_MM: f64 = 10.0;
    /// Default [`DartOptions::drill_offset_mm`] (mm).
    pub const DEFAULT_DRILL_OFFSET_MM: f64 = 5.0;

    /// Darts for stretch and compression limits in percent, with the default count, spacing and
    /// drill offset.
    pub fn new(stretch_pct: Option<f64>, compress_pct: Option<f64>) -> Self {
        Self {
            limits: Limits::Band(Band::from_pct(stretch_pct, compress_pct)),
            max_darts: Self::DEFAULT_MAX_DARTS,
            min_spacing_mm: Self::DEFAULT_MIN_SPACING_MM,
            drill_offset_mm: Self::DEFAULT_DRILL_OFFSET_MM,
            keep_out: None,
            fit: DartFit::LeastStrain,
            budget: flatcut_flatten::Budget::none("darts"),
        }
    }

    /// The search and the final map within `budget` (the darts stage of a flattening).
    pub fn with_budget(mut self, budget: flatcut_flatten::Budget) -> Self {
        self.budget = budget;
        self
    }

    /// Holds the limits of each thread instead ([`Threads`]: a material's limits along, across
    /// and on the bias, with the grain where it lies in the plane of the start map).
    pub fn with_threads(mut self, threads: Threads) -> Self {
        self.limits = Limits::Threads(threads);
        self
    }

    /// Sets [`DartOptions::max_darts`].
    pub fn with_max_darts(mut self, n: usize) -> Self {
        self.max_darts = n;
        self
    }

    /// Sets [`DartOptions::min_spacing_mm`] (mm).
    pub fn with_min_spacing_mm(mut self, mm: f64) -> Self {
        self.min_spacing_mm = mm;
        self
    }

    /// Sets [`DartOptions::drill_offset_mm`] (mm).
    pub fn with_drill_offset_mm(mut self, mm: f64) -> Self {
        self.drill_offset_mm = mm;
        self
    }

    /// Sets the vertices no dart may use ([`DartOptions::keep_out`]).
    pub fn with_keep_out(mut self, k: KeepOut) -> Self {
        self.keep_out = Some(k);
        self
    }

    /// Sets how the final map uses the material's give ([`DartOptions::fit`]).
    pub fn with_fit(mut self, fit: DartFit) -> Self {
        self.fit = fit;
        self
    }
}

/// One dart of the result.
#[derive(Clone, Debug, PartialEq)]
pub struct Dart {
    /// The piece's vertices the dart is cut along, from its mouth on the outline to its point.
    pub path: Vec<u32>,
    /// Its two legs in the cut mesh (vertex paths from mouth to point).
    pub legs: Legs,
    /// The mouth: the path's first vertex, on the outline (3D, mm).
    pub start_3d: DVec3,
    /// The point: the path's last vertex (3D, mm).
    pub apex_3d: DVec3,
    /// Length of the path along the surface (mm).
    pub length_3d_mm: f64,
    /// 2D length of each leg (mm).
    pub leg_2d_mm: [f64; 2],
    /// 2D width of the dart's mouth (mm).
    pub opening_mm: f64,
    /// The drill mark, on the dart a set distance short of its point: in 3D, and in the plane
    /// (midway between the legs).
    pub drill_3d: DVec3,
    /// The drill mark in the plane (mm), midway between the legs.
    pub drill_2d: DVec2,
}

impl Dart {
    /// A dart's measures in the map `x` of the cut mesh.
    pub fn measure(mesh: &TriMesh, path: &[u32], legs: &Legs, x: &[DVec2], drill_mm: f64) -> Self {
        let pos = |v: u32| mesh.positions[v as usize];
        let cum: Vec<f64> = std::iter::once(0.0)
            .chain(path.windows(2).scan(0.0, |acc, w| {
                *acc += pos(w[0]).distance(pos(w[1]));
                Some(*acc)
            }))
            .collect();
        let length = cum.last().copied().unwrap_or(0.0);
        // The drill mark: `drill_mm` before the point, at most halfway down the dart.
        let s = (length - drill_mm).max(0.5 * length);
        let j = cum
            .partition_point(|&c| c < s)
            .clamp(1, path.len().max(2) - 1);
        let seg = (cum[j] - cum[j - 1]).max(f64::MIN_POSITIVE);
        let f = ((s - cum[j - 1]) / seg).clamp(0.0, 1.0);
        let drill_3d = pos(path[j - 1]).lerp(pos(path[j]), f);
        let on_leg = |side: &[u32]| x[side[j - 1] as usize].lerp(x[side[j] as usize], f);
        let drill_2d = 0.5 * (on_leg(&legs.sides[0]) + on_leg(&legs.sides[1]));
        Self {
            path: path.to_vec(),
            legs: legs.clone(),
            start_3d: pos(path[0]),
            apex_3d: pos(*path.last().unwrap_or(&path[0])),
            length_3d_mm: length,
            leg_2d_mm: legs.lengths_2d(x),
            opening_mm: x[legs.sides[0][0] as usize].distance(x[legs.sides[1][0] as usize]),
            drill_3d,
            drill_2d,
        }
    }

    /// The two legs as 2D polylines from mouth to point.
    pub fn leg_polylines(&self, x: &[DVec2]) -> [Vec<DVec2>; 2] {
        self.legs
            .sides
            .clone()
            .map(|s| s.iter().map(|&v| x[v as usize]).collect())
    }
}

/// One count of darts the search tried.
#[derive(Clone, Debug, PartialEq)]
pub struct Attempt {
    /// Number of darts placed.
    pub darts: usize,
    /// Their total 3D length (mm).
    pub total_length_mm: f64,
    /// Largest limit excess reached (log strain).
    pub excess: f64,
    /// True when this count brought every face within the limits.
    pub feasible: bool,
}

/// A piece with its darts.
#[derive(Clone, Debug)]
pub struct Darted {
    /// The piece cut along the darts, flattened (`flat` set).
    pub mesh: TriMesh,
    /// For every vertex of `mesh`, the piece's vertex it copies.
    pub origin: Vec<u32>,
    /// The darts, with their measures in the final map.
    pub darts: Vec<Dart>,
    /// Largest limit excess over the faces (log strain; negative within the limits).
    pub excess: f64,
    /// True when every face is within the limits (`excess` ≤ 0).
    pub feasible: bool,
    /// Where the largest excess is (3D).
    pub worst_3d: DVec3,
    /// Every count the search tried, in order.
    pub attempts: Vec<Attempt>,
    /// The fit of the final map: the one asked for, or the least-strained one where a tight map
    /// would cross or part a dart's legs ([`crate::fit`]).
    pub fit: DartFit,
}

impl Darted {
    /// Total 3D length of the darts (mm): the sewing work.
    pub fn total_length_mm(&self) -> f64 {
        self.darts.iter().map(|d| d.length_3d_mm).sum()
    }
}

/// Why darts could not be placed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DartError {
    /// The piece, or the piece cut along the darts, is not a surface darts can be cut into
    /// (not a manifold disk).
    #[error(transparent)]
    Topology(#[from] TopologyError),
    /// The flattening of the piece cut along the darts failed.
    #[error("flattening the cut piece failed: {0}")]
    Flatten(flatcut_flatten::FlattenError),
    /// The solve that holds every face within the limits failed.
    #[error("the limit solve failed: {0}")]
    Limits(#[from] limits::LimitError),
    /// A numerical solve failed; the message says which and why.
    #[error("the solver failed: {0}")]
    Solver(String),
    /// A placement that cannot be made (too many darts for the outline, a dart that cannot
    /// leave it); the search tries another count.
    #[error("{0}")]
    Placement(String),
    /// No darts within the options bring the piece within the limits.
    #[error(
        "the limits cannot be met with darts: {reason}; reached {:.2} % beyond the limits with {darts} darts, worst near ({:.2}, {:.2}, {:.2})",
        excess_pct(*excess), at.x, at.y, at.z
    )]
    Infeasible {
        /// The darts of the closest attempt (0 when no dart could be placed or help).
        darts: usize,
        /// Largest limit excess reached (log strain).
        excess: f64,
        /// Where the largest excess is (3D, mm).
        at: DVec3,
        /// Why no dart set works (none fits, none can help, none up to the cap suffices).
        reason: String,
    },
    /// The darts that hold the limits close past their mouths: the flat outline overlaps itself,
    /// and no pattern can be cut from it.
    #[error(
        "the darts that bring the piece within the limits ({darts} of them) close past their mouths: the flat piece overlaps itself near ({:.2}, {:.2}, {:.2})",
        at.x, at.y, at.z
    )]
    Overlap {
        /// The number of darts.
        darts: usize,
        /// A point near the overlap (3D, mm).
        at: DVec3,
    },
    /// The darts that hold the limits cannot keep a dart's two legs at equal 2D lengths: they
    /// could not be sewn point to point.
    #[error(
        "the darts that bring the piece within the limits ({darts} of them) cannot keep their legs equal: one dart's legs differ by {apart_mm:.2} mm in the flat piece (a seam is held to {:.1} mm), near ({:.2}, {:.2}, {:.2})",
        LEG_MATCH_MM, at.x, at.y, at.z
    )]
    LegsApart {
        /// The number of darts.
        darts: usize,
        /// The largest difference between a dart's two 2D leg lengths (mm), over
        /// [`LEG_MATCH_MM`].
        apart_mm: f64,
        /// Near that dart (3D, mm).
        at: DVec3,
    },
    /// The parts of a split still include one whose flat outline crosses itself, and no further
    /// cut the split may make undoes it (its pieces or time ran out, or the part beyond the limits
    /// it would have cut next has no cut left).
    #[error(
        "split into {parts} parts, one still overlaps itself flat near ({:.2}, {:.2}, {:.2}){}: no pattern can be cut from it (it needs more parts or more time)",
        at.x, at.y, at.z, beyond_note(*excess)
    )]
    SplitOverlap {
        /// The number of parts of the split.
        parts: usize,
        /// A point near the overlap (3D, mm).
        at: DVec3,
        /// The largest limit excess over the parts' faces (log strain; negative within them).
        excess: f64,
    },
    /// A flat piece (not split) whose outline crosses itself: it overlaps itself flat, however
    /// well each face keeps its limits.
    #[error(
        "the flat piece overlaps itself near ({:.2}, {:.2}, {:.2}): its outline crosses itself, so no pattern can be cut from it (splitting it, --split auto, cuts it into parts that lie flat)",
        at.x, at.y, at.z
    )]
    OutlineCrossing {
        /// A point near the crossing (3D, mm).
        at: DVec3,
    },
    /// A state the algorithm should never reach (a bug); the message says which.
    #[error("internal error (please report): {0}")]
    Internal(String),
}

/// What a split that ends on an overlap says of its limits: nothing when every face is within
/// them, else how far beyond them it stopped.
fn beyond_note(excess: f64) -> String {
    if excess > 0.0 {
        format!(
            ", and it stopped {:.2} % beyond the limits",
            excess_pct(excess)
        )
    } else {
        String::new()
    }
}

/// A log-strain excess as a percentage of stretch.
pub fn excess_pct(e: f64) -> f64 {
    (e.exp() - 1.0) * 100.0
}
