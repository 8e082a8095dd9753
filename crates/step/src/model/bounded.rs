//! Faces of `CURVE_BOUNDED_SURFACE`s: a surface trimmed by closed boundary curves, as some
//! systems write a sheet in a `GEOMETRIC_SET` instead of a shell (ISO 10303-42 §4.5.69). Each
//! becomes a face of its own open shell: every `COMPOSITE_CURVE_SEGMENT` of a boundary is an
//! edge from the point where it starts to where the next one starts (a gap between them is
//! the edge's vertex off its curve, healed and reported like any other), and the loops are
//! oriented by their nesting in the surface's (u, v) — the standard gives their direction no
//! meaning — with the surface's own normal as the face's.

use super::*;

/// Points per edge when finding which way round a loop runs in (u, v).
const ORIENT_SAMPLES: usize = 16;

/// What a boundary segment's parent curve is.
enum Parent<'f> {
    /// A curve on the surface with its 3D curve (`SURFACE_CURVE`, simple or complex).
    OnSurface(u64),
    /// A part of a basis curve between two trimming values (points or parameters).
    Trimmed {
        basis: u64,
        from: Vec<Value<'f>>,
        to: Vec<Value<'f>>,
        agrees: bool,
    },
    /// A bounded curve used whole (a B-spline, a polyline, a pcurve, a circle).
    Whole,
}

