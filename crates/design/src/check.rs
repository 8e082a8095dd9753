//! Checks of a parsed design before anything is built: finite numbers, sane sizes, named errors.

use crate::error::Ctx;
use crate::{CurveDef, DesignError, P3, PieceDef, SeamDef, SurfaceDef};

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

/// Checks one parsed piece (still in design units): quantity, allowance, surface, seams, marks, grain.
pub(crate) fn check_piece(p: &PieceDef) -> Result<(), DesignError> {
    let ctx = Ctx::of(p);
    if p.quantity == 0 {
        return Err(ctx.err("quantity must be at least 1".into()));
    }
    match p.pairs {
        Some(0) => return Err(ctx.err("pairs must be at least 1".into())),
        Some(_) if p.quantity != 1 => {
            return Err(ctx.err(
                "give quantity or pairs, not both (pairs = N cuts N as drawn and N mirrored)"
                    .into(),
            ));
        }
        _ => {}
    }
    if let Some(l) = &p.pair_labels {
        if p.pairs.is_none() {
            return Err(ctx.err("pair_labels needs pairs".into()));
        }
        if l.iter().any(|s| s.trim().is_empty()) || l[0] == l[1] {
            return Err(ctx.err(format!(
                "pair_labels must be two different non-empty labels, got {l:?}"
            )));
        }
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
    Ok(())
}
