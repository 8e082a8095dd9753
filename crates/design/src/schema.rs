//! The file's schema: what a design file may contain, as serde types (design units until loaded).

use crate::step::{StepFaces, StepGroup, StepModel};
use crate::units::Axes;
use serde::Deserialize;

/// Length units of a design file; every length is converted to mm once at load time.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Units {
    #[default]
    /// Millimetres (the default).
    Mm,
    /// Centimetres: 10 mm.
    Cm,
    /// Metres: 1000 mm.
    M,
    /// Inches: 25.4 mm.
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
    Bezier {
        /// Control points, at least two; the first and last are the curve's ends.
        points: Vec<P3>,
    },
    /// B-spline; clamped uniform knots when `knots` is omitted.
    Bspline {
        /// Polynomial degree, at least 1 and below the number of points.
        degree: usize,
        /// Control points (poles), at least `degree + 1`.
        points: Vec<P3>,
        #[serde(default)]
        /// Non-decreasing knots, `points.len() + degree + 1` of them.
        knots: Option<Vec<f64>>,
    },
    /// NURBS; clamped uniform knots when `knots` is omitted.
    Nurbs {
        /// Polynomial degree, at least 1 and below the number of points.
        degree: usize,
        /// Control points (poles), at least `degree + 1`.
        points: Vec<P3>,
        /// One weight per point, finite and > 0.
        weights: Vec<f64>,
        #[serde(default)]
        /// Non-decreasing knots, `points.len() + degree + 1` of them.
        knots: Option<Vec<f64>>,
    },
    /// Straight segments through the points.
    Polyline {
        /// The vertices, at least two, in order.
        points: Vec<P3>,
    },
    /// Cubic Hermite segment: end points and end tangents.
    Hermite {
        /// Start point.
        p0: P3,
        /// Tangent (derivative with respect to the parameter in [0, 1]) at the start point.
        t0: P3,
        /// End point.
        p1: P3,
        /// Tangent (derivative with respect to the parameter in [0, 1]) at the end point.
        t1: P3,
    },
    /// Exact circular arc around `center` in the plane of `x_axis`, `y_axis` (default xy plane),
    /// from `start_deg` to `end_deg`.
    Arc {
        /// The circle's centre.
        center: P3,
        /// The circle's radius, finite and > 0.
        radius: f64,
        /// Start angle in degrees from `x_axis` towards `y_axis`.
        start_deg: f64,
        /// End angle in degrees, above `start_deg` by at most 360.
        end_deg: f64,
        #[serde(default)]
        /// Direction of angle 0 (default x); normalised.
        x_axis: Option<P3>,
        #[serde(default)]
        /// Direction of angle 90° (default y); must not be parallel to `x_axis`.
        y_axis: Option<P3>,
    },
    /// Interpolating C² cubic spline through the points (chord-length, natural ends; a closed
    /// loop when `closed = true`).
    Spline {
        /// The points the spline passes through, in order.
        points: Vec<P3>,
        #[serde(default)]
        /// Whether the spline closes back to its first point, C² there too.
        closed: bool,
    },
}

/// Blending of a Coons patch.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Blend {
    #[default]
    /// Linear blending `1 − t`, `t` (the bilinear Coons patch; the default).
    Linear,
    /// Hermite cubic blending `1 − 3t² + 2t³`, `3t² − 2t³`: zero slope at the edges, so
    /// cross-boundary derivatives depend only on the boundary curves.
    Cubic,
}