impl Builder<'_> {
    /// The one-face open shell of the `CURVE_BOUNDED_SURFACE` `sid` (in the geometric set
    /// `from`).
    pub(super) fn bounded_surface(
        &mut self,
        sid: u64,
        from: u64,
        index: usize,
        seen: &mut BTreeMap<(u64, usize), usize>,
    ) -> Vec<usize> {
        if let Some(&k) = seen.get(&(sid, self.instance)) {
            return vec![k];
        }
        let k = self.faces.len();
        seen.insert((sid, self.instance), k);
        let geometry = self.bounded_face(sid, from);
        if let Ok(g) = &geometry {
            for u in g.bounds.iter().flat_map(|b| &b.uses) {
                self.edges[u.edge].faces.push(k);
            }
        }
        self.faces.push(Face {
            entity: sid,
            shell: index,
            geometry,
            repairs: Vec::new(),
        });
        vec![k]
    }

    fn bounded_face(&mut self, sid: u64, from: u64) -> Result<FaceGeometry, StepError> {
        let (basis, boundaries, implicit_outer) = self.r.visit(sid, from, |_, inst| {
            let a = Reader::expect_simple(inst, "CURVE_BOUNDED_SURFACE")?;
            Ok((
                a.reference(1, "basis_surface")?,
                a.refs(2, "boundaries")?,
                a.boolean(3, "implicit_outer")?,
            ))
        })?;
        if implicit_outer {
            return Err(StepError::entity(
                sid,
                "CURVE_BOUNDED_SURFACE",
                "implicit_outer is true (the basis surface's own edges as the outer boundary): not supported",
            ));
        }
        if boundaries.is_empty() {
            return Err(StepError::entity(
                sid,
                "CURVE_BOUNDED_SURFACE",
                "it has no boundary curves",
            ));
        }
        let surface = self.r.surface(basis, sid)?;
        let mut bounds = Vec::with_capacity(boundaries.len());
        for b in boundaries {
            bounds.push(self.boundary_curve(b, sid)?);
        }
        self.orient(&surface, &mut bounds);
        Ok(FaceGeometry {
            surface_entity: basis,
            surface,
            same_sense: true,
            bounds,
        })
    }

    /// A `BOUNDARY_CURVE` or `OUTER_BOUNDARY_CURVE` as a loop of new edges, one per segment.
    fn boundary_curve(&mut self, bid: u64, sid: u64) -> Result<Bound, StepError> {
        let (outer, segments) = self.r.visit(bid, sid, |_, inst| {
            let a = Attrs::of(inst, &inst.parts[0]);
            let t = a.name.to_ascii_uppercase();
            if inst.parts.len() != 1 || (t != "BOUNDARY_CURVE" && t != "OUTER_BOUNDARY_CURVE") {
                return Err(a.fail("expected BOUNDARY_CURVE or OUTER_BOUNDARY_CURVE"));
            }
            Ok((t == "OUTER_BOUNDARY_CURVE", a.refs(1, "segments")?))
        })?;
        if segments.is_empty() {
            return Err(StepError::entity(
                bid,
                "BOUNDARY_CURVE",
                "the boundary has no segments",
            ));
        }
        // Each segment's curve, its ends in the loop's direction, and whether the loop runs
        // along the curve's own direction there.
        let mut parts = Vec::with_capacity(segments.len());
        for s in segments {
            let (same_sense, parent) = self.r.visit(s, bid, |_, inst| {
                let a = Reader::expect_simple(inst, "COMPOSITE_CURVE_SEGMENT")?;
                Ok((a.boolean(1, "same_sense")?, a.reference(2, "parent_curve")?))
            })?;
            let (curve, p0, p1, agrees) = self.segment_curve(parent, s)?;
            let (start, along) = if same_sense {
                (p0, agrees)
            } else {
                (p1, !agrees)
            };
            parts.push((s, curve, start, along));
        }
        // A vertex where each segment starts; it ends where the next one starts.
        let vs: Vec<usize> = parts
            .iter()
            .map(|&(s, _, point, _)| {
                self.vertices.push(Vertex { entity: s, point });
                self.vertices.len() - 1
            })
            .collect();
        let n = parts.len();
        let mut uses = Vec::with_capacity(n);
        for (k, (s, curve, _, along)) in parts.into_iter().enumerate() {
            let (start, end) = (vs[k], vs[(k + 1) % n]);
            let (p0, p1) = (self.vertices[start].point, self.vertices[end].point);
            let geometry = edge_range(&curve, p0, p1, start == end, along)
                .map(|(t0, t1, degenerate, off_curve_mm)| EdgeGeometry {
                    curve: curve.clone(),
                    start,
                    end,
                    t0,
                    t1,
                    pcurves: Vec::new(),
                    degenerate,
                    off_curve_mm,
                })
                .map_err(|m| StepError::entity(s, "COMPOSITE_CURVE_SEGMENT", m));
            self.edges.push(Edge {
                entity: s,
                geometry,
                faces: Vec::new(),
                repairs: Vec::new(),
                sewn_into: None,
            });
            uses.push(EdgeUse {
                edge: self.edges.len() - 1,
                forward: true,
            });
        }
        Ok(Bound {
            entity: bid,
            outer,
            uses,
            vertex: None,
        })
    }

    /// A segment's parent curve, the points where it starts and ends, and whether it runs the
    /// way of the curve returned (a trimmed curve may run against its basis).
    fn segment_curve(
        &mut self,
        parent: u64,
        seg: u64,
    ) -> Result<(Arc<Curve>, DVec3, DVec3, bool), StepError> {
        let kind = self.r.visit(parent, seg, |_, inst| {
            for name in ["SURFACE_CURVE", "SEAM_CURVE", "INTERSECTION_CURVE"] {
                if let Some(p) = inst.part(name) {
                    // A complex instance's partial value has no name attribute.
                    let at = usize::from(inst.parts.len() == 1);
                    return Ok(Parent::OnSurface(
                        Attrs::of(inst, p).reference(at, "curve_3d")?,
                    ));
                }
            }
            if inst.is("TRIMMED_CURVE") {
                let a = Attrs::of(inst, &inst.parts[0]);
                return Ok(Parent::Trimmed {
                    basis: a.reference(1, "basis_curve")?,
                    from: a.list(2, "trim_1")?.to_vec(),
                    to: a.list(3, "trim_2")?.to_vec(),
                    agrees: a.boolean(4, "sense_agreement")?,
                });
            }
            Ok(Parent::Whole)
        })?;
        match kind {
            Parent::OnSurface(c) => self.segment_curve(c, parent),
            Parent::Trimmed {
                basis,
                from,
                to,
                agrees,
            } => {
                let curve = self.r.curve(basis, parent, Space::Model)?;
                let p0 = self.trim_point(&curve, &from, parent, "trim_1")?;
                let p1 = self.trim_point(&curve, &to, parent, "trim_2")?;
                Ok((curve, p0, p1, agrees))
            }
            Parent::Whole => {
                let curve = self.r.curve(parent, seg, Space::Model)?;
                let (a, b) = curve.domain();
                if !(a.is_finite() && b.is_finite()) {
                    return Err(StepError::entity(
                        parent,
                        curve.name(),
                        "an unbounded curve as a boundary segment (it needs a TRIMMED_CURVE)",
                    ));
                }
                Ok((curve.clone(), curve.eval(a), curve.eval(b), true))
            }
        }
    }

    /// The point a `TRIMMED_CURVE` is trimmed at: its point, else its parameter on `curve`.
    fn trim_point(
        &mut self,
        curve: &Curve,
        select: &[Value],
        id: u64,
        what: &str,
    ) -> Result<DVec3, StepError> {
        for v in select {
            if let Value::Ref(p) = v {
                return self.r.point(*p, id);
            }
        }
        for v in select {
            if let Value::Typed(name, args) = v
                && name.eq_ignore_ascii_case("PARAMETER_VALUE")
                && let Some(x) = args.first().and_then(crate::attrs::number)
            {
                // A conic's parameter is an angle in the file's unit.
                let t = if matches!(curve, Curve::Conic(_)) {
                    x * self.r.rad
                } else {
                    x
                };
                return Ok(curve.eval(t));
            }
        }
        Err(StepError::entity(
            id,
            "TRIMMED_CURVE",
            format!("{what}: neither a point nor a parameter value"),
        ))
    }

    /// Runs the outer loop (the `OUTER_BOUNDARY_CURVE`, else the largest) counter-clockwise in
    /// the surface's (u, v) and the others clockwise, so the surface normal is the face's.
    fn orient(&self, s: &Surface, bounds: &mut [Bound]) {
        let areas: Vec<f64> = bounds.iter().map(|b| self.uv_area(s, b)).collect();
        let outer = bounds.iter().position(|b| b.outer).unwrap_or_else(|| {
            (0..bounds.len())
                .max_by(|&a, &b| areas[a].abs().total_cmp(&areas[b].abs()))
                .unwrap_or(0)
        });
        for (k, b) in bounds.iter_mut().enumerate() {
            if (k == outer) != (areas[k] > 0.0) {
                b.uses.reverse();
                for u in &mut b.uses {
                    u.forward = !u.forward;
                }
            }
        }
    }

    /// The signed area a loop bounds in the surface's (u, v), from points along its edges.
    fn uv_area(&self, s: &Surface, b: &Bound) -> f64 {
        let mut uv: Vec<DVec2> = Vec::new();
        for u in &b.uses {
            let Ok(g) = &self.edges[u.edge].geometry else {
                continue;
            };
            for k in 0..ORIENT_SAMPLES {
                let f = k as f64 / ORIENT_SAMPLES as f64;
                let f = if u.forward { f } else { 1.0 - f };
                let mut q = s.param_of(g.curve.eval(g.t0 + (g.t1 - g.t0) * f), uv.last().copied());
                if let Some(l) = uv.last() {
                    for (d, per) in s.periods().iter().enumerate() {
                        if let Some(per) = per {
                            q[d] += per * ((l[d] - q[d]) / per).round();
                        }
                    }
                }
                uv.push(q);
            }
        }
        let n = uv.len();
        0.5 * (0..n).map(|k| uv[k].perp_dot(uv[(k + 1) % n])).sum::<f64>()
    }
}

