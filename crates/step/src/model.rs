//! The boundary representation a STEP file describes: shells of faces, each face a surface
//! bounded by loops of oriented edges, each edge a curve between two vertices. Faces and edges
//! are numbered from 0 in the order the shells list them; that number is how users select faces.
//!
//! Shells come from `MANIFOLD_SOLID_BREP` and `BREP_WITH_VOIDS` (closed), and
//! `SHELL_BASED_SURFACE_MODEL` (open or closed), and the `CURVE_BOUNDED_SURFACE`s of a
//! `GEOMETRIC_SET` (a face each, `bounded`); a file with none of these but loose
//! `CLOSED_SHELL`/`OPEN_SHELL`s uses those. Lengths are converted to mm with the unit of the
//! representation that holds the shell.
//!
//! A face or edge that cannot be used (an unsupported surface, a bad knot vector) keeps its
//! number and its error, so the rest of the model still loads and other faces can be selected;
//! asking for the bad one reports its error.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use flatcut_geom::{Aabb3, DVec2, DVec3};
use flatcut_surface::ParamCurve;
use flatcut_surface::curve::nearest_from_samples;

use crate::StepError;
use crate::attrs::Attrs;
use crate::edge_use::EdgeUse;
use crate::file::{Instance, StepFile, Value};
use crate::geom::{Curve, Surface};
use crate::heal::{HealOptions, Repair};
use crate::placement::Placement;
use crate::reader::{Reader, Space, Units};

mod bounded;

/// A curve whose length over an edge is below this (mm) makes a degenerate edge when the edge
/// starts and ends at one vertex (an edge at a pole).
const DEGENERATE_MM: f64 = 1e-7;
/// Points compared to decide that a closed curve has zero length.
const DEGENERATE_SAMPLES: usize = 8;
/// Accuracy of locating a vertex on its curve (mm).
const LOCATE_ACCURACY: f64 = 1e-10;
/// Samples per curve span when locating a vertex on a spline or polyline.
const LOCATE_SAMPLES_PER_SPAN: usize = 8;

/// A shell: a connected set of faces (closed: bounds a solid), in one instance of its body.
#[derive(Clone, Debug, PartialEq)]
pub struct Shell {
    /// The shell's instance number (`#id`).
    pub entity: u64,
    /// True for a `CLOSED_SHELL` (it bounds a solid).
    pub closed: bool,
    /// The shell's faces (indices into [`Model::faces`]).
    pub faces: Vec<usize>,
    /// The body instance (index into [`Model::instances`]).
    pub instance: usize,
}

/// One placement of a body (a solid or shell-based surface model) in the world: an assembly
/// places a body as often as it uses it.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyInstance {
    /// The body's instance number (`MANIFOLD_SOLID_BREP`, `SHELL_BASED_SURFACE_MODEL`, …).
    pub body: u64,
    /// The body's name in the file.
    pub name: String,
    /// Which of the body's instances (0 for the first).
    pub copy: usize,
    /// Where the body stands in the world.
    pub placement: Placement,
}

/// A vertex: its position in mm.
#[derive(Clone, Debug, PartialEq)]
pub struct Vertex {
    /// The vertex's instance number (`#id`).
    pub entity: u64,
    /// Its position in the world (mm).
    pub point: DVec3,
}

/// A loop bounding a face (already oriented by the bound's orientation flag).
#[derive(Clone, Debug, PartialEq)]
pub struct Bound {
    /// The loop's instance number (`#id`).
    pub entity: u64,
    /// Declared as the outer bound (`FACE_OUTER_BOUND`).
    pub outer: bool,
    /// The edges in loop order.
    pub uses: Vec<EdgeUse>,
    /// A `VERTEX_LOOP` (a degenerate bound at a single point, e.g. a cone's apex).
    pub vertex: Option<usize>,
}

/// What a face is made of.
#[derive(Clone, Debug)]
pub struct FaceGeometry {
    /// The instance number of the surface.
    pub surface_entity: u64,
    /// The surface (in mm), shared with the faces that use it.
    pub surface: Arc<Surface>,
    /// The face normal is the surface normal `S_u × S_v` (else its opposite).
    pub same_sense: bool,
    /// The face's loops: the outer one and its holes.
    pub bounds: Vec<Bound>,
}