/// A surface in a design file.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
pub enum SurfaceDef {
    /// Tensor-product Bézier patch: `(du+1)(dv+1)` points, v varying fastest.
    Bezier {
        /// Degrees `[du, dv]`, each at least 1.
        degree: [usize; 2],
        /// `(du+1)(dv+1)` control points, v varying fastest.
        points: Vec<P3>,
    },
    /// Bicubic Hermite patch from corner data `corners[i][j] = P(i, j)`.
    Hermite {
        /// `corners[i][j]` is the point at `(u, v) = (i, j)`.
        corners: [[P3; 2]; 2],
        /// `tangents_u[i][j]` is ∂P/∂u at corner `(i, j)`.
        tangents_u: [[P3; 2]; 2],
        /// `tangents_v[i][j]` is ∂P/∂v at corner `(i, j)`.
        tangents_v: [[P3; 2]; 2],
        #[serde(default)]
        /// `twists[i][j]` is ∂²P/∂u∂v at corner `(i, j)` (default zero: a Ferguson patch).
        twists: Option<[[P3; 2]; 2]>,
    },
    /// B-spline patch; `counts = [nu, nv]` poles (v fastest), clamped uniform knots by default.
    Bspline {
        /// Degrees `[du, dv]`, each at least 1.
        degree: [usize; 2],
        /// Number of poles `[nu, nv]`, each above its degree.
        counts: [usize; 2],
        /// `nu · nv` poles, v varying fastest.
        points: Vec<P3>,
        #[serde(default)]
        /// Knots in u, `nu + du + 1` of them (default clamped uniform).
        knots_u: Option<Vec<f64>>,
        #[serde(default)]
        /// Knots in v, `nv + dv + 1` of them (default clamped uniform).
        knots_v: Option<Vec<f64>>,
    },
    /// NURBS patch: as `bspline` with one weight per pole.
    Nurbs {
        /// Degrees `[du, dv]`, each at least 1.
        degree: [usize; 2],
        /// Number of poles `[nu, nv]`, each above its degree.
        counts: [usize; 2],
        /// `nu · nv` poles, v varying fastest.
        points: Vec<P3>,
        /// One weight per pole, finite and > 0.
        weights: Vec<f64>,
        #[serde(default)]
        /// Knots in u, `nu + du + 1` of them (default clamped uniform).
        knots_u: Option<Vec<f64>>,
        #[serde(default)]
        /// Knots in v, `nv + dv + 1` of them (default clamped uniform).
        knots_v: Option<Vec<f64>>,
    },
    /// Coons patch: `P(u,0) = v0`, `P(u,1) = v1`, `P(0,v) = u0`, `P(1,v) = u1`.
    Coons {
        /// The boundary `P(u, 0)`.
        v0: CurveDef,
        /// The boundary `P(u, 1)`.
        v1: CurveDef,
        /// The boundary `P(0, v)`.
        u0: CurveDef,
        /// The boundary `P(1, v)`.
        u1: CurveDef,
        #[serde(default)]
        /// How the boundaries are blended into the interior (default linear).
        blend: Blend,
    },
    /// Gordon surface through a curve network: `u_curves[i]` at `u = u_params[i]` (running in
    /// v), `v_curves[j]` at `v = v_params[j]`.
    Gordon {
        /// Curves of constant u, running in v; at least two.
        u_curves: Vec<CurveDef>,
        /// Curves of constant v, running in u; at least two.
        v_curves: Vec<CurveDef>,
        /// The u value of each of `u_curves`, increasing.
        u_params: Vec<f64>,
        /// The v value of each of `v_curves`, increasing.
        v_params: Vec<f64>,
    },
    /// Ruled surface between two curves.
    Ruled {
        /// The two curves; straight rulings join points of equal parameter.
        curves: [CurveDef; 2],
    },
    /// Developable surface between two rails.
    Developable {
        /// The two rails; rulings join them so that the surface flattens without distortion.
        rails: [CurveDef; 2],
    },
    /// Exact sphere.
    Sphere {
        /// The sphere's centre.
        center: P3,
        /// The sphere's radius, finite and > 0.
        radius: f64,
    },
    /// Exact cylinder around the z axis through `base`.
    Cylinder {
        /// Centre of the bottom circle.
        base: P3,
        /// Radius, finite and > 0.
        radius: f64,
        /// Height along +z, finite and > 0.
        height: f64,
    },
    /// Exact cone frustum around the z axis through `base`.
    Cone {
        /// Centre of the bottom circle.
        base: P3,
        /// Radius of the bottom circle, ≥ 0.
        base_radius: f64,
        /// Radius of the top circle, ≥ 0.
        top_radius: f64,
        /// Height along +z, finite and > 0.
        height: f64,
    },
    /// Exact torus around the z axis.
    Torus {
        /// Centre of the centre circle.
        center: P3,
        /// Radius of the centre circle, above `minor`.
        major: f64,
        /// Radius of the tube, finite and > 0.
        minor: f64,
    },
    /// Triangular Bézier patch of the given degree, `(n+1)(n+2)/2` points.
    TriangularBezier {
        /// Degree `n`, at least 1.
        degree: usize,
        /// `(n+1)(n+2)/2` control points, in the order `flatcut_surface`'s triangular patch
        /// documents.
        points: Vec<P3>,
    },
    /// Several surfaces forming one piece (tessellated crack-free).
    Patches {
        /// The surfaces, meeting edge to edge.
        patches: Vec<SurfaceDef>,
    },
    /// A mesh file (.obj, .stl, .ply), relative to the design file, in the design's units.
    Mesh {
        /// The mesh file's path, relative to the design file.
        file: String,
    },
    /// Faces of a STEP model (relative to the design file, in the model's own unit); expanded
    /// into one piece per face or per smooth group when the design is loaded (see `step`).
    Step {
        /// The STEP file's path, relative to the design file.
        file: String,
        #[serde(default)]
        /// Which faces to take (default all).
        faces: StepFaces,
        #[serde(default)]
        /// How the chosen faces become pieces (default one piece per face).
        group: StepGroup,
        /// The model, once read (set when the design is loaded).
        #[serde(skip)]
        model: Option<StepModel>,
    },
}

