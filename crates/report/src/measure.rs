//! Per-face measures, area-weighted statistics, δ0, seam lengths and regions.

use std::collections::BTreeMap;

use flatcut_geom::{DVec2, DVec3};
use flatcut_mesh::{TriMesh, face_distortion};
use serde::Serialize;

use crate::face::FaceMeasure;

/// Which quantity a picture shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Measure {
    /// Duncan's conformal distortion δ1 = log(μ1/μ2) (radians-like, dimensionless).
    Delta1,
    /// Duncan's isometric distortion δ2.
    Delta2,
    /// Signed principal stretch in percent: the larger of stretch (+) and compression (−).
    Stretch,
    /// Area change in percent: (σ1σ2 − 1)·100.
    Area,
    /// The largest excess of the strain along the grain, across it or on either bias over the
    /// material's limit in that direction, in percentage points (negative: the margin left), for
    /// pieces flattened with a material.
    Material,
}

impl Measure {
    /// The measure named on the command line (`delta1`, `delta2`, `stretch`, `area`,
    /// `material`; exact, lowercase), or `None` for any other name.
    pub fn from_name(s: &str) -> Option<Self> {
        match s {
            "delta1" => Some(Self::Delta1),
            "delta2" => Some(Self::Delta2),
            "stretch" => Some(Self::Stretch),
            "area" => Some(Self::Area),
            "material" => Some(Self::Material),
            _ => None,
        }
    }

    /// The lowercase name [`Measure::from_name`] reads and the JSON writes.
    pub fn name(self) -> &'static str {
        match self {
            Self::Delta1 => "delta1",
            Self::Delta2 => "delta2",
            Self::Stretch => "stretch",
            Self::Area => "area",
            Self::Material => "material",
        }
    }

    /// The legend's title with its unit.
    pub fn title(self) -> &'static str {
        match self {
            Self::Delta1 => "CONFORMAL DISTORTION D1 = LOG(MU1/MU2)",
            Self::Delta2 => "ISOMETRIC DISTORTION D2",
            Self::Stretch => "PRINCIPAL STRETCH % (+ STRETCH, - COMPRESSION)",
            Self::Area => "AREA CHANGE %",
            Self::Material => "EXCESS OVER THE MATERIAL LIMITS ALONG ACROSS BIAS (% POINTS)",
        }
    }

    /// The noise floor of the pictures: a face whose |value| is below it is drawn as exactly 0,
    /// so floating-point noise on an undistorted piece shows as no distortion rather than as
    /// saturated bands on a ±1e-12 scale. 0.01 % is 0.1 mm over a metre, below what any cutter
    /// reproduces; δ1 and δ2 floors are of the same order for small distortions.
    pub fn floor(self) -> f64 {
        match self {
            Self::Delta1 => 1e-4,
            Self::Delta2 => 1e-5,
            Self::Stretch | Self::Area | Self::Material => 0.01,
        }
    }

    /// The value drawn for a face: [`Measure::of`] with |value| below [`Measure::floor`] as 0.
    pub fn drawn(self, f: &FaceMeasure) -> f64 {
        let v = self.of(f);
        if v.abs() < self.floor() { 0.0 } else { v }
    }

    /// True for measures with a sign (drawn with a diverging colour map).
    pub fn signed(self) -> bool {
        matches!(self, Self::Stretch | Self::Area | Self::Material)
    }

    /// The measure's value for one face, unfloored: δ1 or δ2 (dimensionless), the signed
    /// principal stretch or the area change (percent), or the material excess (percentage
    /// points; NaN when the face has none because the piece has no material).
    pub fn of(self, f: &FaceMeasure) -> f64 {
        match self {
            Self::Delta1 => f.delta1,
            Self::Delta2 => f.delta2,
            Self::Stretch => {
                if f.stretch_pct >= f.compress_pct {
                    f.stretch_pct
                } else {
                    -f.compress_pct
                }
            }
            Self::Area => (f.area_ratio - 1.0) * 100.0,
            Self::Material => f.material_excess_pct.unwrap_or(f64::NAN),
        }
    }
}

