//! From instances to geometry: points, directions, placements, curves and surfaces, each read
//! once (cached by instance), lengths converted to mm with the unit of the representation that
//! holds them, angles to radians.
//!
//! Every reference is followed with a guard: an instance met again while it is still being read
//! is a cyclic reference, and chains deeper than [`MAX_REF_DEPTH`] are refused, so the work per
//! instance is bounded.

use std::collections::BTreeMap;
use std::sync::Arc;

use flatcut_geom::{DVec2, DVec3};
use flatcut_surface::SurfaceError;
use flatcut_surface::curve::{BSpline, Ellipse, Frame, Line, Nurbs, Polyline};
use flatcut_surface::patch::bspline::MAX_DEGREE;
use flatcut_surface::patch::{Analytic, BSplinePatch};

use crate::StepError;
use crate::attrs::{Attrs, describe, number};
use crate::file::{Instance, StepFile, Value};
use crate::geom::{Curve, Spline, Surface};
use crate::placement::Placement;

/// Longest chain of references followed from one instance (a B-rep is about 12 deep: shell,
/// face, bound, loop, oriented edge, edge, curve, placement, direction).
pub const MAX_REF_DEPTH: usize = 64;

/// Where a curve lives: in model space (3D, lengths in file units) or in a surface's parameter
/// space (2D, unscaled).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Space {
    /// 3D model space, lengths in the file's unit.
    Model,
    /// A surface's (u, v) parameter space.
    Param,
}

/// The length and plane-angle units of a representation context.
#[derive(Clone, Debug, PartialEq)]
pub struct Units {
    /// The length unit's name as the file gives it, e.g. `millimetre`, `metre`, `inch`.
    pub length: String,
    /// Millimetres per length unit.
    pub mm: f64,
    /// Radians per plane-angle unit.
    pub rad: f64,
    /// False when the file states no length unit (millimetres are then assumed).
    pub stated: bool,
}

impl Units {
    /// Millimetres and radians, as assumed when the file states nothing.
    pub fn assumed_mm() -> Self {
        Self {
            length: "millimetre".into(),
            mm: 1.0,
            rad: 1.0,
            stated: false,
        }
    }
}

/// Reads geometry from a file, with caches and the cycle guard.
pub struct Reader<'f> {
    /// The file the geometry is read from.
    pub file: &'f StepFile,
    /// Millimetres per length unit of the representation being read.
    pub mm: f64,
    /// Radians per plane-angle unit.
    pub rad: f64,
    /// Where the body being read sits (an assembly instance): applied to every point and
    /// direction of model space as it is read. Set with [`Reader::place`].
    xf: Placement,
    stack: Vec<u64>,
    curves: BTreeMap<(u64, bool), Arc<Curve>>,
    surfaces: BTreeMap<u64, Arc<Surface>>,
}

fn si_prefix(p: &str) -> Option<f64> {
    Some(match p.to_ascii_uppercase().as_str() {
        "EXA" => 1e18,
        "PETA" => 1e15,
        "TERA" => 1e12,
        "GIGA" => 1e9,
        "MEGA" => 1e6,
        "KILO" => 1e3,
        "HECTO" => 1e2,
        "DECA" => 1e1,
        "DECI" => 1e-1,
        "CENTI" => 1e-2,
        "MILLI" => 1e-3,
        "MICRO" => 1e-6,
        "NANO" => 1e-9,
        "PICO" => 1e-12,
        "FEMTO" => 1e-15,
        "ATTO" => 1e-18,
        _ => return None,
    })
}

/// What a unit measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum UnitKind {
    Length,
    Angle,
    Other,
}

impl<'f> Reader<'f> {
    /// A reader of `file` with empty caches, in mm and radians until a representation sets its
    /// units.
    pub fn new(file: &'f StepFile) -> Self {
        Self {
            file,
            mm: 1.0,
            rad: 1.0,
            xf: Placement::IDENTITY,
            stack: Vec::new(),
            curves: BTreeMap::new(),
            surfaces: BTreeMap::new(),
        }
    }

    /// Reads what follows as placed by `xf` (the geometry cache is per placement).
    pub fn place(&mut self, xf: Placement) {
        if xf != self.xf {
            self.xf = xf;
            self.curves.clear();
            self.surfaces.clear();
        }
    }