/// A seam: 3D points `[x, y, z]` (joined by shortest mesh-edge paths), surface parameters
/// `[u, v]` of a single-patch piece (same), or, for mesh pieces, vertex indices.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum SeamDef {
    /// 3D points `[x, y, z]` on (or near) the surface.
    Points(Vec<P3>),
    /// Surface parameters `[u, v]` of a single-patch piece.
    Params(Vec<[f64; 2]>),
    /// 0-based vertex indices of a mesh piece's file.
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
    /// The mark's name, carried to the pattern and used in messages.
    pub name: String,
    #[serde(default)]
    /// What the mark is for (default a line).
    pub kind: MarkKind,
    /// Points on (or near) the surface: one for a notch or point, two or more for a line.
    pub points: Vec<P3>,
}

pub(crate) fn one() -> u32 {
    1
}

/// A piece's grain: a line of two points on the surface (the warp runs from the first to the
/// second), or `"auto"`: the flattening chooses the direction that exceeds the material's limits
/// least.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GrainDef {
    /// From the first point to the second, both on (or near) the surface.
    Line([P3; 2]),
    /// Chosen by the flattening: the direction that exceeds the material's limits least.
    Auto,
}

impl GrainDef {
    /// The grain line, if one is drawn.
    pub fn line(&self) -> Option<&[P3; 2]> {
        match self {
            GrainDef::Line(l) => Some(l),
            GrainDef::Auto => None,
        }
    }

    pub(crate) fn line_mut(&mut self) -> Option<&mut [P3; 2]> {
        match self {
            GrainDef::Line(l) => Some(l),
            GrainDef::Auto => None,
        }
    }
}

impl<'de> Deserialize<'de> for GrainDef {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Line([P3; 2]),
            Word(String),
        }
        match Raw::deserialize(d) {
            Ok(Raw::Line(l)) => Ok(GrainDef::Line(l)),
            Ok(Raw::Word(w)) if w == "auto" => Ok(GrainDef::Auto),
            _ => Err(serde::de::Error::custom(
                "grain: expected two points [[x, y, z], [x, y, z]] or \"auto\"",
            )),
        }
    }
}

/// One piece of a design.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PieceDef {
    /// The piece's name, unique in the design.
    pub name: String,
    /// How many to cut as drawn (default 1; `pairs` when given).
    #[serde(default = "one")]
    pub quantity: u32,
    /// `pairs = N`: N as drawn and N mirrored (left and right); sets `quantity` and `mirrored`.
    #[serde(default)]
    pub pairs: Option<u32>,
    /// How many mirror images to cut besides (set from `pairs` at load time).
    #[serde(skip)]
    pub mirrored: u32,
    /// What the labels of a pair say: as drawn, then mirrored (default "L", "R").
    #[serde(default)]
    pub pair_labels: Option<[String; 2]>,
    /// The piece's geometry.
    pub surface: SurfaceDef,
    #[serde(default)]
    /// Seams on the piece's surface where it is cut open (a closed or too-curved surface).
    pub seams: Vec<SeamDef>,
    #[serde(default)]
    /// Notches, stitch lines and points on the surface.
    pub marks: Vec<MarkDef>,
    /// Grain direction: from the first point to the second (on or near the surface), or
    /// `"auto"`.
    #[serde(default)]
    pub grain: Option<GrainDef>,
    #[serde(default)]
    /// Seam allowance in mm whatever the file's units (default: the project's).
    pub seam_allowance_mm: Option<f64>,
    /// The material's name as printed on the pattern piece (a label only).
    #[serde(default)]
    pub material: Option<String>,
    /// A bundled material (`leather`, `woven-cotton`, …) or a material file relative to the
    /// design: its limits per direction and stiffness drive the orthotropic flattening.
    #[serde(default)]
    pub material_properties: Option<String>,
    /// `"auto"`: cut darts where the piece cannot meet its limits otherwise; `"off"`: never
    /// (default: as the command line or project says).
    #[serde(default)]
    pub darts: Option<DartsDef>,
    /// Regions no dart or cut may cross: polygons of points on the surface.
    #[serde(default)]
    pub no_cut: Vec<Vec<P3>>,
    /// The side seams should face where the pattern must cut a closed or split surface (a
    /// direction, e.g. `[0, 0, -1]`: the underside); seams there cost half as much.
    #[serde(default)]
    pub seam_hidden: Option<P3>,
    /// Regions where seams hide (polygons of points on the surface, like `no_cut`): seams cost a
    /// third as much there.
    #[serde(default)]
    pub seam_hidden_regions: Vec<Vec<P3>>,
    /// Which way each dart's intake is pressed when the dart is sewn (default: toward the
    /// piece's centre line); the pattern trues the dart's mouth for it.
    #[serde(default)]
    pub dart_press: Option<DartPress>,
    /// Named stretches of the piece's outline with their own allowance.
    #[serde(default, rename = "edge")]
    pub edges: Vec<crate::EdgeDef>,
    /// Position in the file (0-based), set at load time.
    #[serde(skip)]
    pub index: usize,
    /// The file the piece came from, for error messages.
    #[serde(skip)]
    pub file: String,
    /// The map from a mesh file's coordinates to mm (the design's units, and a size's scale),
    /// applied when the file is read.
    #[serde(skip, default = "no_map")]
    pub mesh_map: Axes,
    /// The stretches of its outline with their own allowance, found when the design is
    /// assembled: its `[[piece.edge]]`s, its part's `[[part.edge]]`s (whole: the stretch of one
    /// on this piece's outline counts) and the style lines beside it, each named after its
    /// seam.
    #[serde(skip)]
    pub outline_edges: Vec<crate::OutlineEdge>,
    /// The size of a graded design the piece is cut in, and its name in the design (set when
    /// the sizes are flattened; the piece is then named `<piece> <size>`).
    #[serde(skip)]
    pub size: Option<PieceSize>,
}