impl FaceGeometry {
    /// The face the other way round (in a shell used reversed): its normal and its loops
    /// reversed, so it bounds the same region.
    pub fn reversed(mut self) -> Self {
        self.same_sense = !self.same_sense;
        for b in &mut self.bounds {
            b.uses.reverse();
            for u in &mut b.uses {
                u.forward = !u.forward;
            }
        }
        self
    }
}

/// A face of the model.
#[derive(Clone, Debug)]
pub struct Face {
    /// The face's instance number (`#id`).
    pub entity: u64,
    /// The shell it belongs to (index into [`Model::shells`]).
    pub shell: usize,
    /// The face's geometry, or why it cannot be used.
    pub geometry: Result<FaceGeometry, StepError>,
    /// What healing changed in the face's topology (loops reversed, vertices merged).
    pub repairs: Vec<Repair>,
}

/// A curve in a surface's parameter space that the file gives for an edge (a `PCURVE`).
#[derive(Clone, Debug)]
pub struct Pcurve {
    /// The instance number of the surface the curve lies on.
    pub surface_entity: u64,
    /// The curve in the surface's (u, v) (its x, y).
    pub curve: Arc<Curve>,
}

/// What an edge is made of: the part of `curve` from parameter `t0` (at `start`) to `t1` (at
/// `end`); `t1 < t0` when the edge runs against the curve.
#[derive(Clone, Debug)]
pub struct EdgeGeometry {
    /// The 3D curve (mm).
    pub curve: Arc<Curve>,
    /// The start vertex (index into [`Model::vertices`]).
    pub start: usize,
    /// The end vertex (index into [`Model::vertices`]).
    pub end: usize,
    /// The curve parameter at `start`.
    pub t0: f64,
    /// The curve parameter at `end`.
    pub t1: f64,
    /// The edge's curves in the parameter spaces of its faces' surfaces.
    pub pcurves: Vec<Pcurve>,
    /// The edge has no length: one vertex, a curve of zero extent (an edge at a pole).
    pub degenerate: bool,
    /// How far its vertices lie from the curve (mm).
    pub off_curve_mm: f64,
}

/// An edge of the model and the faces whose loops use it (a face twice for a seam).
#[derive(Clone, Debug)]
pub struct Edge {
    /// The edge's instance number (`#id`).
    pub entity: u64,
    /// The edge's geometry, or why it cannot be used.
    pub geometry: Result<EdgeGeometry, StepError>,
    /// The faces whose loops use the edge (indices into [`Model::faces`]).
    pub faces: Vec<usize>,
    /// What healing changed in the edge.
    pub repairs: Vec<Repair>,
    /// The edge this one was sewn into (it then bounds no face of its own; see `sew.rs`).
    pub sewn_into: Option<usize>,
}

/// A STEP model: shells, faces, edges and vertices in mm.
#[derive(Clone, Debug)]
pub struct Model {
    /// The schemas the file names (`CONFIG_CONTROL_DESIGN` = AP203, `AUTOMOTIVE_DESIGN` = AP214,
    /// `AP242_MANAGED_MODEL_BASED_3D_ENGINEERING…` = AP242).
    pub schemas: Vec<String>,
    /// The length unit the file states (of the first shell's representation).
    pub units: Units,
    /// The shells, in file order per body instance.
    pub shells: Vec<Shell>,
    /// The faces of all shells.
    pub faces: Vec<Face>,
    /// The edges the faces' loops use.
    pub edges: Vec<Edge>,
    /// The vertices the edges end at.
    pub vertices: Vec<Vertex>,
    /// The placed bodies, in order (one per body for a file that is no assembly).
    pub instances: Vec<BodyInstance>,
    /// The diagonal of the bounding box of the vertices and of points along the edges (mm): a
    /// full torus or sphere has one vertex, its size is in its edges.
    pub size_mm: f64,
    /// The largest defect healed (mm).
    pub heal_mm: f64,
}