    /// Reads instance `id` (referred to by `from`) and runs `f` on it with the cycle guard.
    pub fn visit<T>(
        &mut self,
        id: u64,
        from: u64,
        f: impl FnOnce(&mut Self, &Instance<'f>) -> Result<T, StepError>,
    ) -> Result<T, StepError> {
        if self.stack.contains(&id) {
            return Err(StepError::Cycle { id, through: from });
        }
        let file = self.file;
        let inst = file.instance(id, from)?;
        if self.stack.len() >= MAX_REF_DEPTH {
            return Err(StepError::entity(
                id,
                &inst.type_name(),
                format!("references nest deeper than {MAX_REF_DEPTH}"),
            ));
        }
        self.stack.push(id);
        let r = f(self, &inst);
        self.stack.pop();
        r
    }

    /// The single part of a simple instance, or an error naming what was expected.
    pub fn expect_simple<'i>(
        inst: &'i Instance<'f>,
        want: &str,
    ) -> Result<Attrs<'i, 'f>, StepError> {
        match inst.parts.as_slice() {
            [p] if p.name.eq_ignore_ascii_case(want) => Ok(Attrs::of(inst, p)),
            _ => Err(StepError::entity(
                inst.id,
                &inst.type_name(),
                format!("expected {want}"),
            )),
        }
    }

    fn finite_positive(a: &Attrs, i: usize, what: &str, x: f64) -> Result<f64, StepError> {
        if x.is_finite() && x > 0.0 {
            Ok(x)
        } else {
            Err(a.bad(i, what, format!("must be > 0, got {x}")))
        }
    }

    /// A `CARTESIAN_POINT` with `dim` coordinates, scaled to mm in model space.
    fn coords(&mut self, id: u64, from: u64, space: Space) -> Result<DVec3, StepError> {
        self.visit(id, from, |r, inst| {
            let a = Self::expect_simple(inst, "CARTESIAN_POINT")?;
            let c = a.reals(1, "coordinates")?;
            let want = if space == Space::Model { 3 } else { 2 };
            if c.len() != want {
                return Err(a.bad(
                    1,
                    "coordinates",
                    format!("expected {want} coordinates, found {}", c.len()),
                ));
            }
            let p = DVec3::new(c[0], c[1], c.get(2).copied().unwrap_or(0.0));
            Ok(if space == Space::Model {
                r.xf.point(p * r.mm)
            } else {
                p
            })
        })
    }

    /// A point in model space (mm).
    pub fn point(&mut self, id: u64, from: u64) -> Result<DVec3, StepError> {
        self.coords(id, from, Space::Model)
    }

    /// A point of a parameter space, as (u, v).
    pub fn point2(&mut self, id: u64, from: u64) -> Result<DVec2, StepError> {
        Ok(self.coords(id, from, Space::Param)?.truncate())
    }

    /// A `DIRECTION` (2D ones get z = 0), not normalised, nonzero.
    pub fn direction(&mut self, id: u64, from: u64) -> Result<DVec3, StepError> {
        self.visit(id, from, |_, inst| {
            let a = Self::expect_simple(inst, "DIRECTION")?;
            let c = a.reals(1, "direction ratios")?;
            if !(2..=3).contains(&c.len()) {
                return Err(a.bad(1, "direction ratios", format!("{} ratios", c.len())));
            }
            let d = DVec3::new(c[0], c[1], c.get(2).copied().unwrap_or(0.0));
            if d.length_squared() == 0.0 {
                return Err(a.bad(1, "direction ratios", "all zero"));
            }
            Ok(d)
        })
    }

    /// A `VECTOR`: unit direction times magnitude (in mm in model space).
    fn vector(&mut self, id: u64, from: u64, space: Space) -> Result<DVec3, StepError> {
        self.visit(id, from, |r, inst| {
            let a = Self::expect_simple(inst, "VECTOR")?;
            let d = r.direction(a.reference(1, "orientation")?, id)?;
            let m = a.real(2, "magnitude")?;
            if m.is_nan() || m < 0.0 {
                return Err(a.bad(2, "magnitude", format!("must be >= 0, got {m}")));
            }
            Ok(if space == Space::Model {
                r.xf.vector(d.normalize() * m * r.mm)
            } else {
                d.normalize() * m
            })
        })
    }