/// Area-weighted statistics of one quantity.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
/// Each face is weighted by its 3D area; all zero for an empty or zero-area set. Units are the
/// quantity's own.
pub struct Stats {
    /// Area-weighted mean.
    pub mean: f64,
    /// Largest value over the faces (unweighted).
    pub max: f64,
    /// Median: the least value such that faces at or below it cover half the area.
    pub p50: f64,
    /// The least value such that faces at or below it cover 90 % of the area.
    pub p90: f64,
    /// The least value such that faces at or below it cover 99 % of the area.
    pub p99: f64,
}

/// Length fidelity of a boundary stretch between two marks (or the whole loop).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BoundarySegment {
    /// Boundary vertices where the segment starts and ends (equal for a whole loop).
    /// 0-based index into the mesh's vertices of the segment's first vertex.
    pub from_vertex: u32,
    /// 0-based vertex index of the segment's last vertex.
    pub to_vertex: u32,
    /// Length along the surface's boundary (mm).
    pub length_3d_mm: f64,
    /// Length along the flat piece's outline (mm).
    pub length_2d_mm: f64,
    /// (2D − 3D) / 3D.
    pub relative_error: f64,
}

/// A connected set of faces over a limit.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Region {
    /// "stretch" or "compress".
    pub kind: &'static str,
    /// Number of faces in the region (at least 1).
    pub faces: usize,
    /// The region's 3D area (mm²).
    pub area_mm2: f64,
    /// The worst value in the region, percent.
    pub worst_pct: f64,
    /// The region's area-weighted centroid: off a curved surface (inside a dome, say).
    pub centroid_3d: [f64; 3],
    /// The region's area-weighted centroid in the flat piece (mm; 3D areas weigh it).
    pub centroid_2d: [f64; 2],
    /// Where the worst value is: the centroid of the region's worst face, a point on the
    /// surface (and in the flat map), where a limit's message points to.
    pub worst_at_3d: [f64; 3],
    /// The same face's centroid in the flat piece (mm).
    pub worst_at_2d: [f64; 2],
}

/// What to compute besides the per-face measures.
#[derive(Clone, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct ReportOptions {
    /// Boundary vertices that split the boundary into seam segments (match marks).
    pub boundary_marks: Vec<u32>,
    /// Stretch limit (percent): faces stretched beyond it form the report's `regions`; `None`
    /// looks for no stretch region.
    pub limit_stretch_pct: Option<f64>,
    /// Compression limit (percent, positive): faces compressed beyond it form `regions`.
    pub limit_compress_pct: Option<f64>,
}

impl ReportOptions {
    /// Sets [`ReportOptions::limit_stretch_pct`] (percent).
    pub fn with_limit_stretch_pct(mut self, p: Option<f64>) -> Self {
        self.limit_stretch_pct = p;
        self
    }

    /// Sets [`ReportOptions::limit_compress_pct`] (percent, positive).
    pub fn with_limit_compress_pct(mut self, p: Option<f64>) -> Self {
        self.limit_compress_pct = p;
        self
    }

    /// Sets [`ReportOptions::boundary_marks`] (0-based vertex indices).
    pub fn with_boundary_marks(mut self, marks: Vec<u32>) -> Self {
        self.boundary_marks = marks;
        self
    }
}

/// Why a report could not be computed or drawn. `name` is the piece's name as given to
/// [`Report::compute`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ReportError {
    /// The mesh carries no 2D positions (`TriMesh::flat` is `None`).
    #[error("{name}: the mesh has no flattening (no `vt` coordinates); flatten it first")]
    NoFlattening {
        /// The piece.
        name: String,
    },
    /// The flattening's length differs from the vertex count.
    #[error("{name}: the flattening has {got} positions for {want} vertices")]
    FlatCount {
        /// The piece.
        name: String,
        /// 2D positions in the flattening.
        got: usize,
        /// Vertices of the mesh.
        want: usize,
    },
    /// A triangle has zero area on the surface, so its distortion is undefined.
    #[error("{name}: face {face} is degenerate in 3D (zero area)")]
    DegenerateFace {
        /// The piece.
        name: String,
        /// 0-based triangle index.
        face: usize,
    },
    /// A 3D or 2D vertex coordinate is NaN or infinite.
    #[error("{name}: vertex {vertex} has a non-finite coordinate")]
    NonFinite {
        /// The piece.
        name: String,
        /// 0-based vertex index.
        vertex: usize,
    },
    /// The mesh has no triangle.
    #[error("{name}: the mesh has no triangles")]
    Empty {
        /// The piece.
        name: String,
    },
    /// The SVG could not be rasterised to PNG (parse failure or a pixmap too large to allocate);
    /// the message says which.
    #[error("cannot render the picture: {0}")]
    Render(String),
}

