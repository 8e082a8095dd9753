//! Building a piece: the checked definitions become surfaces, curves and meshes in mm.

use std::path::Path;
use std::sync::Arc;

use flatcut_geom::{DVec3, Tolerances};
use flatcut_mesh::io::read_mesh;
use flatcut_mesh::{TessError, TriMesh, tessellate_patches};
use flatcut_surface::curve::{
    BSpline, Bezier, CubicSpline, Hermite, Nurbs, Polyline, SplineEnds, SplineParam,
};
use flatcut_surface::patch::{
    BSplinePatch, BezierPatch, CoonsPatch, DevelopableSurface, GordonSurface, HermitePatch,
    RuledSurface, TriBezierPatch,
};
use flatcut_surface::{ParamCurve, ParamSurface};

use crate::error::Ctx;
use crate::{Blend, CurveDef, DesignError, P3, PieceDef, SeamDef, SurfaceDef};

/// The geometry of a built piece.
#[derive(Clone, Debug)]
pub enum PieceGeometry {
    /// One or more parametric patches (mm).
    Patches(Vec<Arc<dyn ParamSurface>>),
    /// A mesh (mm).
    Mesh(TriMesh),
    /// Faces of a STEP model (mm).
    Step(crate::step::StepPiece),
}

impl PieceGeometry {
    /// A triangle mesh of the piece: patches are tessellated to `tol.chord_mm` (crack-free across
    /// patches); a mesh is returned as it is.
    pub fn tessellate(&self, tol: &Tolerances) -> Result<TriMesh, TessError> {
        match self {
            PieceGeometry::Mesh(m) => Ok(m.clone()),
            PieceGeometry::Step(s) => s.mesh(tol).map_err(|e| TessError::Face(e.to_string())),
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
        SurfaceDef::Bspline { .. } | SurfaceDef::Nurbs { .. } => spline_patch(ctx, s)?,
        SurfaceDef::Coons {
            v0,
            v1,
            u0,
            u1,
            blend,
        } => coons_patch(ctx, [v0, v1, u0, u1], *blend)?,
        SurfaceDef::Gordon {
            u_curves,
            v_curves,
            u_params,
            v_params,
        } => gordon_surface(ctx, u_curves, v_curves, u_params, v_params)?,
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
                if matches!(
                    p,
                    SurfaceDef::Mesh { .. } | SurfaceDef::Patches { .. } | SurfaceDef::Step { .. }
                ) {
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
        SurfaceDef::Step { .. } => {
            return Err(ctx.err("step: a STEP model is not one parametric surface".into()));
        }
    };
    out.push(surf);
    Ok(())
}

/// A B-spline or NURBS patch of the design (`s` is one of the two), clamped uniform knots where
/// the file gives none.
fn spline_patch(ctx: &Ctx, s: &SurfaceDef) -> Result<Arc<dyn ParamSurface>, DesignError> {
    let (SurfaceDef::Bspline {
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
    }) = s
    else {
        return Err(ctx.err("not a B-spline or NURBS patch".into()));
    };
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
    Ok(Arc::new(
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
        .map_err(|err| ctx.surf("bspline/nurbs", err))?,
    ))
}

/// A Coons patch from its four boundary curves `[v0, v1, u0, u1]`.
fn coons_patch(
    ctx: &Ctx,
    curves: [&CurveDef; 4],
    blend: Blend,
) -> Result<Arc<dyn ParamSurface>, DesignError> {
    let [v0, v1, u0, u1] = curves;
    let c = [
        build_curve(ctx, "coons curve v0", v0)?,
        build_curve(ctx, "coons curve v1", v1)?,
        build_curve(ctx, "coons curve u0", u0)?,
        build_curve(ctx, "coons curve u1", u1)?,
    ];
    let [a, b, cc, d] = c;
    Ok(Arc::new(
        match blend {
            Blend::Linear => CoonsPatch::bilinear(a, b, cc, d),
            Blend::Cubic => CoonsPatch::bicubic(a, b, cc, d),
        }
        .map_err(|err| ctx.surf("coons", err))?,
    ))
}

/// A Gordon surface through its curve network.
fn gordon_surface(
    ctx: &Ctx,
    u_curves: &[CurveDef],
    v_curves: &[CurveDef],
    u_params: &[f64],
    v_params: &[f64],
) -> Result<Arc<dyn ParamSurface>, DesignError> {
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
    Ok(Arc::new(
        GordonSurface::new(uc, vc, u_params.to_vec(), v_params.to_vec())
            .map_err(|err| ctx.surf("gordon", err))?,
    ))
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
            let map = self.mesh_map;
            if !map.is_identity() {
                m.positions
                    .iter_mut()
                    .for_each(|p| *p = flatcut_geom::DVec3::from_array(map.point(p.to_array())));
                // A flat map scales with a uniform scale about the origin; under any other its
                // lengths no longer match the surface's: it is dropped.
                match (map.a[0] == map.a[1] && map.a[1] == map.a[2], &mut m.flat) {
                    (true, Some(f)) => f.iter_mut().for_each(|q| *q *= map.a[0]),
                    _ => m.flat = None,
                }
                if let Some(i) = m
                    .positions
                    .iter()
                    .position(|p| !flatcut_geom::limits::in_range3(*p))
                {
                    return Err(ctx.err(format!(
                        "mesh {}: vertex {} lies beyond ±{:e} mm once converted to mm",
                        path.display(),
                        i + 1,
                        flatcut_geom::limits::MAX_COORD_MM
                    )));
                }
            }
            return Ok(PieceGeometry::Mesh(m));
        }
        if let SurfaceDef::Step { .. } = &self.surface {
            return crate::step::build(self, base_dir).map(PieceGeometry::Step);
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
