//! The design file: the TOML (or JSON) a pattern maker writes by hand to describe pieces as
//! parametric surfaces or meshes, with seams, marks, grain and material per piece.
//!
//! ```toml
//! units = "mm"                 # "mm" (default), "cm", "m", "in": converted to mm at load time
//! [[piece]]
//! name = "saddle"
//! quantity = 2
//! [piece.surface]
//! type = "bezier"
//! degree = [1, 1]
//! points = [[0, 0, 0], [0, 100, 0], [100, 0, 0], [100, 100, 20]]   # v varying fastest
//! ```
//!
//! Surface types: `bezier`, `hermite`, `bspline`, `nurbs`, `coons`, `gordon`, `ruled`,
//! `developable`, `sphere`, `cylinder`, `cone`, `torus`, `triangular-bezier`, `patches` (a list of
//! surfaces forming one piece) and `mesh` (`file = "x.obj"`, relative to the design file). Curves
//! (for coons, gordon, ruled, developable): `bezier`, `bspline`, `nurbs`, `polyline`, `hermite`,
//! `arc`, `spline` (interpolating cubic through points).
//!
//! Unknown keys are errors (`deny_unknown_fields`) so a typo never silently drops data. Every
//! error names the file, the piece (index and name) and what is wrong; parse errors carry the
//! parser's line and column.
//!
//! **Architecture invariant:** this crate only translates the file into surfaces and meshes; all
//! geometry lives in flatcut-surface and flatcut-mesh.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use flatcut_geom::{DVec3, Tolerances};
use flatcut_mesh::io::{MeshIoError, is_mesh_path, read_mesh};
use flatcut_mesh::{TessError, TriMesh, tessellate_patches};
use flatcut_surface::curve::{
    BSpline, Bezier, CubicSpline, Hermite, Nurbs, Polyline, SplineEnds, SplineParam,
};
use flatcut_surface::patch::{
    BSplinePatch, BezierPatch, CoonsPatch, DevelopableSurface, GordonSurface, HermitePatch,
    RuledSurface, TriBezierPatch,
};
use flatcut_surface::{ParamCurve, ParamSurface, SurfaceError};
use serde::Deserialize;

/// Why a design could not be loaded or built. Messages name the file, the piece and the problem.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DesignError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{file}:{line}:{col}: {msg}")]
    Syntax {
        file: String,
        line: usize,
        col: usize,
        msg: String,
    },
    #[error("{file}: the design has no [[piece]]")]
    NoPieces { file: String },
    #[error("{file}: piece {index} '{piece}': {msg}")]
    Piece {
        file: String,
        index: usize,
        piece: String,
        msg: String,
    },
    #[error("{file}: piece {index} '{piece}': {source}")]
    Surface {
        file: String,
        index: usize,
        piece: String,
        source: SurfaceError,
    },
    #[error("{file}: piece {index} '{piece}': {source}")]
    Mesh {
        file: String,
        index: usize,
        piece: String,
        source: Box<MeshIoError>,
    },
    #[error("{file}: piece {index} '{piece}': {source}")]
    Tessellation {
        file: String,
        index: usize,
        piece: String,
        source: TessError,
    },
}

/// Length units of a design file; every length is converted to mm once at load time.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Units {
    #[default]
    Mm,
    Cm,
    M,
    In,
}

impl Units {
    /// Millimetres per unit.
    pub fn mm(self) -> f64 {
        match self {
            Units::Mm => 1.0,
            Units::Cm => 10.0,
            Units::M => 1000.0,
            Units::In => 25.4,
        }
    }
}

/// A 3D point as written in the file (design units until loaded).
pub type P3 = [f64; 3];

/// A curve in a design file.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
pub enum CurveDef {
    /// Bézier curve of degree `points.len() − 1`.
    Bezier { points: Vec<P3> },
    /// B-spline; clamped uniform knots when `knots` is omitted.
    Bspline {
        degree: usize,
        points: Vec<P3>,
        #[serde(default)]
        knots: Option<Vec<f64>>,
    },
    /// NURBS; clamped uniform knots when `knots` is omitted.
    Nurbs {
        degree: usize,
        points: Vec<P3>,
        weights: Vec<f64>,
        #[serde(default)]
        knots: Option<Vec<f64>>,
    },
    /// Straight segments through the points.
    Polyline { points: Vec<P3> },
    /// Cubic Hermite segment: end points and end tangents.
    Hermite { p0: P3, t0: P3, p1: P3, t1: P3 },
    /// Exact circular arc around `center` in the plane of `x_axis`, `y_axis` (default xy plane),
    /// from `start_deg` to `end_deg`.
    Arc {
        center: P3,
        radius: f64,
        start_deg: f64,
        end_deg: f64,
        #[serde(default)]
        x_axis: Option<P3>,
        #[serde(default)]
        y_axis: Option<P3>,
    },
    /// Interpolating C² cubic spline through the points (chord-length, natural ends; a closed
    /// loop when `closed = true`).
    Spline {
        points: Vec<P3>,
        #[serde(default)]
        closed: bool,
    },
}