    /// An `AXIS2_PLACEMENT_3D` or `AXIS2_PLACEMENT_2D` as a frame.
    pub fn placement(&mut self, id: u64, from: u64) -> Result<Frame, StepError> {
        self.visit(id, from, |r, inst| {
            let name = inst.type_name();
            let bad = |e: SurfaceError| StepError::entity(id, &name, e.to_string());
            if inst.is("AXIS2_PLACEMENT_3D") {
                let a = Attrs::of(inst, &inst.parts[0]);
                let o = r.point(a.reference(1, "location")?, id)?;
                let z = match a.opt_reference(2, "axis")? {
                    Some(d) => r.direction(d, id)?,
                    None => DVec3::Z,
                };
                let x = match a.opt_reference(3, "ref_direction")? {
                    Some(d) => r.direction(d, id)?,
                    // ISO 10303-42 first_proj_axis: (1, 0, 0), or (0, 1, 0) along the x axis.
                    None if z.normalize().dot(DVec3::X).abs() > 1.0 - 1e-12 => DVec3::Y,
                    None => DVec3::X,
                };
                Frame::new(o, r.xf.vector(z), Some(r.xf.vector(x))).map_err(bad)
            } else if inst.is("AXIS2_PLACEMENT_2D") {
                let a = Attrs::of(inst, &inst.parts[0]);
                let o = r.point2(a.reference(1, "location")?, id)?.extend(0.0);
                let x = match a.opt_reference(2, "ref_direction")? {
                    Some(d) => r.direction(d, id)?,
                    None => DVec3::X,
                };
                Frame::new(o, DVec3::Z, Some(x)).map_err(bad)
            } else {
                Err(StepError::entity(
                    id,
                    &name,
                    "expected AXIS2_PLACEMENT_3D or AXIS2_PLACEMENT_2D",
                ))
            }
        })
    }

    /// A curve in model space (mm) or in a parameter space.
    pub fn curve(&mut self, id: u64, from: u64, space: Space) -> Result<Arc<Curve>, StepError> {
        let key = (id, space == Space::Model);
        if let Some(c) = self.curves.get(&key) {
            return Ok(c.clone());
        }
        let c = Arc::new(self.visit(id, from, |r, inst| r.read_curve(inst, space))?);
        self.curves.insert(key, c.clone());
        Ok(c)
    }

    fn read_curve(&mut self, inst: &Instance<'f>, space: Space) -> Result<Curve, StepError> {
        let id = inst.id;
        let name = inst.type_name();
        let bad = |e: SurfaceError| StepError::entity(id, &name, e.to_string());
        if inst.parts.len() > 1 {
            return self.bspline_curve(inst, space);
        }
        let a = Attrs::of(inst, &inst.parts[0]);
        let scale = if space == Space::Model { self.mm } else { 1.0 };
        match a.name.to_ascii_uppercase().as_str() {
            "LINE" => {
                let p = self.coords(a.reference(1, "pnt")?, id, space)?;
                let v = self.vector(a.reference(2, "dir")?, id, space)?;
                Ok(Curve::Line(Line::new(p, v).map_err(bad)?))
            }
            "CIRCLE" => {
                let f = self.placement(a.reference(1, "position")?, id)?;
                let r = Self::finite_positive(&a, 2, "radius", a.real(2, "radius")? * scale)?;
                Ok(Curve::Conic(Ellipse::circle(f, r).map_err(bad)?))
            }
            "ELLIPSE" => {
                let f = self.placement(a.reference(1, "position")?, id)?;
                let r1 =
                    Self::finite_positive(&a, 2, "semi_axis_1", a.real(2, "semi_axis_1")? * scale)?;
                let r2 =
                    Self::finite_positive(&a, 3, "semi_axis_2", a.real(3, "semi_axis_2")? * scale)?;
                Ok(Curve::Conic(Ellipse::new(f, r1, r2).map_err(bad)?))
            }
            "B_SPLINE_CURVE_WITH_KNOTS"
            | "UNIFORM_CURVE"
            | "QUASI_UNIFORM_CURVE"
            | "BEZIER_CURVE" => self.bspline_curve(inst, space),
            "POLYLINE" => {
                let pts = a
                    .refs(1, "points")?
                    .into_iter()
                    .map(|p| self.coords(p, id, space))
                    .collect::<Result<Vec<_>, _>>()?;
                Ok(Curve::Polyline(Polyline::new(pts).map_err(bad)?))
            }
            "TRIMMED_CURVE" => {
                // The edge's vertices bound the part used; the basis curve carries the geometry.
                let basis = a.reference(1, "basis_curve")?;
                Ok((*self.curve(basis, id, space)?).clone())
            }
            "SURFACE_CURVE" | "SEAM_CURVE" | "INTERSECTION_CURVE" if space == Space::Model => {
                let c = a.reference(1, "curve_3d")?;
                Ok((*self.curve(c, id, space)?).clone())
            }
            "PCURVE" if space == Space::Model => {
                let (surface, uv) = self.pcurve(id, inst)?;
                Ok(Curve::OnSurface { uv, surface })
            }
            _ => Err(StepError::entity(id, &name, "not supported")),
        }
    }