/// Builds the model while walking the topology (entities are keyed by instance number and body
/// instance: an assembly's second copy of a body gets faces, edges and vertices of its own).
struct Builder<'f> {
    r: Reader<'f>,
    instance: usize,
    faces: Vec<Face>,
    edges: Vec<Edge>,
    edge_of: BTreeMap<(u64, usize), usize>,
    vertices: Vec<Vertex>,
    vertex_of: BTreeMap<(u64, usize), Result<usize, StepError>>,
}

impl Model {
    /// Reads a `.step`/`.stp` file, healing with the default limit.
    pub fn read(path: &Path) -> Result<Model, StepError> {
        Self::read_with(path, &HealOptions::default())
    }

    /// Reads a `.step`/`.stp` file, healing within `heal`.
    pub fn read_with(path: &Path, heal: &HealOptions) -> Result<Model, StepError> {
        Self::from_file_with(&StepFile::read(path)?, heal)
    }

    /// Builds the model of an indexed file, healing with the default limit.
    pub fn from_file(file: &StepFile) -> Result<Model, StepError> {
        Self::from_file_with(file, &HealOptions::default())
    }

    /// Builds the model of an indexed file, healing within `heal`.
    pub fn from_file_with(file: &StepFile, heal: &HealOptions) -> Result<Model, StepError> {
        let mut b = Builder {
            r: Reader::new(file),
            instance: 0,
            faces: Vec::new(),
            edges: Vec::new(),
            edge_of: BTreeMap::new(),
            vertices: Vec::new(),
            vertex_of: BTreeMap::new(),
        };
        let tops = top_level_shells(file, &mut b.r)?;
        if tops.is_empty() {
            return Err(StepError::NoShells);
        }
        loose_surfaces(file, &mut b.r)?;
        let contexts = representation_contexts(file, &mut b.r)?;
        let fallback = unique_units(file, &mut b.r)?;
        let bodies: Vec<u64> = tops.iter().map(|t| t.0).collect();
        let placements = crate::assembly::placements(file, &mut b.r, &bodies)?;
        let mut shells = Vec::new();
        let mut instances = Vec::new();
        let mut first_units = None;
        let mut seen_faces = BTreeMap::new();
        for (item, shell_ids) in tops {
            let units = match contexts.get(&item) {
                Some(&ctx) => b.r.context_units(ctx, item)?,
                None => None,
            }
            .or_else(|| fallback.clone())
            .unwrap_or_else(Units::assumed_mm);
            first_units.get_or_insert(units.clone());
            let name = crate::assembly::body_name(&mut b.r, item);
            let places = placements
                .get(&item)
                .cloned()
                .unwrap_or_else(|| vec![Placement::IDENTITY]);
            for (copy, placement) in places.into_iter().enumerate() {
                b.instance = instances.len();
                instances.push(BodyInstance {
                    body: item,
                    name: name.clone(),
                    copy,
                    placement,
                });
                b.r.mm = units.mm;
                b.r.rad = units.rad;
                b.r.place(placement);
                for &(sid, closed) in &shell_ids {
                    let index = shells.len();
                    let faces = b.shell(sid, item, index, &mut seen_faces)?;
                    shells.push(Shell {
                        entity: sid,
                        closed,
                        faces,
                        instance: b.instance,
                    });
                }
            }
        }
        let size_mm = extent(&b.vertices, &b.edges);
        let mut model = Model {
            schemas: file.schemas.clone(),
            units: first_units.unwrap_or_else(Units::assumed_mm),
            shells,
            faces: b.faces,
            edges: b.edges,
            vertices: b.vertices,
            instances,
            size_mm,
            heal_mm: heal.limit_for(size_mm),
        };
        model.heal();
        Ok(model)
    }

    /// The geometry of face `index`, or its error.
    pub fn face(&self, index: usize) -> Result<&FaceGeometry, StepError> {
        let f = self.faces.get(index).ok_or(StepError::NoSuchFace {
            index,
            count: self.faces.len(),
        })?;
        f.geometry.as_ref().map_err(Clone::clone)
    }

    /// The bounding box of the vertices (mm).
    pub fn vertex_bbox(&self) -> Aabb3 {
        Aabb3::from_points(self.vertices.iter().map(|v| v.point))
    }
}