/// Blending of a Coons patch.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Blend {
    #[default]
    Linear,
    Cubic,
}

/// A surface in a design file.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
pub enum SurfaceDef {
    /// Tensor-product Bézier patch: `(du+1)(dv+1)` points, v varying fastest.
    Bezier { degree: [usize; 2], points: Vec<P3> },
    /// Bicubic Hermite patch from corner data `corners[i][j] = P(i, j)`.
    Hermite {
        corners: [[P3; 2]; 2],
        tangents_u: [[P3; 2]; 2],
        tangents_v: [[P3; 2]; 2],
        #[serde(default)]
        twists: Option<[[P3; 2]; 2]>,
    },
    /// B-spline patch; `counts = [nu, nv]` poles (v fastest), clamped uniform knots by default.
    Bspline {
        degree: [usize; 2],
        counts: [usize; 2],
        points: Vec<P3>,
        #[serde(default)]
        knots_u: Option<Vec<f64>>,
        #[serde(default)]
        knots_v: Option<Vec<f64>>,
    },
    /// NURBS patch: as `bspline` with one weight per pole.
    Nurbs {
        degree: [usize; 2],
        counts: [usize; 2],
        points: Vec<P3>,
        weights: Vec<f64>,
        #[serde(default)]
        knots_u: Option<Vec<f64>>,
        #[serde(default)]
        knots_v: Option<Vec<f64>>,
    },
    /// Coons patch: `P(u,0) = v0`, `P(u,1) = v1`, `P(0,v) = u0`, `P(1,v) = u1`.
    Coons {
        v0: CurveDef,
        v1: CurveDef,
        u0: CurveDef,
        u1: CurveDef,
        #[serde(default)]
        blend: Blend,
    },
    /// Gordon surface through a curve network: `u_curves[i]` at `u = u_params[i]` (running in
    /// v), `v_curves[j]` at `v = v_params[j]`.
    Gordon {
        u_curves: Vec<CurveDef>,
        v_curves: Vec<CurveDef>,
        u_params: Vec<f64>,
        v_params: Vec<f64>,
    },
    /// Ruled surface between two curves.
    Ruled { curves: [CurveDef; 2] },
    /// Developable surface between two rails.
    Developable { rails: [CurveDef; 2] },
    /// Exact sphere.
    Sphere { center: P3, radius: f64 },
    /// Exact cylinder around the z axis through `base`.
    Cylinder { base: P3, radius: f64, height: f64 },
    /// Exact cone frustum around the z axis through `base`.
    Cone {
        base: P3,
        base_radius: f64,
        top_radius: f64,
        height: f64,
    },
    /// Exact torus around the z axis.
    Torus { center: P3, major: f64, minor: f64 },
    /// Triangular Bézier patch of the given degree, `(n+1)(n+2)/2` points.
    TriangularBezier { degree: usize, points: Vec<P3> },
    /// Several surfaces forming one piece (tessellated crack-free).
    Patches { patches: Vec<SurfaceDef> },
    /// A mesh file (.obj, .stl, .ply), relative to the design file, in the design's units.
    Mesh { file: String },
}

/// A seam: 3D points `[x, y, z]` (joined by shortest mesh-edge paths), surface parameters
/// `[u, v]` of a single-patch piece (same), or, for mesh pieces, vertex indices.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum SeamDef {
    Points(Vec<P3>),
    Params(Vec<[f64; 2]>),
    Vertices(Vec<u32>),
}

/// What a mark is for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MarkKind {
    /// A notch on the outline.
    Notch,
    /// A stitch or placement line.
    #[default]
    Line,
    /// A drill hole or single reference point.
    Point,
}

/// A named mark on the surface: a notch, a stitch line, a reference point.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MarkDef {
    pub name: String,
    #[serde(default)]
    pub kind: MarkKind,
    pub points: Vec<P3>,
}

fn one() -> u32 {
    1
}