    /// The basis surface and the (u, v) curve of a `PCURVE`.
    pub fn pcurve(
        &mut self,
        id: u64,
        inst: &Instance<'f>,
    ) -> Result<(Arc<Surface>, Arc<Curve>), StepError> {
        let a = Self::expect_simple(inst, "PCURVE")?;
        let surface = self.surface(a.reference(1, "basis_surface")?, id)?;
        let rep = a.reference(2, "reference_to_curve")?;
        let uv = self.visit(rep, id, |r, rinst| {
            let ra = Self::expect_simple(rinst, "DEFINITIONAL_REPRESENTATION")?;
            let items = ra.refs(1, "items")?;
            let first = *items
                .first()
                .ok_or_else(|| ra.bad(1, "items", "the representation has no curve"))?;
            r.curve(first, rep, Space::Param)
        })?;
        Ok((surface, uv))
    }

    /// Knot vector from STEP's distinct knots and multiplicities, checked before expanding:
    /// knots increasing, multiplicities ≥ 1 and summing to `count + degree + 1`.
    fn knot_vector(
        a: &Attrs,
        (mi, ki): (usize, usize),
        degree: usize,
        count: usize,
    ) -> Result<Vec<f64>, StepError> {
        let mults = a.ints(mi, "knot_multiplicities")?;
        let knots = a.reals(ki, "knots")?;
        if mults.len() != knots.len() {
            return Err(a.bad(
                ki,
                "knots",
                format!("{} knots but {} multiplicities", knots.len(), mults.len()),
            ));
        }
        if let Some(k) = knots
            .windows(2)
            .position(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
        {
            return Err(a.bad(
                ki,
                "knots",
                format!(
                    "knots must increase: item {} is {} after {}",
                    k + 2,
                    knots[k + 1],
                    knots[k]
                ),
            ));
        }
        let want = count + degree + 1;
        let mut total: i64 = 0;
        for (k, &m) in mults.iter().enumerate() {
            if !(1..=degree as i64 + 1).contains(&m) {
                return Err(a.bad(
                    mi,
                    "knot_multiplicities",
                    format!("item {} is {m}; must lie in 1..={}", k + 1, degree + 1),
                ));
            }
            total += m;
        }
        if total != want as i64 {
            return Err(a.bad(
                mi,
                "knot_multiplicities",
                format!(
                    "they sum to {total}, but {count} control points of degree {degree} need {want}"
                ),
            ));
        }
        let mut out = Vec::with_capacity(want);
        for (&k, &m) in knots.iter().zip(&mults) {
            out.extend(std::iter::repeat_n(k, m as usize));
        }
        Ok(out)
    }

    fn degree(a: &Attrs, i: usize, what: &str) -> Result<usize, StepError> {
        let d = a.int(i, what)?;
        if (1..=MAX_DEGREE as i64).contains(&d) {
            Ok(d as usize)
        } else {
            Err(a.bad(i, what, format!("{d} is outside 1..={MAX_DEGREE}")))
        }
    }

    fn weights(a: &Attrs, i: usize, values: &[f64]) -> Result<(), StepError> {
        if let Some(k) = values.iter().position(|w| !(w.is_finite() && *w > 0.0)) {
            return Err(a.bad(
                i,
                "weights_data",
                format!("weight {} is {}: weights must be > 0", k + 1, values[k]),
            ));
        }
        Ok(())
    }

    /// A B-spline curve, simple (`B_SPLINE_CURVE_WITH_KNOTS`) or complex (rational).
    fn bspline_curve(&mut self, inst: &Instance<'f>, space: Space) -> Result<Curve, StepError> {
        let id = inst.id;
        let name = inst.type_name();
        let unsupported = || StepError::entity(id, &name, "not supported");
        let form = KnotForm::of(inst, "CURVE");
        let (curve, knots, knot_idx, rational) = if inst.parts.len() == 1 {
            let a = Attrs::of(inst, &inst.parts[0]);
            a.expect_len(if form.is_some() { 6 } else { 9 })?;
            (a, a, (6, 7), None)
        } else {
            let c = inst.part("B_SPLINE_CURVE").ok_or_else(unsupported)?;
            let k = match form {
                Some(_) => c,
                None => inst
                    .part("B_SPLINE_CURVE_WITH_KNOTS")
                    .ok_or_else(unsupported)?,
            };
            let r = inst.part("RATIONAL_B_SPLINE_CURVE");
            (
                Attrs::of(inst, c),
                Attrs::of(inst, k),
                (0, 1),
                r.map(|r| Attrs::of(inst, r)),
            )
        };
        // Simple form: name first; complex B_SPLINE_CURVE part: no name.
        let o = usize::from(inst.parts.len() == 1);
        let degree = Self::degree(&curve, o, "degree")?;
        let pts = curve
            .refs(o + 1, "control_points_list")?
            .into_iter()
            .map(|p| self.coords(p, id, space))
            .collect::<Result<Vec<_>, _>>()?;
        let kv = match form {
            Some(f) => f.knots(degree, pts.len()).ok_or_else(|| {
                StepError::entity(id, &name, "its control points do not fit its knot form")
            })?,
            None => Self::knot_vector(&knots, knot_idx, degree, pts.len())?,
        };
        let bad = |e: SurfaceError| StepError::entity(id, &name, e.to_string());
        match rational {
            None => Ok(Curve::BSpline(BSpline::new(degree, kv, pts).map_err(bad)?)),
            Some(r) => {
                let w = r.reals(0, "weights_data")?;
                if w.len() != pts.len() {
                    return Err(r.bad(
                        0,
                        "weights_data",
                        format!("{} weights for {} control points", w.len(), pts.len()),
                    ));
                }
                Self::weights(&r, 0, &w)?;
                Ok(Curve::Nurbs(Nurbs::new(degree, kv, pts, w).map_err(bad)?))
            }
        }
    }

    /// A surface (cached per instance).
    pub fn surface(&mut self, id: u64, from: u64) -> Result<Arc<Surface>, StepError> {
        if let Some(s) = self.surfaces.get(&id) {
            return Ok(s.clone());
        }
        let s = Arc::new(self.visit(id, from, |r, inst| r.read_surface(inst))?);
        self.surfaces.insert(id, s.clone());
        Ok(s)
    }

    fn read_surface(&mut self, inst: &Instance<'f>) -> Result<Surface, StepError> {
        let id = inst.id;
        let name = inst.type_name();
        if inst.parts.len() > 1 {
            return self.bspline_surface(inst);
        }
        let bad = |e: SurfaceError| StepError::entity(id, &name, e.to_string());
        let a = Attrs::of(inst, &inst.parts[0]);
        let mm = self.mm;
        let an = match a.name.to_ascii_uppercase().as_str() {
            "PLANE" => Analytic::plane(self.placement(a.reference(1, "position")?, id)?),
            "CYLINDRICAL_SURFACE" => {
                let f = self.placement(a.reference(1, "position")?, id)?;
                Analytic::cylinder(f, a.real(2, "radius")? * mm).map_err(bad)?
            }
            "CONICAL_SURFACE" => {
                let f = self.placement(a.reference(1, "position")?, id)?;
                let r = a.real(2, "radius")? * mm;
                Analytic::cone(f, r, a.real(3, "semi_angle")? * self.rad).map_err(bad)?
            }
            "SPHERICAL_SURFACE" => {
                let f = self.placement(a.reference(1, "position")?, id)?;
                Analytic::sphere(f, a.real(2, "radius")? * mm).map_err(bad)?
            }
            "TOROIDAL_SURFACE" => {
                let f = self.placement(a.reference(1, "position")?, id)?;
                let (r1, r2) = (a.real(2, "major_radius")?, a.real(3, "minor_radius")?);
                Analytic::torus(f, r1 * mm, r2 * mm).map_err(bad)?
            }
            // A spindle torus (minor radius above the major, its tube crossing the axis);
            // `select_outer` names the part a face lies on (the apple or the lemon), and the
            // torus's (u, v) reaches both: each point is found on the branch that passes through
            // it (`analytic_param_of`), so the flag only has to be well formed.
            "DEGENERATE_TOROIDAL_SURFACE" => {
                let f = self.placement(a.reference(1, "position")?, id)?;
                let (r1, r2) = (a.real(2, "major_radius")?, a.real(3, "minor_radius")?);
                a.boolean(4, "select_outer")?;
                Analytic::torus(f, r1 * mm, r2 * mm).map_err(bad)?
            }
            "SURFACE_OF_LINEAR_EXTRUSION" => {
                let c = self.curve(a.reference(1, "swept_curve")?, id, Space::Model)?;
                let v = self.vector(a.reference(2, "extrusion_axis")?, id, Space::Model)?;
                Analytic::extrusion(c, v).map_err(bad)?
            }
            "SURFACE_OF_REVOLUTION" => {
                let c = self.curve(a.reference(1, "swept_curve")?, id, Space::Model)?;
                let ax = a.reference(2, "axis_position")?;
                let (p, d) = self.visit(ax, id, |r, ai| {
                    let aa = Self::expect_simple(ai, "AXIS1_PLACEMENT")?;
                    let p = r.point(aa.reference(1, "location")?, ax)?;
                    let d = match aa.opt_reference(2, "axis")? {
                        Some(d) => r.direction(d, ax)?,
                        None => DVec3::Z,
                    };
                    Ok((p, r.xf.vector(d)))
                })?;
                Analytic::revolution(c, p, d).map_err(bad)?
            }
            "B_SPLINE_SURFACE_WITH_KNOTS"
            | "UNIFORM_SURFACE"
            | "QUASI_UNIFORM_SURFACE"
            | "BEZIER_SURFACE" => return self.bspline_surface(inst),
            "RECTANGULAR_TRIMMED_SURFACE" => {
                // The face's loops bound the part used; the basis surface carries the geometry.
                return Ok((*self.surface(a.reference(1, "basis_surface")?, id)?).clone());
            }
            _ => return Err(StepError::entity(id, &name, "not supported")),
        };
        Ok(Surface::Analytic(an))
    }

    fn bspline_surface(&mut self, inst: &Instance<'f>) -> Result<Surface, StepError> {
        let id = inst.id;
        let name = inst.type_name();
        let unsupported = || StepError::entity(id, &name, "not supported");
        let form = KnotForm::of(inst, "SURFACE");
        let (surf, knots, rational) = if inst.parts.len() == 1 {
            let a = Attrs::of(inst, &inst.parts[0]);
            a.expect_len(if form.is_some() { 8 } else { 13 })?;
            (a, a, None)
        } else {
            let s = inst.part("B_SPLINE_SURFACE").ok_or_else(unsupported)?;
            let k = match form {
                Some(_) => s,
                None => inst
                    .part("B_SPLINE_SURFACE_WITH_KNOTS")
                    .ok_or_else(unsupported)?,
            };
            (
                Attrs::of(inst, s),
                Attrs::of(inst, k),
                inst.part("RATIONAL_B_SPLINE_SURFACE")
                    .map(|r| Attrs::of(inst, r)),
            )
        };
        let simple = inst.parts.len() == 1;
        let o = usize::from(simple);
        let du = Self::degree(&surf, o, "u_degree")?;
        let dv = Self::degree(&surf, o + 1, "v_degree")?;
        let rows = surf.list(o + 2, "control_points_list")?;
        let mut pts = Vec::new();
        let mut nv = None;
        for (i, row) in rows.iter().enumerate() {
            let Value::List(row) = row else {
                return Err(surf.bad(
                    o + 2,
                    "control_points_list",
                    format!("row {}: expected a list, found {}", i + 1, describe(row)),
                ));
            };
            if *nv.get_or_insert(row.len()) != row.len() {
                return Err(surf.bad(o + 2, "control_points_list", "rows of different lengths"));
            }
            for v in row {
                let Value::Ref(p) = v else {
                    return Err(surf.bad(
                        o + 2,
                        "control_points_list",
                        format!("expected references, found {}", describe(v)),
                    ));
                };
                pts.push(self.point(*p, id)?);
            }
        }
        let (nu, nv) = (rows.len(), nv.unwrap_or(0));
        let (mu, mv, ku, kv) = if simple { (8, 9, 10, 11) } else { (0, 1, 2, 3) };
        let (knots_u, knots_v) = match form {
            Some(f) => {
                let misfit =
                    || StepError::entity(id, &name, "its control points do not fit its knot form");
                (
                    f.knots(du, nu).ok_or_else(misfit)?,
                    f.knots(dv, nv).ok_or_else(misfit)?,
                )
            }
            None => (
                Self::knot_vector(&knots, (mu, ku), du, nu)?,
                Self::knot_vector(&knots, (mv, kv), dv, nv)?,
            ),
        };
        let weights = match rational {
            None => None,
            Some(r) => {
                let rows = r.list(0, "weights_data")?;
                let mut w = Vec::with_capacity(nu * nv);
                for row in rows {
                    let Value::List(row) = row else {
                        return Err(r.bad(0, "weights_data", "expected a list of lists"));
                    };
                    for x in row {
                        w.push(number(x).ok_or_else(|| {
                            r.bad(
                                0,
                                "weights_data",
                                format!("expected numbers, found {}", describe(x)),
                            )
                        })?);
                    }
                }
                if w.len() != nu * nv {
                    return Err(r.bad(
                        0,
                        "weights_data",
                        format!("{} weights for {} control points", w.len(), nu * nv),
                    ));
                }
                Self::weights(&r, 0, &w)?;
                Some(w)
            }
        };
        let bad = |e: SurfaceError| StepError::entity(id, &name, e.to_string());
        Ok(Surface::Spline(Spline::new(
            BSplinePatch::new(du, dv, knots_u, knots_v, nu, nv, pts, weights).map_err(bad)?,
        )))
    }

    /// The length and plane-angle units of a representation context (`#id`), if it states them.
    pub fn context_units(&mut self, id: u64, from: u64) -> Result<Option<Units>, StepError> {
        self.visit(id, from, |r, inst| {
            let Some(p) = inst.part("GLOBAL_UNIT_ASSIGNED_CONTEXT") else {
                return Ok(None);
            };
            let a = Attrs::of(inst, p);
            let mut units = Units::assumed_mm();
            for u in a.refs(0, "units")? {
                match r.unit(u, id)? {
                    (UnitKind::Length, f, n) => {
                        units.mm = f;
                        units.length = n;
                        units.stated = true;
                    }
                    (UnitKind::Angle, f, _) => units.rad = f,
                    (UnitKind::Other, ..) => {}
                }
            }
            Ok(units.stated.then_some(units))
        })
    }

    /// A unit: what it measures, its size (mm or radians) and its name.
    fn unit(&mut self, id: u64, from: u64) -> Result<(UnitKind, f64, String), StepError> {
        self.visit(id, from, |r, inst| {
            let kind = if inst.part("LENGTH_UNIT").is_some() {
                UnitKind::Length
            } else if inst.part("PLANE_ANGLE_UNIT").is_some() {
                UnitKind::Angle
            } else {
                UnitKind::Other
            };
            let name = inst.type_name();
            if let Some(si) = inst.part("SI_UNIT") {
                let a = Attrs::of(inst, si);
                let prefix = match a.get(0, "prefix")? {
                    Value::Enum(p) => Some(*p),
                    _ => None,
                };
                let base = a.enumeration(1, "name")?.to_ascii_uppercase();
                let pf = match prefix {
                    Some(p) => si_prefix(p)
                        .ok_or_else(|| a.bad(0, "prefix", format!("unknown SI prefix .{p}.")))?,
                    None => 1.0,
                };
                let (kind, size) = match base.as_str() {
                    "METRE" => (UnitKind::Length, pf * 1000.0),
                    "RADIAN" => (UnitKind::Angle, pf),
                    _ => (kind, pf),
                };
                let label = format!("{}{}", prefix.unwrap_or(""), base).to_ascii_lowercase();
                return Ok((kind, size, label));
            }
            if let Some(cb) = inst.part("CONVERSION_BASED_UNIT") {
                let a = Attrs::of(inst, cb);
                let label = match a.get(0, "name")? {
                    Value::Str(s) => s.to_ascii_lowercase(),
                    _ => String::new(),
                };
                let conv = a.reference(1, "conversion_factor")?;
                let size = r.visit(conv, id, |r, ci| {
                    // (…_MEASURE_WITH_UNIT(value, unit)) or MEASURE_WITH_UNIT(value, unit).
                    let p = ci
                        .parts
                        .iter()
                        .find(|p| p.params.len() == 2)
                        .ok_or_else(|| {
                            StepError::entity(conv, &ci.type_name(), "expected a measure with unit")
                        })?;
                    let ca = Attrs::of(ci, p);
                    let v = ca.real(0, "value_component")?;
                    let (_, f, _) = r.unit(ca.reference(1, "unit_component")?, conv)?;
                    Ok(v * f)
                })?;
                if !(size.is_finite() && size > 0.0) {
                    return Err(StepError::entity(
                        id,
                        &name,
                        format!("the unit's size is {size}"),
                    ));
                }
                return Ok((kind, size, label));
            }
            Ok((UnitKind::Other, 1.0, name))
        })
    }
}

/// The knot vectors ISO 10303-42 implies for B-splines written without knots: uniform,
/// quasi-uniform (clamped, uniform inside) and piecewise Bézier.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum KnotForm {
    Uniform,
    QuasiUniform,
    Bezier,
}