/// The distortion report of one flattened piece. Field names are the JSON contract.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    /// The piece's name (also the prefix of every error about it).
    pub name: String,
    /// Number of triangles.
    pub faces: usize,
    /// Triangles whose flat image is reversed or degenerate (σ1σ2 ≤ 0); any makes the piece
    /// fail [`Report::within_limits`].
    pub flipped: usize,
    /// Surface area (mm²).
    pub area_3d_mm2: f64,
    /// Area of the flat piece (mm²; 0 when it cannot be computed).
    pub area_2d_mm2: f64,
    /// Duncan's global distortion δ0 = log(s2/s1), intrinsic distances in the flat piece
    /// against geodesic distances on the surface ([`crate::delta0`]).
    pub delta0: f64,
    /// The least ratio of flat to surface distance.
    pub delta0_s1: f64,
    /// The greatest ratio of flat to surface distance.
    pub delta0_s2: f64,
    /// `exact` (from every face's principal stretches, which bound every pair of points).
    pub delta0_method: String,
    /// A bound on the difference between `delta0` and the exact figure of the map (0: exact).
    pub delta0_error_bound: f64,
    /// Pairs of points sampled for δ0 (0: exact, none sampled).
    pub delta0_pairs: usize,
    /// Area-weighted mean of Duncan's conformal distortion δ1 = log(μ1/μ2) (dimensionless,
    /// 0 for a conformal map); the `delta1_*` figures are its [`Stats`].
    pub delta1_mean: f64,
    /// Largest δ1 of any face.
    pub delta1_max: f64,
    /// Area-weighted median of δ1.
    pub delta1_p50: f64,
    /// Area-weighted 90th percentile of δ1.
    pub delta1_p90: f64,
    /// Area-weighted 99th percentile of δ1.
    pub delta1_p99: f64,
    /// Area-weighted mean of Duncan's isometric distortion δ2 = (μ1 + 1/μ1 + μ2 + 1/μ2 − 4)/2
    /// (dimensionless, 0 for an isometry); the `delta2_*` figures are its [`Stats`].
    pub delta2_mean: f64,
    /// Largest δ2 of any face.
    pub delta2_max: f64,
    /// Area-weighted median of δ2.
    pub delta2_p50: f64,
    /// Area-weighted 90th percentile of δ2.
    pub delta2_p90: f64,
    /// Area-weighted 99th percentile of δ2.
    pub delta2_p99: f64,
    /// Area-weighted mean of the area ratio σ1σ2 (1 = area kept).
    pub area_mean: f64,
    /// Area-weighted mean of |log(σ1σ2)| (metrics.py's "area").
    pub area_log_mean: f64,
    /// Largest stretch (σ1 − 1)·100 of any face (percent, at least 0).
    pub stretch_max_pct: f64,
    /// Area-weighted 90th percentile of the stretch (percent).
    pub stretch_p90_pct: f64,
    /// Largest compression (1 − σ2)·100 of any face (percent, positive, at least 0).
    pub compress_max_pct: f64,
    /// Area-weighted 90th percentile of the compression (percent).
    pub compress_p90_pct: f64,
    /// (2D boundary length − 3D boundary length) / 3D, all loops.
    pub boundary_length_error: f64,
    /// The boundary loops cut at the marks of [`ReportOptions::boundary_marks`], segment by
    /// segment with its 3D and 2D lengths (a loop with one mark is one whole-loop segment; a
    /// loop with none gives no segment).
    pub boundary_segments: Vec<BoundarySegment>,
    /// Regions beyond the limits asked for (empty when within or when no limit was given).
    pub regions: Vec<Region>,
    /// Where the distortion concentrates, limits or not: the connected regions of the 1 % of
    /// the surface area most stretched and the 1 % most compressed, worst first (at most
    /// [`MAX_HOT_SPOTS`]); empty for a map without measurable distortion.
    pub hot_spots: Vec<Region>,
    /// The mating seams this piece takes part in (filled by whoever knows the other pieces: the
    /// seams of a design, or the coincident boundaries of several flattened meshes).
    pub mating_seams: Vec<crate::MatingSeamReport>,
    /// The darts cut into the piece to meet the limits (absent when there are none).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub darts: Vec<crate::DartReport>,
    /// The strain along the material's grain and its limits per direction (with a material).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub grain: Option<crate::GrainReport>,
    /// Each face's measures, indexed like `TriMesh::triangles` (not in the JSON; the pictures
    /// and [`Report::stats`] read it).
    #[serde(skip)]
    pub per_face: Vec<FaceMeasure>,
}

