//! Checks of a parsed design before anything is built: finite numbers within the sane range
//! of `flatcut_geom::limits` (checked in mm, whatever the file's units), degrees and counts that
//! fit before anything is allocated from them, named errors.

use flatcut_geom::limits::{self, MAX_CONTROL_POINTS, MAX_DEGREE, MAX_QUANTITY};

use crate::error::Ctx;
use crate::{CurveDef, DartPress, DesignError, GrainDef, P3, PieceDef, SeamDef, SurfaceDef};

/// Every coordinate finite and within range once converted to mm (`s` mm per design unit).
fn check_points(ctx: &Ctx, s: f64, what: &str, pts: &[P3]) -> Result<(), DesignError> {
    for (i, p) in pts.iter().enumerate() {
        if let Some(x) = p.iter().map(|x| x * s).find(|x| !limits::in_range(*x)) {
            return Err(ctx.err(format!(
                "{what}: point {i}: coordinate {}",
                limits::out_of_range_reason(x)
            )));
        }
    }
    Ok(())
}

/// A positive length within range once converted to mm.
fn check_len(ctx: &Ctx, s: f64, what: &str, x: f64) -> Result<(), DesignError> {
    if x.is_finite() && x > 0.0 && limits::in_range(x * s) {
        Ok(())
    } else {
        Err(ctx.err(format!(
            "{what} must be finite, > 0 and at most {:e} mm, got {x}",
            limits::MAX_COORD_MM
        )))
    }
}

fn check_degree(ctx: &Ctx, what: &str, d: usize) -> Result<(), DesignError> {
    if d <= MAX_DEGREE {
        Ok(())
    } else {
        Err(ctx.err(format!(
            "{what}: degree {d} is above the largest supported degree {MAX_DEGREE}"
        )))
    }
}

/// `counts = [nu, nv]` of a tensor-product patch against its point list, checked before any
/// knot vector is built from the counts.
fn check_counts(
    ctx: &Ctx,
    degree: [usize; 2],
    counts: [usize; 2],
    points: usize,
) -> Result<(), DesignError> {
    for (dir, d) in ["u", "v"].into_iter().zip(degree) {
        check_degree(ctx, &format!("surface ({dir})"), d)?;
    }
    let total = counts[0]
        .checked_mul(counts[1])
        .filter(|n| *n <= MAX_CONTROL_POINTS);
    match total {
        None => Err(ctx.err(format!(
            "surface: counts [{}, {}] ask for more than {MAX_CONTROL_POINTS} control points",
            counts[0], counts[1]
        ))),
        Some(n) if n != points => Err(ctx.err(format!(
            "surface: counts [{}, {}] need {n} points, the file gives {points}",
            counts[0], counts[1]
        ))),
        Some(_) => Ok(()),
    }
}

fn check_curve(ctx: &Ctx, s: f64, what: &str, c: &CurveDef) -> Result<(), DesignError> {
    match c {
        CurveDef::Bezier { points }
        | CurveDef::Polyline { points }
        | CurveDef::Spline { points, .. } => check_points(ctx, s, what, points),
        CurveDef::Bspline { degree, points, .. } | CurveDef::Nurbs { degree, points, .. } => {
            check_degree(ctx, what, *degree)?;
            check_points(ctx, s, what, points)
        }
        CurveDef::Hermite { p0, t0, p1, t1 } => check_points(ctx, s, what, &[*p0, *t0, *p1, *t1]),
        CurveDef::Arc {
            center,
            radius,
            start_deg,
            end_deg,
            x_axis,
            y_axis,
        } => {
            check_points(ctx, s, what, &[*center])?;
            for (axis, a) in [("x_axis", x_axis), ("y_axis", y_axis)] {
                if let Some(a) = a {
                    check_points(ctx, 1.0, &format!("{what}: {axis}"), &[*a])?;
                }
            }
            check_len(ctx, s, &format!("{what}: radius"), *radius)?;
            if !(start_deg.is_finite() && end_deg.is_finite()) {
                return Err(ctx.err(format!("{what}: non-finite angle")));
            }
            Ok(())
        }
    }
}

