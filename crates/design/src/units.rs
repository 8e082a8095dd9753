//! Unit conversion: every length of a parsed piece scaled from design units to mm, once, at load.

use crate::{CurveDef, GrainDef, P3, PieceDef, SeamDef, SurfaceDef};

pub(crate) fn sp(p: &mut P3, s: f64) {
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
        // A STEP file states its own unit; the model is converted to mm when read.
        SurfaceDef::Step { .. } => {}
    }
}

pub(crate) fn scale_piece(p: &mut PieceDef, s: f64) {
    scale_surface(&mut p.surface, s);
    for seam in &mut p.seams {
        if let SeamDef::Points(pts) = seam {
            pts.iter_mut().for_each(|q| sp(q, s));
        }
    }
    for m in &mut p.marks {
        m.points.iter_mut().for_each(|q| sp(q, s));
    }
    if let Some(g) = p.grain.as_mut().and_then(GrainDef::line_mut) {
        g.iter_mut().for_each(|q| sp(q, s));
    }
    for region in p.no_cut.iter_mut().chain(p.seam_hidden_regions.iter_mut()) {
        region.iter_mut().for_each(|q| sp(q, s));
    }
    p.mesh_scale = s;
}