/// Most hot spots a report lists (the long tail of one-face regions says nothing more).
pub const MAX_HOT_SPOTS: usize = 10;
/// Stretch or compression below this (percent) is not a hot spot: well under what any
/// material or cutting process resolves (0.01 % is 0.1 mm over a metre).
const NEGLIGIBLE_PCT: f64 = 0.01;

/// The connected regions at or beyond the 99th area percentile of stretch and of compression.
fn hot_spots(
    mesh: &TriMesh,
    flat: &[DVec2],
    faces: &[FaceMeasure],
    stretch_p99: f64,
    compress_p99: f64,
) -> Vec<Region> {
    let s = stretch_p99.max(NEGLIGIBLE_PCT);
    let c = compress_p99.max(NEGLIGIBLE_PCT);
    let mut v = over_limit(mesh, flat, faces, "stretch", |f| {
        (f.stretch_pct >= s).then_some(f.stretch_pct)
    });
    v.extend(over_limit(mesh, flat, faces, "compress", |f| {
        (f.compress_pct >= c).then_some(f.compress_pct)
    }));
    v.sort_by(|a, b| b.worst_pct.total_cmp(&a.worst_pct));
    v.truncate(MAX_HOT_SPOTS);
    v
}

/// Faces from which the per-face measures are computed on two threads, each half of the faces
/// ([`face_measures`]); below, a thread costs more than it saves.
const TWO_THREADS_FROM: usize = 50_000;

/// `a` on another thread and `b` on this one if `apart`, else one after the other: the results
/// are the same.
fn beside<A: Send, B>(apart: bool, a: impl FnOnce() -> A + Send, b: impl FnOnce() -> B) -> (A, B) {
    if !apart {
        return (a(), b());
    }
    std::thread::scope(|s| {
        let a = s.spawn(a);
        let b = b();
        // A panic there is a bug, carried on here as if it were this thread's.
        (a.join().unwrap_or_else(|e| std::panic::resume_unwind(e)), b)
    })
}

/// Every face's measures, in face order; `Err(t)` for the first face `t` that is degenerate.
/// Each face's measures are its own, so a large mesh's two halves are measured side by side.
fn face_measures(mesh: &TriMesh) -> Result<Vec<FaceMeasure>, usize> {
    let n = mesh.triangles.len();
    if n < TWO_THREADS_FROM {
        return (0..n).map(|t| face_measure(mesh, t)).collect();
    }
    let half = n / 2;
    let (first, second) = beside(
        true,
        || {
            (0..half)
                .map(|t| face_measure(mesh, t))
                .collect::<Result<Vec<_>, _>>()
        },
        || {
            (half..n)
                .map(|t| face_measure(mesh, t))
                .collect::<Result<Vec<_>, _>>()
        },
    );
    let mut all = first?;
    all.extend(second?);
    Ok(all)
}