/// Refuses a file whose shapes hold surfaces outside any shell that flatcut cannot read as
/// faces (a `GEOMETRIC_SET` of trimmed or untrimmed surfaces beside the solids; its
/// `CURVE_BOUNDED_SURFACE`s are read): the model would come in without them, with less area
/// than the file has.
fn loose_surfaces(file: &StepFile, r: &mut Reader) -> Result<(), StepError> {
    for set in file.ids_of_type("GEOMETRIC_SET") {
        let items = r.visit(set, set, |_, inst| {
            let a = Attrs::of(inst, &inst.parts[0]);
            a.refs(1, "elements")
        })?;
        for item in items {
            let Some(t) = file.type_of(item) else {
                continue;
            };
            let t = t.to_ascii_uppercase();
            // Read as a face of its own (see `bounded`).
            if t == "CURVE_BOUNDED_SURFACE" {
                continue;
            }
            if t.ends_with("_SURFACE") || t.ends_with("_FACE") {
                return Err(StepError::entity(
                    set,
                    "GEOMETRIC_SET",
                    format!(
                        "holds the surface #{item} ({t}) outside any shell: flatcut reads the faces of shells and curve-bounded surfaces only, and the model would come in without it"
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// The top-level shape items and their shells `(shell, closed)`, in item order.
fn top_level_shells(
    file: &StepFile,
    r: &mut Reader,
) -> Result<Vec<(u64, Vec<(u64, bool)>)>, StepError> {
    let mut items: Vec<u64> = Vec::new();
    for t in [
        "MANIFOLD_SOLID_BREP",
        "BREP_WITH_VOIDS",
        "SHELL_BASED_SURFACE_MODEL",
    ] {
        items.extend(file.ids_of_type(t));
    }
    // A geometric set's curve-bounded surfaces: each a face of an open shell of its own.
    for set in file.ids_of_type("GEOMETRIC_SET") {
        let elements = r.visit(set, set, |_, inst| {
            Attrs::of(inst, &inst.parts[0]).refs(1, "elements")
        })?;
        if elements.iter().any(|&e| is_bounded_surface(file, e)) {
            items.push(set);
        }
    }
    items.sort_unstable();
    let mut out = Vec::new();
    for item in items {
        let shells = r.visit(item, item, |r, inst| {
            let a = Attrs::of(inst, &inst.parts[0]);
            let kind = a.name.to_ascii_uppercase();
            let mut shells = Vec::new();
            match kind.as_str() {
                "GEOMETRIC_SET" => {
                    for e in a.refs(1, "elements")? {
                        if is_bounded_surface(r.file, e) {
                            shells.push((e, false));
                        }
                    }
                }
                "MANIFOLD_SOLID_BREP" => shells.push((a.reference(1, "outer")?, true)),
                "BREP_WITH_VOIDS" => {
                    shells.push((a.reference(1, "outer")?, true));
                    for v in a.refs(2, "voids")? {
                        shells.push((v, true));
                    }
                }
                _ => {
                    for s in a.refs(1, "sbsm_boundary")? {
                        let closed = r
                            .file
                            .type_of(s)
                            .is_some_and(|t| t.eq_ignore_ascii_case("CLOSED_SHELL"));
                        shells.push((s, closed));
                    }
                }
            }
            Ok(shells)
        })?;
        out.push((item, shells));
    }
    if out.is_empty() {
        for (t, closed) in [("CLOSED_SHELL", true), ("OPEN_SHELL", false)] {
            for s in file.ids_of_type(t) {
                out.push((s, vec![(s, closed)]));
            }
        }
        out.sort_by_key(|x| x.0);
    }
    Ok(out)
}

/// Whether instance `id` is a `CURVE_BOUNDED_SURFACE` (read as a face of its own).
fn is_bounded_surface(file: &StepFile, id: u64) -> bool {
    file.type_of(id)
        .is_some_and(|t| t.eq_ignore_ascii_case("CURVE_BOUNDED_SURFACE"))
}

/// For each item of a shape representation, the representation's context.
fn representation_contexts(
    file: &StepFile,
    r: &mut Reader,
) -> Result<BTreeMap<u64, u64>, StepError> {
    let mut out = BTreeMap::new();
    let reps: Vec<u64> = [
        "ADVANCED_BREP_SHAPE_REPRESENTATION",
        "MANIFOLD_SURFACE_SHAPE_REPRESENTATION",
        "SHAPE_REPRESENTATION",
        "FACETED_BREP_SHAPE_REPRESENTATION",
        "GEOMETRICALLY_BOUNDED_SURFACE_SHAPE_REPRESENTATION",
    ]
    .iter()
    .flat_map(|t| file.ids_of_type(t).collect::<Vec<_>>())
    .collect();
    for rep in reps {
        let pairs = r.visit(rep, rep, |_, inst| {
            let a = Attrs::of(inst, &inst.parts[0]);
            let items = a.refs(1, "items")?;
            let ctx = a.reference(2, "context_of_items")?;
            Ok(items.into_iter().map(|i| (i, ctx)).collect::<Vec<_>>())
        })?;
        for (i, c) in pairs {
            out.entry(i).or_insert(c);
        }
    }
    Ok(out)
}

/// The units of the file's only unit-bearing context, when there is exactly one distinct set.
fn unique_units(file: &StepFile, r: &mut Reader) -> Result<Option<Units>, StepError> {
    let mut found: Option<Units> = None;
    for id in file.complex_ids().collect::<Vec<_>>() {
        let is_ctx = r.visit(id, id, |_, inst| {
            Ok(inst.part("GLOBAL_UNIT_ASSIGNED_CONTEXT").is_some())
        })?;
        if !is_ctx {
            continue;
        }
        if let Some(u) = r.context_units(id, id)? {
            match &found {
                None => found = Some(u),
                Some(f) if *f == u => {}
                Some(_) => return Ok(None),
            }
        }
    }
    Ok(found)
}

/// Where on `curve` the edge from `p0` to `p1` lies: `(t0, t1)`, whether it is degenerate (one
/// vertex, no length) and how far its vertices lie from the curve (mm).
fn edge_range(
    curve: &Curve,
    p0: DVec3,
    p1: DVec3,
    closed: bool,
    same_sense: bool,
) -> Result<(f64, f64, bool, f64), String> {
    use std::f64::consts::TAU;
    let (t0, t1) = match curve {
        Curve::Line(l) => (l.param_of(p0), l.param_of(p1)),
        Curve::Conic(e) => {
            let a0 = e.param_of(p0);
            let a1 = e.param_of(p1);
            let d = if same_sense { a1 - a0 } else { a0 - a1 };
            let mut d = d.rem_euclid(TAU);
            if closed || d == 0.0 {
                d = TAU;
            }
            (a0, if same_sense { a0 + d } else { a0 - d })
        }
        _ => {
            let (a, b) = curve.domain();
            let ends_meet = curve.eval(a).distance(curve.eval(b)) <= 1e-4;
            if closed {
                if !ends_meet {
                    // One vertex on an open curve: the edge is the curve's point nearest it
                    // (no length), else the file is wrong.
                    let (t, d) =
                        nearest_from_samples(curve, p0, LOCATE_ACCURACY, &[a, 0.5 * (a + b), b]);
                    if d > DEGENERATE_MM {
                        return Err(
                            "the edge starts and ends at one vertex but its curve is open".into(),
                        );
                    }
                    (t, t)
                } else if same_sense {
                    (a, b)
                } else {
                    (b, a)
                }
            } else {
                let mut ts = Vec::new();
                let mut br = curve.breakpoints();
                if br.len() < 2 {
                    br = vec![a, b];
                }
                for w in br.windows(2) {
                    for k in 0..LOCATE_SAMPLES_PER_SPAN {
                        ts.push(w[0] + (w[1] - w[0]) * k as f64 / LOCATE_SAMPLES_PER_SPAN as f64);
                    }
                }
                ts.push(b);
                let locate = |p: DVec3, at_start: bool| {
                    let (t, _) = nearest_from_samples(curve, p, LOCATE_ACCURACY, &ts);
                    // On a closed curve a vertex at the seam is both ends: pick by direction.
                    if ends_meet && (curve.eval(a).distance(p) <= 1e-4) {
                        if same_sense == at_start { a } else { b }
                    } else {
                        t
                    }
                };
                (locate(p0, true), locate(p1, false))
            }
        }
    };
    let mut off = 0.0f64;
    for (t, p) in [(t0, p0), (t1, p1)] {
        let d = curve.eval(t).distance(p);
        if d.is_nan() {
            return Err(format!(
                "its {} cannot be evaluated at its vertices",
                curve.name()
            ));
        }
        off = off.max(d);
    }
    // No length: a degenerate edge when it starts and ends at one vertex.
    let length: f64 = (0..DEGENERATE_SAMPLES)
        .map(|k| {
            let a = t0 + (t1 - t0) * k as f64 / DEGENERATE_SAMPLES as f64;
            let b = t0 + (t1 - t0) * (k + 1) as f64 / DEGENERATE_SAMPLES as f64;
            curve.eval(a).distance(curve.eval(b))
        })
        .sum();
    let degenerate = t0 == t1 || length <= DEGENERATE_MM;
    if degenerate && !closed {
        return Err("the edge has zero length on its curve".into());
    }
    Ok((t0, t1, degenerate, off))
}

impl<'f> Builder<'f> {
    fn shell(
        &mut self,
        sid: u64,
        from: u64,
        index: usize,
        seen: &mut BTreeMap<(u64, usize), usize>,
    ) -> Result<Vec<usize>, StepError> {
        if is_bounded_surface(self.r.file, sid) {
            return Ok(self.bounded_surface(sid, from, index, seen));
        }
        // An oriented shell (a solid's void, written reversed) is its element's faces, each
        // reversed when the orientation is false.
        let (element, reversed) = self.r.visit(sid, from, |_, inst| {
            let a = Attrs::of(inst, &inst.parts[0]);
            let t = a.name.to_ascii_uppercase();
            if t == "ORIENTED_CLOSED_SHELL" || t == "ORIENTED_OPEN_SHELL" {
                Ok((a.reference(2, "element")?, !a.boolean(3, "orientation")?))
            } else {
                Ok((sid, false))
            }
        })?;
        let face_ids = self.r.visit(element, sid, |_, inst| {
            let a = Attrs::of(inst, &inst.parts[0]);
            let t = a.name.to_ascii_uppercase();
            if t != "CLOSED_SHELL" && t != "OPEN_SHELL" {
                return Err(
                    a.fail("expected CLOSED_SHELL, OPEN_SHELL or an ORIENTED_CLOSED_SHELL of one")
                );
            }
            a.refs(1, "cfs_faces")
        })?;
        let mut out = Vec::with_capacity(face_ids.len());
        for fid in face_ids {
            if let Some(&k) = seen.get(&(fid, self.instance)) {
                out.push(k);
                continue;
            }
            let k = self.faces.len();
            seen.insert((fid, self.instance), k);
            // A face that cannot be read keeps its number and its error.
            let geometry = self
                .face(fid, sid)
                .map(|g| if reversed { g.reversed() } else { g });
            if let Ok(g) = &geometry {
                for u in g.bounds.iter().flat_map(|b| &b.uses) {
                    self.edges[u.edge].faces.push(k);
                }
            }
            self.faces.push(Face {
                entity: fid,
                shell: index,
                geometry,
                repairs: Vec::new(),
            });
            out.push(k);
        }
        Ok(out)
    }

    fn face(&mut self, fid: u64, from: u64) -> Result<FaceGeometry, StepError> {
        let (bounds, surf, same_sense) = self.r.visit(fid, from, |_, inst| {
            let a = Attrs::of(inst, &inst.parts[0]);
            let t = a.name.to_ascii_uppercase();
            if inst.parts.len() != 1 || (t != "ADVANCED_FACE" && t != "FACE_SURFACE") {
                return Err(StepError::entity(
                    fid,
                    &inst.type_name(),
                    "not supported (faces must be ADVANCED_FACE or FACE_SURFACE)",
                ));
            }
            Ok((
                a.refs(1, "bounds")?,
                a.reference(2, "face_geometry")?,
                a.boolean(3, "same_sense")?,
            ))
        })?;
        let surface = self.r.surface(surf, fid)?;
        let mut out = Vec::with_capacity(bounds.len());
        for b in bounds {
            out.push(self.bound(b, fid)?);
        }
        Ok(FaceGeometry {
            surface_entity: surf,
            surface,
            same_sense,
            bounds: out,
        })
    }

    fn bound(&mut self, bid: u64, fid: u64) -> Result<Bound, StepError> {
        let (outer, lp, orientation) = self.r.visit(bid, fid, |_, inst| {
            let a = Attrs::of(inst, &inst.parts[0]);
            let t = a.name.to_ascii_uppercase();
            if t != "FACE_OUTER_BOUND" && t != "FACE_BOUND" {
                return Err(a.fail("expected FACE_OUTER_BOUND or FACE_BOUND"));
            }
            Ok((
                t == "FACE_OUTER_BOUND",
                a.reference(1, "bound")?,
                a.boolean(2, "orientation")?,
            ))
        })?;
        enum Loop {
            Edges(Vec<u64>),
            Vertex(u64),
        }
        let l = self.r.visit(lp, bid, |_, inst| {
            let a = Attrs::of(inst, &inst.parts[0]);
            match a.name.to_ascii_uppercase().as_str() {
                "EDGE_LOOP" => Ok(Loop::Edges(a.refs(1, "edge_list")?)),
                "VERTEX_LOOP" => Ok(Loop::Vertex(a.reference(1, "loop_vertex")?)),
                _ => Err(StepError::entity(
                    lp,
                    &inst.type_name(),
                    "not supported (loops must be EDGE_LOOP or VERTEX_LOOP)",
                )),
            }
        })?;
        let mut bound = Bound {
            entity: bid,
            outer,
            uses: Vec::new(),
            vertex: None,
        };
        match l {
            Loop::Vertex(v) => bound.vertex = Some(self.vertex(v, lp)?),
            Loop::Edges(oes) => {
                for oe in oes {
                    let (edge, forward) = self.r.visit(oe, lp, |_, inst| {
                        let a = Reader::expect_simple(inst, "ORIENTED_EDGE")?;
                        Ok((
                            a.reference(3, "edge_element")?,
                            a.boolean(4, "orientation")?,
                        ))
                    })?;
                    let e = self.edge(edge, oe)?;
                    bound.uses.push(EdgeUse { edge: e, forward });
                }
                if bound.uses.is_empty() {
                    return Err(StepError::entity(lp, "EDGE_LOOP", "the loop has no edges"));
                }
                if !orientation {
                    bound.uses.reverse();
                    for u in &mut bound.uses {
                        u.forward = !u.forward;
                    }
                }
            }
        }
        Ok(bound)
    }

    fn vertex(&mut self, vid: u64, from: u64) -> Result<usize, StepError> {
        if let Some(v) = self.vertex_of.get(&(vid, self.instance)) {
            return v.clone();
        }
        let r = self
            .r
            .visit(vid, from, |r, inst| {
                let a = Reader::expect_simple(inst, "VERTEX_POINT")?;
                r.point(a.reference(1, "vertex_geometry")?, vid)
            })
            .map(|point| {
                self.vertices.push(Vertex { entity: vid, point });
                self.vertices.len() - 1
            });
        self.vertex_of.insert((vid, self.instance), r.clone());
        r
    }

    /// The index of edge `#eid`, reading it the first time.
    fn edge(&mut self, eid: u64, from: u64) -> Result<usize, StepError> {
        if let Some(&e) = self.edge_of.get(&(eid, self.instance)) {
            return Ok(e);
        }
        // The edge must at least be an EDGE_CURVE to take a number.
        let file = self.r.file;
        match file.type_of(eid) {
            Some(t) if t.eq_ignore_ascii_case("EDGE_CURVE") => {}
            Some(t) => {
                return Err(StepError::entity(
                    eid,
                    t,
                    "not supported (edges must be EDGE_CURVE)",
                ));
            }
            None if !file.contains(eid) => return Err(StepError::Dangling { from, to: eid }),
            None => return Err(StepError::entity(eid, "(complex)", "expected EDGE_CURVE")),
        }
        let geometry = self.edge_geometry(eid, from);
        let k = self.edges.len();
        self.edges.push(Edge {
            entity: eid,
            geometry,
            faces: Vec::new(),
            repairs: Vec::new(),
            sewn_into: None,
        });
        self.edge_of.insert((eid, self.instance), k);
        Ok(k)
    }

    fn edge_geometry(&mut self, eid: u64, from: u64) -> Result<EdgeGeometry, StepError> {
        let (v0, v1, gid, same_sense) = self.r.visit(eid, from, |_, inst| {
            let a = Reader::expect_simple(inst, "EDGE_CURVE")?;
            Ok((
                a.reference(1, "edge_start")?,
                a.reference(2, "edge_end")?,
                a.reference(3, "edge_geometry")?,
                a.boolean(4, "same_sense")?,
            ))
        })?;
        let start = self.vertex(v0, eid)?;
        let end = self.vertex(v1, eid)?;
        let curve = self.r.curve(gid, eid, Space::Model)?;
        let pcurves = self.pcurves(gid, eid);
        let (p0, p1) = (self.vertices[start].point, self.vertices[end].point);
        let (t0, t1, degenerate, off_curve_mm) =
            edge_range(&curve, p0, p1, start == end, same_sense)
                .map_err(|m| StepError::entity(eid, "EDGE_CURVE", m))?;
        Ok(EdgeGeometry {
            curve,
            start,
            end,
            t0,
            t1,
            pcurves,
            degenerate,
            off_curve_mm,
        })
    }

    /// The pcurves of a `SURFACE_CURVE`/`SEAM_CURVE`, when they can be read (they only guide the
    /// projection onto spline surfaces, so an unreadable one is left out).
    fn pcurves(&mut self, gid: u64, eid: u64) -> Vec<Pcurve> {
        let assoc: Vec<u64> = self
            .r
            .visit(gid, eid, |_, inst: &Instance| {
                let a = Attrs::of(inst, &inst.parts[0]);
                match a.name.to_ascii_uppercase().as_str() {
                    "SURFACE_CURVE" | "SEAM_CURVE" | "INTERSECTION_CURVE" => Ok(a
                        .list(2, "associated_geometry")?
                        .iter()
                        .filter_map(|v| match v {
                            Value::Ref(r) => Some(*r),
                            _ => None,
                        })
                        .collect()),
                    _ => Ok(Vec::new()),
                }
            })
            .unwrap_or_default();
        let mut out = Vec::new();
        for p in assoc {
            if self
                .r
                .file
                .type_of(p)
                .is_some_and(|t| t.eq_ignore_ascii_case("PCURVE"))
            {
                let got = self.r.visit(p, gid, |r, inst| {
                    let a = Attrs::of(inst, &inst.parts[0]);
                    let s = a.reference(1, "basis_surface")?;
                    let (_, uv) = r.pcurve(p, inst)?;
                    Ok((s, uv))
                });
                if let Ok((surface_entity, curve)) = got {
                    out.push(Pcurve {
                        surface_entity,
                        curve,
                    });
                }
            }
        }
        out
    }
}

/// Points along each edge's curve: enough to see a closed edge's extent from its one vertex.
const EXTENT_SAMPLES: usize = 8;

/// The diagonal of the bounding box of the vertices and of [`EXTENT_SAMPLES`] points along each
/// edge (mm); 0 for a model without finite points.
fn extent(vertices: &[Vertex], edges: &[Edge]) -> f64 {
    let along = edges
        .iter()
        .filter_map(|e| e.geometry.as_ref().ok())
        .flat_map(|g| {
            (1..EXTENT_SAMPLES).map(move |k| {
                let t = g.t0 + (g.t1 - g.t0) * k as f64 / EXTENT_SAMPLES as f64;
                g.curve.eval(t)
            })
        });
    let d = Aabb3::from_points(vertices.iter().map(|v| v.point).chain(along)).diagonal();
    if d.is_finite() { d } else { 0.0 }
}