#[cfg(test)]
mod tests {
    use crate::{Model, StepFile, Tessellation, face_area};
    use flatcut_geom::Tolerances;
    use flatcut_mesh::tessellate::TessOptions;

    /// A 100 × 60 mm sheet on the plane z = 5 (normal +z) with a hole of radius 10, written as
    /// a `CURVE_BOUNDED_SURFACE`: the outer boundary clockwise seen from +z, its last side a
    /// line used backwards, a gap of 0.001 mm at one corner; the hole two half circles trimmed
    /// by parameter values (degrees), each used backwards: clockwise too. Both loops run the
    /// way a hole would, so a face taken as written would be "repaired" as the wrong way round.
    fn sheet() -> String {
        let line = |id: u64, a: (f64, f64), b: (f64, f64)| {
            let d = (b.0 - a.0, b.1 - a.1);
            let len = d.0.hypot(d.1);
            format!(
                "#{id}=TRIMMED_CURVE('',#{},(#{}),(#{}),.T.,.CARTESIAN.);\n\
                 #{}=LINE('',#{},#{});\n#{}=VECTOR('',#{},1.);\n#{}=DIRECTION('',({},{},0.));\n\
                 #{}=CARTESIAN_POINT('',({},{},5.));\n#{}=CARTESIAN_POINT('',({},{},5.));\n",
                id + 1,
                id + 5,
                id + 6,
                id + 1,
                id + 5,
                id + 2,
                id + 2,
                id + 3,
                id + 3,
                d.0 / len,
                d.1 / len,
                id + 5,
                a.0,
                a.1,
                id + 6,
                b.0,
                b.1
            )
        };
        let mut data = String::new();
        // Clockwise from +z: (0,0) → (0,60) → (100,60) → (100,0) → back to (0,0), the last
        // side a line from (0,0) to (100,0) used backwards.
        data += &line(100, (0.0, 0.0), (0.0, 60.0));
        data += &line(110, (0.0, 60.0), (100.0, 60.0));
        data += &line(120, (100.0, 60.0), (100.0, 0.001));
        data += &line(130, (0.0, 0.0), (100.0, 0.0));
        data += "#10=COMPOSITE_CURVE_SEGMENT(.CONTINUOUS.,.T.,#100);\n\
                 #11=COMPOSITE_CURVE_SEGMENT(.CONTINUOUS.,.T.,#110);\n\
                 #12=COMPOSITE_CURVE_SEGMENT(.CONTINUOUS.,.T.,#120);\n\
                 #13=COMPOSITE_CURVE_SEGMENT(.CONTINUOUS.,.F.,#130);\n\
                 #20=OUTER_BOUNDARY_CURVE('',(#10,#11,#12,#13),.F.);\n\
                 #30=CIRCLE('',#31,10.);\n#31=AXIS2_PLACEMENT_3D('',#32,#33,#34);\n\
                 #32=CARTESIAN_POINT('',(40.,30.,5.));\n#33=DIRECTION('',(0.,0.,1.));\n\
                 #34=DIRECTION('',(1.,0.,0.));\n\
                 #35=TRIMMED_CURVE('',#30,(PARAMETER_VALUE(0.)),(PARAMETER_VALUE(180.)),.T.,.PARAMETER.);\n\
                 #36=TRIMMED_CURVE('',#30,(PARAMETER_VALUE(180.)),(PARAMETER_VALUE(360.)),.T.,.PARAMETER.);\n\
                 #37=COMPOSITE_CURVE_SEGMENT(.CONTINUOUS.,.F.,#36);\n\
                 #38=COMPOSITE_CURVE_SEGMENT(.CONTINUOUS.,.F.,#35);\n\
                 #39=BOUNDARY_CURVE('',(#37,#38),.F.);\n\
                 #40=PLANE('',#41);\n#41=AXIS2_PLACEMENT_3D('',#42,#33,#34);\n\
                 #42=CARTESIAN_POINT('',(0.,0.,5.));\n\
                 #50=CURVE_BOUNDED_SURFACE('sheet',#40,(#20,#39),.F.);\n\
                 #60=GEOMETRIC_SET('',(#50));\n\
                 #61=GEOMETRICALLY_BOUNDED_SURFACE_SHAPE_REPRESENTATION('',(#60),#70);\n\
                 #70=(GEOMETRIC_REPRESENTATION_CONTEXT(3) GLOBAL_UNIT_ASSIGNED_CONTEXT((#71,#72,#73)) REPRESENTATION_CONTEXT('',''));\n\
                 #71=(LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.));\n\
                 #72=(NAMED_UNIT(*) PLANE_ANGLE_UNIT() CONVERSION_BASED_UNIT('DEGREE',#74));\n\
                 #73=(NAMED_UNIT(*) SI_UNIT($,.STERADIAN.) SOLID_ANGLE_UNIT());\n\
                 #74=PLANE_ANGLE_MEASURE_WITH_UNIT(PLANE_ANGLE_MEASURE(0.0174532925199433),#75);\n\
                 #75=(NAMED_UNIT(*) PLANE_ANGLE_UNIT() SI_UNIT($,.RADIAN.));\n";
        format!(
            "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\nFILE_NAME('sheet','',(''),(''),'','','');\nFILE_SCHEMA(('AUTOMOTIVE_DESIGN'));\nENDSEC;\nDATA;\n{data}ENDSEC;\nEND-ISO-10303-21;\n"
        )
    }