/// A piece of one size of a graded design.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PieceSize {
    /// The size's name.
    pub size: String,
    /// The piece's name in the design (without the size).
    pub piece: String,
}

impl PieceDef {
    /// One piece of `surface` with every per-piece setting at its default (one copy, no seams,
    /// marks or grain): how a mesh or STEP file, or a part's whole surface, becomes a piece.
    pub(crate) fn of_surface(name: String, surface: SurfaceDef, file: String) -> PieceDef {
        PieceDef {
            name,
            quantity: 1,
            pairs: None,
            mirrored: 0,
            pair_labels: None,
            surface,
            seams: Vec::new(),
            marks: Vec::new(),
            grain: None,
            seam_allowance_mm: None,
            material: None,
            material_properties: None,
            darts: None,
            no_cut: Vec::new(),
            seam_hidden: None,
            seam_hidden_regions: Vec::new(),
            dart_press: None,
            edges: Vec::new(),
            index: 0,
            file,
            mesh_map: Axes::IDENTITY,
            outline_edges: Vec::new(),
            size: None,
        }
    }

    /// Turns `pairs = N` into N as drawn and N mirrored (after the checks).
    pub(crate) fn resolve_pairs(&mut self) {
        if let Some(n) = self.pairs {
            self.quantity = n;
            self.mirrored = n;
        }
    }

    /// The labels of a pair's two sides (as drawn, mirrored).
    pub fn pair_labels(&self) -> [String; 2] {
        self.pair_labels
            .clone()
            .unwrap_or_else(|| ["L".to_string(), "R".to_string()])
    }
}

/// Whether darts are cut into a piece.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DartsDef {
    /// Where the piece cannot meet its limits otherwise.
    Auto,
    /// Never.
    Off,
}

pub(crate) fn no_map() -> Axes {
    Axes::IDENTITY
}

/// Which way a dart's intake is pressed when the dart is sewn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DartPress {
    /// Toward the piece's centre line: the line through its middle along its grain (without a
    /// grain, along its length).
    Centre,
    /// Toward the side of each dart that faces this point (on or near the surface).
    Toward(P3),
}

impl DartPress {
    pub(crate) fn point_mut(&mut self) -> Option<&mut P3> {
        match self {
            DartPress::Toward(p) => Some(p),
            DartPress::Centre => None,
        }
    }
}

impl<'de> Deserialize<'de> for DartPress {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Point(P3),
            Word(String),
        }
        match Raw::deserialize(d) {
            Ok(Raw::Point(p)) => Ok(DartPress::Toward(p)),
            Ok(Raw::Word(w)) if w == "centre" || w == "center" => Ok(DartPress::Centre),
            _ => Err(serde::de::Error::custom(
                "dart_press: expected \"centre\" or a point [x, y, z]",
            )),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct DesignFile {
    #[serde(default)]
    pub(crate) units: Units,
    #[serde(default, rename = "piece")]
    pub(crate) pieces: Vec<PieceDef>,
    #[serde(default, rename = "part")]
    pub(crate) parts: Vec<crate::PartDef>,
    #[serde(default, rename = "join")]
    pub(crate) joins: Vec<crate::JoinDef>,
    #[serde(default)]
    pub(crate) grading: Option<crate::GradingDef>,
}