/// The measures of face `t`; `Err(t)` if it is degenerate.
fn face_measure(mesh: &TriMesh, t: usize) -> Result<FaceMeasure, usize> {
    let tri3 = mesh.corners(t);
    let tri2 = mesh.flat_corners(t).expect("flat checked");
    let d = face_distortion(tri3, tri2).ok_or(t)?;
    let flipped = d.flipped();
    // A flipped or collapsed face is infinitely distorted: never hidden as "undistorted".
    let (delta1, delta2) = if flipped {
        (f64::INFINITY, f64::INFINITY)
    } else {
        (d.delta1(), d.delta2())
    };
    Ok(FaceMeasure {
        mu1: d.mu1(),
        mu2: d.mu2(),
        delta1,
        delta2,
        area_ratio: d.det,
        stretch_pct: ((d.sigma1 - 1.0) * 100.0).max(0.0),
        compress_pct: if flipped {
            100.0
        } else {
            ((1.0 - d.sigma2) * 100.0).max(0.0)
        },
        flipped,
        dir_max_2d: d.dir_max_2d,
        area_3d: mesh.triangle_area(t),
        material_excess_pct: None,
    })
}

fn weighted_stats(values: &[(f64, f64)]) -> Stats {
    // values: (value, weight)
    let total: f64 = values.iter().map(|v| v.1).sum();
    if values.is_empty() || total <= 0.0 {
        return Stats::default();
    }
    let mean = values.iter().map(|(v, w)| v * w).sum::<f64>() / total;
    let max = values.iter().map(|v| v.0).fold(f64::NEG_INFINITY, f64::max);
    let sorted = sorted_by_value(values);
    let q = |p: f64| {
        let target = p * total;
        let mut acc = 0.0;
        for (v, w) in &sorted {
            acc += w;
            if acc >= target {
                return *v;
            }
        }
        sorted.last().map_or(0.0, |v| v.0)
    };
    Stats {
        mean,
        max,
        p50: q(0.5),
        p90: q(0.9),
        p99: q(0.99),
    }
}

/// `values` in the order of a stable sort by value ([`f64::total_cmp`]; equal values keep their
/// order, so the quantiles sum the weights in the same order every time): a least significant
/// digit first radix sort of the values' bits mapped to unsigned integers in `total_cmp`'s
/// order, stable as it is and linear where the sort by comparisons was most of a million-face
/// report's statistics.
fn sorted_by_value(values: &[(f64, f64)]) -> Vec<(f64, f64)> {
    const SIGN: u64 = 1 << 63;
    // Negative values (sign bit set) reversed below the positive ones.
    let key = |x: f64| {
        let b = x.to_bits();
        if b & SIGN != 0 { !b } else { b | SIGN }
    };
    let value = |k: u64| f64::from_bits(if k & SIGN != 0 { k & !SIGN } else { !k });
    let mut a: Vec<(u64, f64)> = values.iter().map(|&(v, w)| (key(v), w)).collect();
    let digit = |k: u64, d: usize| ((k >> (8 * d)) & 0xff) as usize;
    let mut count = [[0usize; 256]; 8];
    for &(k, _) in &a {
        for (d, c) in count.iter_mut().enumerate() {
            c[digit(k, d)] += 1;
        }
    }
    let mut b = vec![(0u64, 0.0); a.len()];
    for (d, c) in count.iter().enumerate() {
        // A digit every key shares leaves the order as it is.
        if c.contains(&a.len()) {
            continue;
        }
        let mut at = [0usize; 256];
        let mut start = 0;
        for (slot, &n) in at.iter_mut().zip(c) {
            *slot = start;
            start += n;
        }
        for &(k, w) in &a {
            let slot = &mut at[digit(k, d)];
            b[*slot] = (k, w);
            *slot += 1;
        }
        std::mem::swap(&mut a, &mut b);
    }
    a.into_iter().map(|(k, w)| (value(k), w)).collect()
}