/// One piece of a design.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PieceDef {
    pub name: String,
    /// How many to cut (default 1).
    #[serde(default = "one")]
    pub quantity: u32,
    pub surface: SurfaceDef,
    #[serde(default)]
    pub seams: Vec<SeamDef>,
    #[serde(default)]
    pub marks: Vec<MarkDef>,
    /// Grain direction: from the first point to the second (on or near the surface).
    #[serde(default)]
    pub grain: Option<[P3; 2]>,
    #[serde(default)]
    pub seam_allowance_mm: Option<f64>,
    #[serde(default)]
    pub material: Option<String>,
    /// Position in the file (0-based), set at load time.
    #[serde(skip)]
    pub index: usize,
    /// The file the piece came from, for error messages.
    #[serde(skip)]
    pub file: String,
    /// Millimetres per design unit, applied to mesh files when they are read.
    #[serde(skip, default = "unit_scale")]
    pub mesh_scale: f64,
}

fn unit_scale() -> f64 {
    1.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DesignFile {
    #[serde(default)]
    units: Units,
    #[serde(default, rename = "piece")]
    pieces: Vec<PieceDef>,
}

/// A loaded design: pieces with every length in mm.
#[derive(Clone, Debug, PartialEq)]
pub struct Design {
    /// Units the file was written in (lengths are already converted).
    pub units: Units,
    pub pieces: Vec<PieceDef>,
    /// Name of the source (file path or the name given to `from_*_str`).
    pub source: String,
}

/// The geometry of a built piece.
#[derive(Clone, Debug)]
pub enum PieceGeometry {
    /// One or more parametric patches (mm).
    Patches(Vec<Arc<dyn ParamSurface>>),
    /// A mesh (mm).
    Mesh(TriMesh),
}

impl PieceGeometry {
    /// A triangle mesh of the piece: patches are tessellated to `tol.chord_mm` (crack-free across
    /// patches); a mesh is returned as it is.
    pub fn tessellate(&self, tol: &Tolerances) -> Result<TriMesh, TessError> {
        match self {
            PieceGeometry::Mesh(m) => Ok(m.clone()),
            PieceGeometry::Patches(p) if p.len() == 1 && is_developable(p[0].as_ref()) => {
                // Ruling-aligned grid: the polyhedral surface is exactly developable too.
                flatcut_mesh::grid::tessellate_grid(p[0].as_ref(), tol)
            }
            PieceGeometry::Patches(p) => {
                let refs: Vec<&dyn ParamSurface> = p.iter().map(|s| s.as_ref()).collect();
                let mut m = tessellate_patches(&refs, tol)?;
                if p.len() == 1 {
                    m.patch_of_vertex = None;
                }
                Ok(m)
            }
        }
    }
}

/// A single rectangular patch whose sampled Gaussian curvature is below this (scaled by its
/// size squared) is tessellated on a grid along its parameter lines.
const DEVELOPABLE_SCALED_K: f64 = 1e-9;
/// Samples per side for that test.
const DEVELOPABLE_SAMPLES: usize = 16;

fn is_developable(s: &dyn ParamSurface) -> bool {
    s.domain_kind() == flatcut_surface::DomainKind::Rectangle
        && flatcut_surface::diffgeom::developability(s, DEVELOPABLE_SAMPLES).max_scaled_k
            < DEVELOPABLE_SCALED_K
}

fn line_col(src: &str, offset: usize) -> (usize, usize) {
    let before = &src[..offset.min(src.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

impl Design {
    /// Loads a design from a `.toml` or `.json` file, or a mesh file (`.obj`, `.stl`, `.ply`)
    /// as a one-piece design named after the file.
    pub fn load(path: &Path) -> Result<Design, DesignError> {
        let name = path.display().to_string();
        if is_mesh_path(path) {
            let stem = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "mesh".into());
            let file = path
                .file_name()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            return Ok(Design {
                units: Units::Mm,
                pieces: vec![PieceDef {
                    name: stem,
                    quantity: 1,
                    surface: SurfaceDef::Mesh { file },
                    seams: Vec::new(),
                    marks: Vec::new(),
                    grain: None,
                    seam_allowance_mm: None,
                    material: None,
                    index: 0,
                    file: name,
                    mesh_scale: 1.0,
                }],
                source: path.display().to_string(),
            });
        }
        let text = std::fs::read_to_string(path).map_err(|source| DesignError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let is_json = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"));
        if is_json {
            Self::from_json_str(&text, &name)
        } else {
            Self::from_toml_str(&text, &name)
        }
    }

    /// Parses TOML text; `name` names the source in errors.
    pub fn from_toml_str(text: &str, name: &str) -> Result<Design, DesignError> {
        let f: DesignFile = toml::from_str(text).map_err(|e| {
            let (line, col) = e.span().map_or((0, 0), |s| line_col(text, s.start));
            DesignError::Syntax {
                file: name.to_string(),
                line,
                col,
                msg: e.message().to_string(),
            }
        })?;
        Self::finish(f, name)
    }

    /// Parses JSON text (same structure as TOML: `{"units": "mm", "piece": [...]}`).
    pub fn from_json_str(text: &str, name: &str) -> Result<Design, DesignError> {
        let f: DesignFile = serde_json::from_str(text).map_err(|e| DesignError::Syntax {
            file: name.to_string(),
            line: e.line(),
            col: e.column(),
            msg: e.to_string(),
        })?;
        Self::finish(f, name)
    }

    fn finish(f: DesignFile, name: &str) -> Result<Design, DesignError> {
        if f.pieces.is_empty() {
            return Err(DesignError::NoPieces {
                file: name.to_string(),
            });
        }
        let s = f.units.mm();
        let mut pieces = f.pieces;
        for (i, p) in pieces.iter_mut().enumerate() {
            p.index = i;
            p.file = name.to_string();
            let ctx = Ctx::of(p);
            if p.quantity == 0 {
                return Err(ctx.err("quantity must be at least 1".into()));
            }
            if let Some(a) = p.seam_allowance_mm
                && !(a.is_finite() && a >= 0.0)
            {
                return Err(ctx.err(format!("seam_allowance_mm must be finite and ≥ 0, got {a}")));
            }
            check_surface(&ctx, &p.surface)?;
            for (k, seam) in p.seams.iter().enumerate() {
                match seam {
                    SeamDef::Points(pts) => check_points(&ctx, &format!("seam {k}"), pts)?,
                    SeamDef::Params(uv) if uv.iter().flatten().any(|x| !x.is_finite()) => {
                        return Err(ctx.err(format!("seam {k}: non-finite (u, v)")));
                    }
                    _ => {}
                }
            }
            for m in &p.marks {
                check_points(&ctx, &format!("mark '{}'", m.name), &m.points)?;
                if m.points.is_empty() {
                    return Err(ctx.err(format!("mark '{}' has no points", m.name)));
                }
            }
            if let Some(g) = &p.grain {
                check_points(&ctx, "grain", g)?;
                if g[0] == g[1] {
                    return Err(ctx.err("grain: the two points coincide (no direction)".into()));
                }
            }
            if s != 1.0 {
                scale_piece(p, s);
            }
        }
        Ok(Design {
            units: f.units,
            pieces,
            source: name.to_string(),
        })
    }
}

/// Error context: file, piece index and name.
struct Ctx {
    file: String,
    index: usize,
    piece: String,
}

impl Ctx {
    fn of(p: &PieceDef) -> Ctx {
        Ctx {
            file: p.file.clone(),
            index: p.index,
            piece: p.name.clone(),
        }
    }
    fn err(&self, msg: String) -> DesignError {
        DesignError::Piece {
            file: self.file.clone(),
            index: self.index,
            piece: self.piece.clone(),
            msg,
        }
    }
    fn surf(&self, what: &str, e: SurfaceError) -> DesignError {
        self.err(format!("{what}: {e}"))
    }
}

fn check_points(ctx: &Ctx, what: &str, pts: &[P3]) -> Result<(), DesignError> {
    match pts.iter().position(|p| !p.iter().all(|x| x.is_finite())) {
        Some(i) => Err(ctx.err(format!("{what}: point {i} has a non-finite coordinate"))),
        None => Ok(()),
    }
}

fn check_len(ctx: &Ctx, what: &str, x: f64) -> Result<(), DesignError> {
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        Err(ctx.err(format!("{what} must be finite and > 0, got {x}")))
    }
}

fn check_curve(ctx: &Ctx, what: &str, c: &CurveDef) -> Result<(), DesignError> {
    match c {
        CurveDef::Bezier { points }
        | CurveDef::Polyline { points }
        | CurveDef::Spline { points, .. }
        | CurveDef::Bspline { points, .. }
        | CurveDef::Nurbs { points, .. } => check_points(ctx, what, points),
        CurveDef::Hermite { p0, t0, p1, t1 } => check_points(ctx, what, &[*p0, *t0, *p1, *t1]),
        CurveDef::Arc {
            center,
            radius,
            start_deg,
            end_deg,
            ..
        } => {
            check_points(ctx, what, &[*center])?;
            check_len(ctx, &format!("{what}: radius"), *radius)?;
            if !(start_deg.is_finite() && end_deg.is_finite()) {
                return Err(ctx.err(format!("{what}: non-finite angle")));
            }
            Ok(())
        }
    }
}

fn check_surface(ctx: &Ctx, s: &SurfaceDef) -> Result<(), DesignError> {
    match s {
        SurfaceDef::Bezier { points, .. }
        | SurfaceDef::Bspline { points, .. }
        | SurfaceDef::Nurbs { points, .. }
        | SurfaceDef::TriangularBezier { points, .. } => check_points(ctx, "surface", points),
        SurfaceDef::Hermite {
            corners,
            tangents_u,
            tangents_v,
            twists,
        } => {
            let mut all: Vec<P3> = Vec::new();
            for a in [
                Some(corners),
                Some(tangents_u),
                Some(tangents_v),
                twists.as_ref(),
            ]
            .into_iter()
            .flatten()
            {
                all.extend(a.iter().flatten());
            }
            check_points(ctx, "hermite data", &all)
        }
        SurfaceDef::Coons { v0, v1, u0, u1, .. } => {
            for (n, c) in [("v0", v0), ("v1", v1), ("u0", u0), ("u1", u1)] {
                check_curve(ctx, &format!("coons curve {n}"), c)?;
            }
            Ok(())
        }
        SurfaceDef::Gordon {
            u_curves, v_curves, ..
        } => {
            for (i, c) in u_curves.iter().enumerate() {
                check_curve(ctx, &format!("gordon u-curve {i}"), c)?;
            }
            for (i, c) in v_curves.iter().enumerate() {
                check_curve(ctx, &format!("gordon v-curve {i}"), c)?;
            }
            Ok(())
        }
        SurfaceDef::Ruled { curves } => {
            for (i, c) in curves.iter().enumerate() {
                check_curve(ctx, &format!("ruled curve {i}"), c)?;
            }
            Ok(())
        }
        SurfaceDef::Developable { rails } => {
            for (i, c) in rails.iter().enumerate() {
                check_curve(ctx, &format!("developable rail {i}"), c)?;
            }
            Ok(())
        }
        SurfaceDef::Sphere { center, radius } => {
            check_points(ctx, "sphere", &[*center])?;
            check_len(ctx, "sphere radius", *radius)
        }
        SurfaceDef::Cylinder {
            base,
            radius,
            height,
        } => {
            check_points(ctx, "cylinder", &[*base])?;
            check_len(ctx, "cylinder radius", *radius)?;
            check_len(ctx, "cylinder height", *height)
        }
        SurfaceDef::Cone {
            base,
            base_radius,
            top_radius,
            height,
        } => {
            check_points(ctx, "cone", &[*base])?;
            check_len(ctx, "cone base_radius", *base_radius)?;
            check_len(ctx, "cone height", *height)?;
            if !(top_radius.is_finite() && *top_radius >= 0.0) {
                return Err(ctx.err(format!(
                    "cone top_radius must be finite and ≥ 0, got {top_radius}"
                )));
            }
            Ok(())
        }
        SurfaceDef::Torus {
            center,
            major,
            minor,
        } => {
            check_points(ctx, "torus", &[*center])?;
            check_len(ctx, "torus major", *major)?;
            check_len(ctx, "torus minor", *minor)
        }
        SurfaceDef::Patches { patches } => {
            if patches.is_empty() {
                return Err(ctx.err("patches: the list is empty".into()));
            }
            for p in patches {
                check_surface(ctx, p)?;
            }
            Ok(())
        }
        SurfaceDef::Mesh { .. } => Ok(()),
    }
}

fn sp(p: &mut P3, s: f64) {
    for x in p.iter_mut() {
        *x *= s;
    }
}

fn scale_curve(c: &mut CurveDef, s: f64) {
    match c {
        CurveDef::Bezier { points }
        | CurveDef::Polyline { points }
        | CurveDef::Spline { points, .. }
        | CurveDef::Bspline { points, .. }
        | CurveDef::Nurbs { points, .. } => points.iter_mut().for_each(|p| sp(p, s)),
        CurveDef::Hermite { p0, t0, p1, t1 } => {
            for p in [p0, t0, p1, t1] {
                sp(p, s);
            }
        }
        CurveDef::Arc { center, radius, .. } => {
            sp(center, s);
            *radius *= s;
        }
    }
}

fn scale_surface(surf: &mut SurfaceDef, s: f64) {
    match surf {
        SurfaceDef::Bezier { points, .. }
        | SurfaceDef::Bspline { points, .. }
        | SurfaceDef::Nurbs { points, .. }
        | SurfaceDef::TriangularBezier { points, .. } => points.iter_mut().for_each(|p| sp(p, s)),
        SurfaceDef::Hermite {
            corners,
            tangents_u,
            tangents_v,
            twists,
        } => {
            for a in [
                Some(corners),
                Some(tangents_u),
                Some(tangents_v),
                twists.as_mut(),
            ]
            .into_iter()
            .flatten()
            {
                a.iter_mut().flatten().for_each(|p| sp(p, s));
            }
        }
        SurfaceDef::Coons { v0, v1, u0, u1, .. } => {
            for c in [v0, v1, u0, u1] {
                scale_curve(c, s);
            }
        }
        SurfaceDef::Gordon {
            u_curves, v_curves, ..
        } => u_curves
            .iter_mut()
            .chain(v_curves.iter_mut())
            .for_each(|c| scale_curve(c, s)),
        SurfaceDef::Ruled { curves: c } | SurfaceDef::Developable { rails: c } => {
            c.iter_mut().for_each(|c| scale_curve(c, s))
        }
        SurfaceDef::Sphere { center, radius } => {
            sp(center, s);
            *radius *= s;
        }
        SurfaceDef::Cylinder {
            base,
            radius,
            height,
        } => {
            sp(base, s);
            *radius *= s;
            *height *= s;
        }
        SurfaceDef::Cone {
            base,
            base_radius,
            top_radius,
            height,
        } => {
            sp(base, s);
            *base_radius *= s;
            *top_radius *= s;
            *height *= s;
        }
        SurfaceDef::Torus {
            center,
            major,
            minor,
        } => {
            sp(center, s);
            *major *= s;
            *minor *= s;
        }
        SurfaceDef::Patches { patches } => patches.iter_mut().for_each(|p| scale_surface(p, s)),
        // Mesh files are scaled when read (see `PieceDef::build`): they carry design units.
        SurfaceDef::Mesh { .. } => {}
    }
}

fn scale_piece(p: &mut PieceDef, s: f64) {
    scale_surface(&mut p.surface, s);
    for seam in &mut p.seams {
        if let SeamDef::Points(pts) = seam {
            pts.iter_mut().for_each(|q| sp(q, s));
        }
    }
    for m in &mut p.marks {
        m.points.iter_mut().for_each(|q| sp(q, s));
    }
    if let Some(g) = &mut p.grain {
        g.iter_mut().for_each(|q| sp(q, s));
    }
    p.mesh_scale = s;
}

fn v3(p: &P3) -> DVec3 {
    DVec3::from_array(*p)
}

fn pts(p: &[P3]) -> Vec<DVec3> {
    p.iter().map(v3).collect()
}

fn clamped_knots(degree: usize, count: usize) -> Vec<f64> {
    if count <= degree {
        // Invalid; let the constructor report the count mismatch.
        return vec![0.0; degree + 1 + count];
    }
    let inner = count - degree;
    let mut k = vec![0.0; degree + 1];
    for i in 1..inner {
        k.push(i as f64 / inner as f64);
    }
    k.extend(std::iter::repeat_n(1.0, degree + 1));
    k
}

fn build_curve(ctx: &Ctx, what: &str, c: &CurveDef) -> Result<Arc<dyn ParamCurve>, DesignError> {
    let e = |err| ctx.surf(what, err);
    Ok(match c {
        CurveDef::Bezier { points } => Arc::new(Bezier::new(pts(points)).map_err(e)?),
        CurveDef::Bspline {
            degree,
            points,
            knots,
        } => {
            let k = knots
                .clone()
                .unwrap_or_else(|| clamped_knots(*degree, points.len()));
            Arc::new(BSpline::new(*degree, k, pts(points)).map_err(e)?)
        }
        CurveDef::Nurbs {
            degree,
            points,
            weights,
            knots,
        } => {
            let k = knots
                .clone()
                .unwrap_or_else(|| clamped_knots(*degree, points.len()));
            Arc::new(Nurbs::new(*degree, k, pts(points), weights.clone()).map_err(e)?)
        }
        CurveDef::Polyline { points } => Arc::new(Polyline::new(pts(points)).map_err(e)?),
        CurveDef::Hermite { p0, t0, p1, t1 } => {
            Arc::new(Hermite::new(v3(p0), v3(t0), v3(p1), v3(t1)).map_err(e)?)
        }
        CurveDef::Arc {
            center,
            radius,
            start_deg,
            end_deg,
            x_axis,
            y_axis,
        } => Arc::new(
            Nurbs::circle_arc(
                v3(center),
                x_axis.as_ref().map_or(DVec3::X, v3),
                y_axis.as_ref().map_or(DVec3::Y, v3),
                *radius,
                start_deg.to_radians(),
                end_deg.to_radians(),
            )
            .map_err(e)?,
        ),
        CurveDef::Spline { points, closed } => {
            let ends = if *closed {
                SplineEnds::Closed
            } else {
                SplineEnds::Relaxed
            };
            Arc::new(
                CubicSpline::interpolate(&pts(points), ends, SplineParam::ChordLength)
                    .map_err(e)?,
            )
        }
    })
}

fn build_surface(
    ctx: &Ctx,
    s: &SurfaceDef,
    out: &mut Vec<Arc<dyn ParamSurface>>,
) -> Result<(), DesignError> {
    let e = |what: &'static str| move |err| ctx.surf(what, err);
    let surf: Arc<dyn ParamSurface> = match s {
        SurfaceDef::Bezier { degree, points } => {
            Arc::new(BezierPatch::new(degree[0], degree[1], pts(points)).map_err(e("bezier"))?)
        }
        SurfaceDef::Hermite {
            corners,
            tangents_u,
            tangents_v,
            twists,
        } => {
            let m = |a: &[[P3; 2]; 2]| a.map(|r| r.map(|p| v3(&p)));
            let tw = twists.as_ref().map_or([[DVec3::ZERO; 2]; 2], m);
            Arc::new(
                HermitePatch::new(m(corners), m(tangents_u), m(tangents_v), tw)
                    .map_err(e("hermite"))?,
            )
        }
        SurfaceDef::Bspline {
            degree,
            counts,
            points,
            knots_u,
            knots_v,
        }
        | SurfaceDef::Nurbs {
            degree,
            counts,
            points,
            knots_u,
            knots_v,
            ..
        } => {
            let weights = match s {
                SurfaceDef::Nurbs { weights, .. } => Some(weights.clone()),
                _ => None,
            };
            let ku = knots_u
                .clone()
                .unwrap_or_else(|| clamped_knots(degree[0], counts[0]));
            let kv = knots_v
                .clone()
                .unwrap_or_else(|| clamped_knots(degree[1], counts[1]));
            Arc::new(
                BSplinePatch::new(
                    degree[0],
                    degree[1],
                    ku,
                    kv,
                    counts[0],
                    counts[1],
                    pts(points),
                    weights,
                )
                .map_err(e("bspline/nurbs"))?,
            )
        }
        SurfaceDef::Coons {
            v0,
            v1,
            u0,
            u1,
            blend,
        } => {
            let c = [
                build_curve(ctx, "coons curve v0", v0)?,
                build_curve(ctx, "coons curve v1", v1)?,
                build_curve(ctx, "coons curve u0", u0)?,
                build_curve(ctx, "coons curve u1", u1)?,
            ];
            let [a, b, cc, d] = c;
            Arc::new(
                match blend {
                    Blend::Linear => CoonsPatch::bilinear(a, b, cc, d),
                    Blend::Cubic => CoonsPatch::bicubic(a, b, cc, d),
                }
                .map_err(e("coons"))?,
            )
        }
        SurfaceDef::Gordon {
            u_curves,
            v_curves,
            u_params,
            v_params,
        } => {
            let uc = u_curves
                .iter()
                .enumerate()
                .map(|(i, c)| build_curve(ctx, &format!("gordon u-curve {i}"), c))
                .collect::<Result<Vec<_>, _>>()?;
            let vc = v_curves
                .iter()
                .enumerate()
                .map(|(i, c)| build_curve(ctx, &format!("gordon v-curve {i}"), c))
                .collect::<Result<Vec<_>, _>>()?;
            Arc::new(
                GordonSurface::new(uc, vc, u_params.clone(), v_params.clone())
                    .map_err(e("gordon"))?,
            )
        }
        SurfaceDef::Ruled { curves } => Arc::new(
            RuledSurface::new(
                build_curve(ctx, "ruled curve 0", &curves[0])?,
                build_curve(ctx, "ruled curve 1", &curves[1])?,
            )
            .map_err(e("ruled"))?,
        ),
        SurfaceDef::Developable { rails } => Arc::new(
            DevelopableSurface::between(
                build_curve(ctx, "developable rail 0", &rails[0])?,
                build_curve(ctx, "developable rail 1", &rails[1])?,
            )
            .map_err(e("developable"))?,
        ),
        SurfaceDef::Sphere { center, radius } => {
            Arc::new(BSplinePatch::sphere(v3(center), *radius).map_err(e("sphere"))?)
        }
        SurfaceDef::Cylinder {
            base,
            radius,
            height,
        } => Arc::new(BSplinePatch::cylinder(v3(base), *radius, *height).map_err(e("cylinder"))?),
        SurfaceDef::Cone {
            base,
            base_radius,
            top_radius,
            height,
        } => Arc::new(
            BSplinePatch::cone(v3(base), *base_radius, *top_radius, *height).map_err(e("cone"))?,
        ),
        SurfaceDef::Torus {
            center,
            major,
            minor,
        } => Arc::new(BSplinePatch::torus(v3(center), *major, *minor).map_err(e("torus"))?),
        SurfaceDef::TriangularBezier { degree, points } => {
            Arc::new(TriBezierPatch::new(*degree, pts(points)).map_err(e("triangular-bezier"))?)
        }
        SurfaceDef::Patches { patches } => {
            for p in patches {
                if matches!(p, SurfaceDef::Mesh { .. } | SurfaceDef::Patches { .. }) {
                    return Err(ctx.err(
                        "patches: a patch list may hold parametric surfaces only (no mesh, no nested list)"
                            .into(),
                    ));
                }
                build_surface(ctx, p, out)?;
            }
            return Ok(());
        }
        SurfaceDef::Mesh { .. } => {
            return Err(ctx.err("mesh: not a parametric surface".into()));
        }
    };
    out.push(surf);
    Ok(())
}

impl PieceDef {
    /// Builds the piece's geometry; mesh files are resolved against `base_dir` (the design
    /// file's directory) and scaled from the design's units to mm.
    pub fn build(&self, base_dir: &Path) -> Result<PieceGeometry, DesignError> {
        let ctx = Ctx::of(self);
        if let SurfaceDef::Mesh { file } = &self.surface {
            let path = base_dir.join(file);
            let mut m = read_mesh(&path).map_err(|source| DesignError::Mesh {
                file: ctx.file.clone(),
                index: ctx.index,
                piece: ctx.piece.clone(),
                source: Box::new(source),
            })?;
            if self.mesh_scale != 1.0 {
                m.positions.iter_mut().for_each(|p| *p *= self.mesh_scale);
                if let Some(f) = &mut m.flat {
                    f.iter_mut().for_each(|q| *q *= self.mesh_scale);
                }
            }
            return Ok(PieceGeometry::Mesh(m));
        }
        let mut out = Vec::new();
        build_surface(&ctx, &self.surface, &mut out)?;
        Ok(PieceGeometry::Patches(out))
    }

    /// Builds, tessellates and cuts the piece along its seams: the mesh a flattening starts from.
    pub fn mesh(&self, base_dir: &Path, tol: &Tolerances) -> Result<TriMesh, DesignError> {
        let ctx = Ctx::of(self);
        let m =
            self.build(base_dir)?
                .tessellate(tol)
                .map_err(|source| DesignError::Tessellation {
                    file: ctx.file.clone(),
                    index: ctx.index,
                    piece: ctx.piece.clone(),
                    source,
                })?;
        if self.seams.is_empty() {
            return Ok(m);
        }
        let mut lists = Vec::new();
        for (k, s) in self.seams.iter().enumerate() {
            let list = match s {
                SeamDef::Vertices(v) => v.clone(),
                SeamDef::Points(p) => flatcut_mesh::seam_from_points(&m, &pts(p))
                    .map_err(|err| ctx.err(format!("seam {k}: {err}")))?,
                SeamDef::Params(uv) => {
                    if m.patch_of_vertex.is_some() || m.params.is_none() {
                        return Err(ctx.err(format!(
                            "seam {k}: (u, v) seams need a single-patch surface; give 3D points"
                        )));
                    }
                    let uv: Vec<flatcut_geom::DVec2> = uv
                        .iter()
                        .map(|q| flatcut_geom::DVec2::from_array(*q))
                        .collect();
                    flatcut_mesh::seams::seam_from_params(&m, &uv)
                        .unwrap_or(Ok(Vec::new()))
                        .map_err(|err| ctx.err(format!("seam {k}: {err}")))?
                }
            };
            lists.push(list);
        }
        flatcut_mesh::cut_along_seams(&m, &lists).map_err(|err| ctx.err(format!("seams: {err}")))
    }
}

#[cfg(test)]
mod tests;