    #[test]
    fn a_curve_bounded_surface_is_a_face_oriented_by_its_nesting() {
        let model = Model::from_file(&StepFile::parse(sheet()).unwrap()).unwrap();
        assert_eq!(model.faces.len(), 1);
        assert_eq!(model.shells.len(), 1);
        assert!(!model.shells[0].closed);
        assert_eq!(model.faces[0].entity, 50);
        let g = model.face(0).unwrap();
        assert_eq!(g.bounds.len(), 2);
        let exact = 100.0 * 60.0 - std::f64::consts::PI * 100.0;
        let area = face_area(&model, 0).unwrap();
        // The 0.001 mm gap at (100, 0) moves a corner by at most that.
        assert!((area - exact).abs() < 0.1, "area {area}, exact {exact}");
        let t = Tessellation::new(
            &model,
            &[0],
            &Tolerances::DEFAULT.with_chord_mm(0.01),
            &TessOptions::DEFAULT,
        )
        .unwrap();
        let fm = &t.faces[0];
        // The plane's normal (+z) is the face's, whichever way the file ran its boundaries, and
        // the loops were not "repaired" for running the other way.
        for k in 0..fm.mesh.triangles.len() {
            let [a, b, c] = fm.mesh.corners(k);
            assert!((b - a).cross(c - a).z > 0.0);
        }
        assert!(
            fm.repairs
                .iter()
                .all(|r| r.kind != crate::heal::RepairKind::Orientation),
            "{:?}",
            fm.repairs
        );
        assert!(
            (fm.mesh.area() - exact).abs() < 0.01 * 100.0,
            "{}",
            fm.mesh.area()
        );
    }
}