impl Report {
    /// Measures a flattened mesh (`mesh.flat` must be set).
    pub fn compute(
        name: &str,
        mesh: &TriMesh,
        opts: &ReportOptions,
    ) -> Result<Report, ReportError> {
        let flat = mesh
            .flat
            .as_ref()
            .ok_or_else(|| ReportError::NoFlattening { name: name.into() })?;
        if flat.len() != mesh.positions.len() {
            return Err(ReportError::FlatCount {
                name: name.into(),
                got: flat.len(),
                want: mesh.positions.len(),
            });
        }
        if mesh.triangles.is_empty() {
            return Err(ReportError::Empty { name: name.into() });
        }
        for (i, (p, q)) in mesh.positions.iter().zip(flat).enumerate() {
            if !flatcut_geom::finite3(*p) || !flatcut_geom::finite2(*q) {
                return Err(ReportError::NonFinite {
                    name: name.into(),
                    vertex: i,
                });
            }
        }
        let apart = mesh.triangles.len() >= TWO_THREADS_FROM;
        // The boundary needs the mesh's topology, not the faces' measures: it is traced on
        // another thread while the faces are measured here.
        let ((boundary_length_error, boundary_segments), per_face) = beside(
            apart,
            || boundary(mesh, flat, &opts.boundary_marks),
            || face_measures(mesh),
        );
        let per_face = per_face.map_err(|face| ReportError::DegenerateFace {
            name: name.into(),
            face,
        })?;
        let flipped = per_face.iter().filter(|f| f.flipped).count();
        let stats = |m: fn(&FaceMeasure) -> f64| {
            weighted_stats(
                &per_face
                    .iter()
                    .map(|f| (m(f), f.area_3d))
                    .collect::<Vec<_>>(),
            )
        };
        // Each statistic sorts every face's value: two on another thread, two on this one.
        let ((s1, s2), (st, co)) = beside(
            apart,
            || (stats(|f| f.delta1), stats(|f| f.delta2)),
            || (stats(|f| f.stretch_pct), stats(|f| f.compress_pct)),
        );
        let area3: f64 = per_face.iter().map(|f| f.area_3d).sum();
        let area_mean = per_face
            .iter()
            .map(|f| f.area_ratio * f.area_3d)
            .sum::<f64>()
            / area3;
        let area_log_mean = per_face
            .iter()
            .map(|f| f.area_ratio.abs().ln().abs() * f.area_3d)
            .sum::<f64>()
            / area3;

        let d0 = crate::delta0::delta0(&per_face);
        let mut regions = Vec::new();
        if let Some(lim) = opts.limit_stretch_pct {
            regions.extend(over_limit(mesh, flat, &per_face, "stretch", |f| {
                (f.stretch_pct > lim).then_some(f.stretch_pct)
            }));
        }
        if let Some(lim) = opts.limit_compress_pct {
            regions.extend(over_limit(mesh, flat, &per_face, "compress", |f| {
                (f.compress_pct > lim).then_some(f.compress_pct)
            }));
        }
        let hot_spots = hot_spots(mesh, flat, &per_face, st.p99, co.p99);
        Ok(Report {
            name: name.into(),
            faces: per_face.len(),
            flipped,
            area_3d_mm2: area3,
            area_2d_mm2: mesh.flat_area().unwrap_or(0.0),
            delta0: d0.delta0,
            delta0_s1: d0.s1,
            delta0_s2: d0.s2,
            delta0_method: d0.method.into(),
            delta0_error_bound: d0.error_bound,
            delta0_pairs: 0,
            delta1_mean: s1.mean,
            delta1_max: s1.max,
            delta1_p50: s1.p50,
            delta1_p90: s1.p90,
            delta1_p99: s1.p99,
            delta2_mean: s2.mean,
            delta2_max: s2.max,
            delta2_p50: s2.p50,
            delta2_p90: s2.p90,
            delta2_p99: s2.p99,
            area_mean,
            area_log_mean,
            stretch_max_pct: st.max,
            stretch_p90_pct: st.p90,
            compress_max_pct: co.max,
            compress_p90_pct: co.p90,
            boundary_length_error,
            boundary_segments,
            regions,
            hot_spots,
            mating_seams: Vec::new(),
            darts: Vec::new(),
            grain: None,
            per_face,
        })
    }

    /// True when no region exceeds the limits asked for and no face is flipped.
    pub fn within_limits(&self) -> bool {
        self.regions.is_empty()
            && self.flipped == 0
            && self.grain.as_ref().is_none_or(crate::GrainReport::within)
    }

    /// Sets the grain section and each face's excess over the material's limits from it.
    pub fn set_grain(&mut self, grain: Option<crate::GrainReport>) {
        if let Some(g) = &grain {
            for (f, e) in self.per_face.iter_mut().zip(&g.face_excess_pct) {
                f.material_excess_pct = Some(*e);
            }
        }
        self.grain = grain;
    }