impl KnotForm {
    /// The form an instance names (`UNIFORM_CURVE`, `QUASI_UNIFORM_SURFACE`, …), for `kind`
    /// `"CURVE"` or `"SURFACE"`; `None` when it gives its knots.
    fn of(inst: &Instance<'_>, kind: &str) -> Option<Self> {
        inst.parts.iter().find_map(|p| {
            let n = p.name.to_ascii_uppercase();
            let base = n.strip_suffix(kind)?;
            match base {
                "UNIFORM_" => Some(Self::Uniform),
                "QUASI_UNIFORM_" => Some(Self::QuasiUniform),
                "BEZIER_" => Some(Self::Bezier),
                _ => None,
            }
        })
    }

    /// The knot vector of `count` control points of `degree` (None when they do not fit).
    fn knots(self, degree: usize, count: usize) -> Option<Vec<f64>> {
        if degree == 0 || count <= degree {
            return None;
        }
        let ends = |segments: usize, inner: usize| {
            let mut k = vec![0.0; degree + 1];
            for s in 1..segments {
                k.extend(std::iter::repeat_n(s as f64, inner));
            }
            k.extend(std::iter::repeat_n(segments as f64, degree + 1));
            k
        };
        let out = match self {
            Self::Uniform => (0..count + degree + 1)
                .map(|i| i as f64 - degree as f64)
                .collect(),
            Self::QuasiUniform => ends(count - degree, 1),
            Self::Bezier => {
                if !(count - 1).is_multiple_of(degree) {
                    return None;
                }
                ends((count - 1) / degree, degree)
            }
        };
        Some(out)
    }
}

#[cfg(test)]
mod knot_form_tests {
    use super::KnotForm;

    #[test]
    fn implied_knot_vectors() {
        // 5 cubic control points: quasi-uniform 0 0 0 0 1 2 2 2 2; uniform -3 … 5.
        assert_eq!(
            KnotForm::QuasiUniform.knots(3, 5),
            Some(vec![0.0, 0.0, 0.0, 0.0, 1.0, 2.0, 2.0, 2.0, 2.0])
        );
        assert_eq!(
            KnotForm::Uniform.knots(3, 5),
            Some((-3..=5).map(f64::from).collect())
        );
        // Two cubic Bézier segments share their middle point: 7 points.
        assert_eq!(
            KnotForm::Bezier.knots(3, 7),
            Some(vec![0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0, 2.0])
        );
        assert_eq!(KnotForm::Bezier.knots(3, 6), None);
        assert_eq!(KnotForm::QuasiUniform.knots(3, 3), None);
    }
}