fn check_surface(ctx: &Ctx, s: f64, surf: &SurfaceDef) -> Result<(), DesignError> {
    match surf {
        SurfaceDef::Bezier { degree, points } => {
            check_degree(ctx, "surface (u)", degree[0])?;
            check_degree(ctx, "surface (v)", degree[1])?;
            check_points(ctx, s, "surface", points)
        }
        SurfaceDef::Bspline {
            degree,
            counts,
            points,
            ..
        }
        | SurfaceDef::Nurbs {
            degree,
            counts,
            points,
            ..
        } => {
            check_counts(ctx, *degree, *counts, points.len())?;
            check_points(ctx, s, "surface", points)
        }
        SurfaceDef::TriangularBezier { degree, points } => {
            check_degree(ctx, "surface", *degree)?;
            check_points(ctx, s, "surface", points)
        }
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
            check_points(ctx, s, "hermite data", &all)
        }
        SurfaceDef::Coons { v0, v1, u0, u1, .. } => {
            for (n, c) in [("v0", v0), ("v1", v1), ("u0", u0), ("u1", u1)] {
                check_curve(ctx, s, &format!("coons curve {n}"), c)?;
            }
            Ok(())
        }
        SurfaceDef::Gordon {
            u_curves, v_curves, ..
        } => {
            for (i, c) in u_curves.iter().enumerate() {
                check_curve(ctx, s, &format!("gordon u-curve {i}"), c)?;
            }
            for (i, c) in v_curves.iter().enumerate() {
                check_curve(ctx, s, &format!("gordon v-curve {i}"), c)?;
            }
            Ok(())
        }
        SurfaceDef::Ruled { curves } => {
            for (i, c) in curves.iter().enumerate() {
                check_curve(ctx, s, &format!("ruled curve {i}"), c)?;
            }
            Ok(())
        }
        SurfaceDef::Developable { rails } => {
            for (i, c) in rails.iter().enumerate() {
                check_curve(ctx, s, &format!("developable rail {i}"), c)?;
            }
            Ok(())
        }
        SurfaceDef::Sphere { center, radius } => {
            check_points(ctx, s, "sphere", &[*center])?;
            check_len(ctx, s, "sphere radius", *radius)
        }
        SurfaceDef::Cylinder {
            base,
            radius,
            height,
        } => {
            check_points(ctx, s, "cylinder", &[*base])?;
            check_len(ctx, s, "cylinder radius", *radius)?;
            check_len(ctx, s, "cylinder height", *height)
        }
        SurfaceDef::Cone {
            base,
            base_radius,
            top_radius,
            height,
        } => {
            check_points(ctx, s, "cone", &[*base])?;
            check_len(ctx, s, "cone base_radius", *base_radius)?;
            check_len(ctx, s, "cone height", *height)?;
            if !(*top_radius >= 0.0 && limits::in_range(top_radius * s)) {
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
            check_points(ctx, s, "torus", &[*center])?;
            check_len(ctx, s, "torus major", *major)?;
            check_len(ctx, s, "torus minor", *minor)
        }
        SurfaceDef::Patches { patches } => {
            if patches.is_empty() {
                return Err(ctx.err("patches: the list is empty".into()));
            }
            for p in patches {
                check_surface(ctx, s, p)?;
            }
            Ok(())
        }
        SurfaceDef::Mesh { .. } => Ok(()),
        SurfaceDef::Step { faces, .. } => crate::step::check_faces(ctx, faces),
    }
}

/// Checks one parsed piece (still in design units, `s` mm per unit): quantity, allowance,
/// surface, seams, marks, grain.
pub(crate) fn check_piece(p: &PieceDef, s: f64) -> Result<(), DesignError> {
    let ctx = Ctx::of(p);
    if p.quantity == 0 || p.quantity > MAX_QUANTITY {
        return Err(ctx.err(format!(
            "quantity must be between 1 and {MAX_QUANTITY}, got {}",
            p.quantity
        )));
    }
    match p.pairs {
        Some(n) if n == 0 || n > MAX_QUANTITY => {
            return Err(ctx.err(format!(
                "pairs must be between 1 and {MAX_QUANTITY}, got {n}"
            )));
        }
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
        && !(a.is_finite() && a >= 0.0 && limits::in_range(a))
    {
        return Err(ctx.err(format!(
            "seam_allowance_mm must be finite, ≥ 0 and at most {:e} mm, got {a}",
            limits::MAX_COORD_MM
        )));
    }
    check_surface(&ctx, s, &p.surface)?;
    for (k, seam) in p.seams.iter().enumerate() {
        match seam {
            SeamDef::Points(pts) => check_points(&ctx, s, &format!("seam {k}"), pts)?,
            SeamDef::Params(uv) if uv.iter().flatten().any(|x| !x.is_finite()) => {
                return Err(ctx.err(format!("seam {k}: non-finite (u, v)")));
            }
            _ => {}
        }
    }
    for m in &p.marks {
        check_points(&ctx, s, &format!("mark '{}'", m.name), &m.points)?;
        if m.points.is_empty() {
            return Err(ctx.err(format!("mark '{}' has no points", m.name)));
        }
    }
    for (k, region) in p.no_cut.iter().enumerate() {
        check_points(&ctx, s, &format!("no_cut region {k}"), region)?;
        if region.len() < 3 {
            return Err(ctx.err(format!(
                "no_cut region {k} has {} points; a region needs at least 3",
                region.len()
            )));
        }
    }
    for (k, region) in p.seam_hidden_regions.iter().enumerate() {
        check_points(&ctx, s, &format!("seam_hidden_regions {k}"), region)?;
        if region.len() < 3 {
            return Err(ctx.err(format!(
                "seam_hidden_regions {k} has {} points; a region needs at least 3",
                region.len()
            )));
        }
    }
    if let Some(d) = p.seam_hidden {
        let len = d.iter().map(|c| c * c).sum::<f64>().sqrt();
        if !len.is_finite() || len == 0.0 {
            return Err(ctx.err(format!(
                "seam_hidden {d:?} is not a direction (it needs a finite, non-zero length)"
            )));
        }
    }
    if let Some(g) = p.grain.as_ref().and_then(GrainDef::line) {
        check_points(&ctx, s, "grain", g)?;
        if g[0] == g[1] {
            return Err(ctx.err("grain: the two points coincide (no direction)".into()));
        }
    }
    if let Some(DartPress::Toward(q)) = &p.dart_press {
        check_points(&ctx, s, "dart_press", &[*q])?;
    }
    for (k, e) in p.edges.iter().enumerate() {
        e.check(s).map_err(|m| ctx.err(m))?;
        if let Some(j) = p.edges[..k].iter().position(|o| o.name == e.name) {
            return Err(ctx.err(format!("edge '{}': edge {j} has the same name", e.name)));
        }
    }
    Ok(())
}