    /// Area-weighted statistics of a measure over the faces (values as [`Measure::of`] gives
    /// them, unfloored).
    pub fn stats(&self, m: Measure) -> Stats {
        weighted_stats(
            &self
                .per_face
                .iter()
                .map(|f| (m.of(f), f.area_3d))
                .collect::<Vec<_>>(),
        )
    }
}

/// Boundary loops (ordered) of the mesh.
fn boundary_loops(mesh: &TriMesh) -> Vec<Vec<u32>> {
    flatcut_mesh::Topology::build(mesh)
        .map(|t| t.boundary_loops)
        .unwrap_or_default()
}

fn boundary(mesh: &TriMesh, flat: &[DVec2], marks: &[u32]) -> (f64, Vec<BoundarySegment>) {
    let loops = boundary_loops(mesh);
    let (mut l3, mut l2) = (0.0, 0.0);
    let mut segs = Vec::new();
    for lp in &loops {
        let n = lp.len();
        let len3 = |a: u32, b: u32| mesh.positions[a as usize].distance(mesh.positions[b as usize]);
        let len2 = |a: u32, b: u32| flat[a as usize].distance(flat[b as usize]);
        for k in 0..n {
            l3 += len3(lp[k], lp[(k + 1) % n]);
            l2 += len2(lp[k], lp[(k + 1) % n]);
        }
        let cuts: Vec<usize> = (0..n).filter(|&k| marks.contains(&lp[k])).collect();
        if cuts.is_empty() {
            continue;
        }
        for (c, &start) in cuts.iter().enumerate() {
            let end = cuts[(c + 1) % cuts.len()];
            let (mut a3, mut a2) = (0.0, 0.0);
            let mut k = start;
            loop {
                let j = (k + 1) % n;
                a3 += len3(lp[k], lp[j]);
                a2 += len2(lp[k], lp[j]);
                k = j;
                if k == end {
                    break;
                }
            }
            segs.push(BoundarySegment {
                from_vertex: lp[start],
                to_vertex: lp[end],
                length_3d_mm: a3,
                length_2d_mm: a2,
                relative_error: (a2 - a3) / a3,
            });
        }
    }
    (if l3 > 0.0 { (l2 - l3) / l3 } else { 0.0 }, segs)
}

fn over_limit(
    mesh: &TriMesh,
    flat: &[DVec2],
    faces: &[FaceMeasure],
    kind: &'static str,
    over: impl Fn(&FaceMeasure) -> Option<f64>,
) -> Vec<Region> {
    let bad: Vec<bool> = faces.iter().map(|f| over(f).is_some()).collect();
    // Edge adjacency among the bad faces.
    let mut edge_faces: BTreeMap<(u32, u32), Vec<usize>> = BTreeMap::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if !bad[t] {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            edge_faces.entry((a.min(b), a.max(b))).or_default().push(t);
        }
    }
    let mut label = vec![usize::MAX; faces.len()];
    let mut regions = Vec::new();
    for seed in 0..faces.len() {
        if !bad[seed] || label[seed] != usize::MAX {
            continue;
        }
        let id = regions.len();
        let mut stack = vec![seed];
        label[seed] = id;
        let (mut count, mut area, mut worst, mut worst_face) = (0usize, 0.0, 0.0f64, seed);
        let (mut c3, mut c2) = (DVec3::ZERO, DVec2::ZERO);
        while let Some(t) = stack.pop() {
            count += 1;
            let a = faces[t].area_3d;
            area += a;
            let v = over(&faces[t]).unwrap_or(0.0);
            if v > worst || (v == worst && t < worst_face) {
                (worst, worst_face) = (v, t);
            }
            let [p, q, r] = mesh.corners(t);
            c3 += (p + q + r) / 3.0 * a;
            let tri = mesh.triangles[t];
            c2 += (flat[tri[0] as usize] + flat[tri[1] as usize] + flat[tri[2] as usize]) / 3.0 * a;
            for k in 0..3 {
                let (x, y) = (tri[k], tri[(k + 1) % 3]);
                for &u in &edge_faces[&(x.min(y), x.max(y))] {
                    if label[u] == usize::MAX {
                        label[u] = id;
                        stack.push(u);
                    }
                }
            }
        }
        regions.push(Region {
            kind,
            faces: count,
            area_mm2: area,
            worst_pct: worst,
            centroid_3d: (c3 / area).to_array(),
            centroid_2d: (c2 / area).to_array(),
            worst_at_3d: (mesh.corners(worst_face).iter().sum::<DVec3>() / 3.0).to_array(),
            worst_at_2d: (mesh.triangles[worst_face]
                .iter()
                .map(|&v| flat[v as usize])
                .sum::<DVec2>()
                / 3.0)
                .to_array(),
        });
    }
    regions.sort_by(|a, b| b.worst_pct.total_cmp(&a.worst_pct));
    regions
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A wavy 3D grid of `2 n²` faces mapped to the plane by a shear that varies over it: every
    /// face's measures differ.
    fn wavy(n: usize) -> TriMesh {
        let mut m = flatcut_mesh::test_grid::grid_mesh(n, n, |i, j| {
            let (x, y) = (i as f64, j as f64);
            DVec3::new(x, y, 0.3 * (0.2 * x).sin() * (0.15 * y).cos())
        });
        let flat = m
            .positions
            .iter()
            .map(|p| DVec2::new(p.x + 0.01 * p.y * (0.1 * p.x).cos(), 1.02 * p.y))
            .collect();
        m.flat = Some(flat);
        m
    }

    #[test]
    fn faces_measured_in_two_halves_are_the_faces_measured_in_order() {
        let m = wavy(170);
        assert!(m.triangles.len() >= TWO_THREADS_FROM);
        let r = Report::compute("wavy", &m, &ReportOptions::default()).unwrap();
        assert_eq!(r.per_face.len(), m.triangles.len());
        for (t, f) in r.per_face.iter().enumerate() {
            let want = face_measure(&m, t).unwrap();
            // Bit for bit (Debug prints every digit of each value).
            assert_eq!(format!("{f:?}"), format!("{want:?}"), "face {t}");
        }
        // And the statistics are those of the faces in order.
        let delta2: Vec<(f64, f64)> = r.per_face.iter().map(|f| (f.delta2, f.area_3d)).collect();
        let s2 = weighted_stats(&delta2);
        assert_eq!(r.delta2_mean.to_bits(), s2.mean.to_bits());
        assert_eq!(r.delta2_p90.to_bits(), s2.p90.to_bits());
    }

    #[test]
    fn values_sorted_by_their_bits_are_in_a_stable_sort_by_value() {
        // Ties (each value several times, with different weights), both zeros, infinities and
        // values of every sign and size.
        let special = [
            0.0,
            -0.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            1e-300,
            -1e300,
            5e-324,
        ];
        let values: Vec<(f64, f64)> = (0..20_000u64)
            .map(|i| {
                let h = i.wrapping_mul(0x9e37_79b9_7f4a_7c15) >> 40;
                let v = match h % 4 {
                    0 => special[(h / 4 % 7) as usize],
                    1 => (h % 97) as f64 * 0.25,
                    2 => -((h % 13) as f64) * 3.5,
                    _ => (h as f64).sin() * 1e5,
                };
                (v, i as f64)
            })
            .collect();
        let mut want = values.clone();
        want.sort_by(|a, b| a.0.total_cmp(&b.0));
        let got = sorted_by_value(&values);
        let bits = |v: &[(f64, f64)]| -> Vec<(u64, u64)> {
            v.iter().map(|p| (p.0.to_bits(), p.1.to_bits())).collect()
        };
        assert_eq!(bits(&got), bits(&want));
    }

    #[test]
    fn the_first_degenerate_face_is_named_whichever_half_it_is_in() {
        let mut m = wavy(170);
        let n = m.triangles.len();
        // Collapse a face in the second half, then also one in the first half.
        let collapse = |m: &mut TriMesh, t: usize| {
            let [a, b, _] = m.triangles[t];
            m.triangles[t] = [a, b, b];
        };
        collapse(&mut m, n - 10);
        let face = |m: &TriMesh| match Report::compute("wavy", m, &ReportOptions::default()) {
            Err(ReportError::DegenerateFace { face, .. }) => face,
            other => panic!("expected a degenerate face, got {other:?}"),
        };
        assert_eq!(face(&m), n - 10);
        collapse(&mut m, 7);
        assert_eq!(face(&m), 7);
    }
}
