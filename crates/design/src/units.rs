//! Lengths mapped once: every point, vector and length of a parsed design carried through a
//! per-axis scale ([`Axes`]) — the file's units to millimetres at load, and a size of a grading
//! (the design scaled about the grading's origin, each axis by its own factor).
//!
//! Control-point surfaces and curves (Bézier, B-spline, NURBS, Hermite, and the Coons, Gordon,
//! ruled and developable surfaces built from such curves) are affine invariant: mapping their
//! points maps the shape exactly. An interpolating `spline` is rebuilt through the mapped
//! points, which under a scale that differs per axis is close to, not exactly, the mapped
//! curve (its chord-length parameters change). Exact primitives (sphere, cylinder, cone, torus,
//! arc) keep their kind only under a scale their symmetry allows; any other is refused by name.

use crate::{CurveDef, GrainDef, P3, PieceDef, SeamDef, SurfaceDef};

/// The map `p ↦ a ⊙ p + b` (⊙ per axis): a scale per axis about some point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Axes {
    /// Factor per axis (x, y, z); dimensionless.
    pub a: [f64; 3],
    /// Offset per axis after scaling (mm once loaded).
    pub b: [f64; 3],
}

impl Axes {
    /// The map that leaves every point where it is.
    pub const IDENTITY: Axes = Axes {
        a: [1.0; 3],
        b: [0.0; 3],
    };

    /// One factor on every axis about the origin (a unit conversion).
    pub fn uniform(s: f64) -> Axes {
        Axes {
            a: [s; 3],
            b: [0.0; 3],
        }
    }

    /// `scale` per axis about `origin`: `p ↦ origin + scale ⊙ (p − origin)`.
    pub fn about(origin: P3, scale: [f64; 3]) -> Axes {
        Axes {
            a: scale,
            b: [0, 1, 2].map(|k| origin[k] - scale[k] * origin[k]),
        }
    }

    /// This map, then `next`.
    pub fn then(&self, next: &Axes) -> Axes {
        Axes {
            a: [0, 1, 2].map(|k| next.a[k] * self.a[k]),
            b: [0, 1, 2].map(|k| next.a[k] * self.b[k] + next.b[k]),
        }
    }

    /// Whether the map moves nothing (every factor 1, every offset 0).
    pub fn is_identity(&self) -> bool {
        *self == Axes::IDENTITY
    }

    /// The image `a ⊙ p + b` of a point.
    pub fn point(&self, p: P3) -> P3 {
        [0, 1, 2].map(|k| self.a[k] * p[k] + self.b[k])
    }

    /// The image `a ⊙ v` of a vector (a difference of points: no offset).
    pub fn vector(&self, v: P3) -> P3 {
        [0, 1, 2].map(|k| self.a[k] * v[k])
    }

    fn same(x: f64, y: f64) -> bool {
        (x - y).abs() <= 1e-12 * x.abs().max(y.abs())
    }

    /// The one factor of the axes listed, if they share it.
    fn factor(&self, axes: &[usize]) -> Option<f64> {
        let f = self.a[axes[0]];
        axes.iter().all(|&k| Self::same(self.a[k], f)).then_some(f)
    }
}

pub(crate) fn map_point(p: &mut P3, m: &Axes) {
    *p = m.point(*p);
}

fn map_points(pts: &mut [P3], m: &Axes) {
    pts.iter_mut().for_each(|p| map_point(p, m));
}

/// The error of an exact primitive under a scale its symmetry does not allow.
fn not_kept(what: &str, need: &str) -> String {
    format!(
        "a {what} stays a {what} only when scaled {need}; give this size its own design (`design = \"file\"`)"
    )
}

fn map_curve(c: &mut CurveDef, m: &Axes) -> Result<(), String> {
    match c {
        CurveDef::Bezier { points }
        | CurveDef::Polyline { points }
        | CurveDef::Spline { points, .. }
        | CurveDef::Bspline { points, .. }
        | CurveDef::Nurbs { points, .. } => map_points(points, m),
        CurveDef::Hermite { p0, t0, p1, t1 } => {
            map_point(p0, m);
            map_point(p1, m);
            *t0 = m.vector(*t0);
            *t1 = m.vector(*t1);
        }
        CurveDef::Arc { center, radius, .. } => {
            let f = m
                .factor(&[0, 1, 2])
                .ok_or_else(|| not_kept("circular arc", "alike on every axis"))?;
            map_point(center, m);
            *radius *= f;
        }
    }
    Ok(())
}

/// `units`: the map converts the file's units (a STEP model states its own and is left alone).
fn map_surface(surf: &mut SurfaceDef, m: &Axes, units: bool) -> Result<(), String> {
    match surf {
        SurfaceDef::Bezier { points, .. }
        | SurfaceDef::Bspline { points, .. }
        | SurfaceDef::Nurbs { points, .. }
        | SurfaceDef::TriangularBezier { points, .. } => map_points(points, m),
        SurfaceDef::Hermite {
            corners,
            tangents_u,
            tangents_v,
            twists,
        } => {
            corners.iter_mut().flatten().for_each(|p| map_point(p, m));
            for a in [Some(tangents_u), Some(tangents_v), twists.as_mut()]
                .into_iter()
                .flatten()
            {
                a.iter_mut().flatten().for_each(|v| *v = m.vector(*v));
            }
        }
        SurfaceDef::Coons { v0, v1, u0, u1, .. } => {
            for c in [v0, v1, u0, u1] {
                map_curve(c, m)?;
            }
        }
        SurfaceDef::Gordon {
            u_curves, v_curves, ..
        } => {
            for c in u_curves.iter_mut().chain(v_curves.iter_mut()) {
                map_curve(c, m)?;
            }
        }
        SurfaceDef::Ruled { curves: c } | SurfaceDef::Developable { rails: c } => {
            for c in c.iter_mut() {
                map_curve(c, m)?;
            }
        }
        SurfaceDef::Sphere { center, radius } => {
            let f = m
                .factor(&[0, 1, 2])
                .ok_or_else(|| not_kept("sphere", "alike on every axis"))?;
            map_point(center, m);
            *radius *= f;
        }
        SurfaceDef::Cylinder {
            base,
            radius,
            height,
        } => {
            let f = m
                .factor(&[0, 1])
                .ok_or_else(|| not_kept("cylinder", "alike in x and y"))?;
            map_point(base, m);
            *radius *= f;
            *height *= m.a[2];
        }
        SurfaceDef::Cone {
            base,
            base_radius,
            top_radius,
            height,
        } => {
            let f = m
                .factor(&[0, 1])
                .ok_or_else(|| not_kept("cone", "alike in x and y"))?;
            map_point(base, m);
            *base_radius *= f;
            *top_radius *= f;
            *height *= m.a[2];
        }
        SurfaceDef::Torus {
            center,
            major,
            minor,
        } => {
            let f = m
                .factor(&[0, 1, 2])
                .ok_or_else(|| not_kept("torus", "alike on every axis"))?;
            map_point(center, m);
            *major *= f;
            *minor *= f;
        }
        SurfaceDef::Patches { patches } => {
            for p in patches {
                map_surface(p, m, units)?;
            }
        }
        // Mesh files are mapped when read (see `PieceDef::build`): they carry design units.
        SurfaceDef::Mesh { .. } => {}
        // A STEP file states its own unit; the model is converted to mm when read.
        SurfaceDef::Step { .. } if units => {}
        SurfaceDef::Step { .. } => {
            return Err(
                "a STEP model is read as it is and cannot be scaled; give this size its own design (`design = \"file\"`)"
                    .into(),
            );
        }
    }
    Ok(())
}

/// Maps every length of a piece (its surface, seams, marks, grain, no-cut regions, edges and
/// dart pressing point); mesh files are mapped when read. `units`: the map converts the file's
/// units.
pub(crate) fn map_piece(p: &mut PieceDef, m: &Axes, units: bool) -> Result<(), String> {
    map_surface(&mut p.surface, m, units)?;
    for seam in &mut p.seams {
        if let SeamDef::Points(pts) = seam {
            map_points(pts, m);
        }
    }
    for mk in &mut p.marks {
        map_points(&mut mk.points, m);
    }
    if let Some(g) = p.grain.as_mut().and_then(GrainDef::line_mut) {
        map_points(g, m);
    }
    for region in p.no_cut.iter_mut().chain(p.seam_hidden_regions.iter_mut()) {
        map_points(region, m);
    }
    for e in &mut p.edges {
        e.map(m);
    }
    if let Some(q) = p.dart_press.as_mut().and_then(|d| d.point_mut()) {
        map_point(q, m);
    }
    p.mesh_map = p.mesh_map.then(m);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scale_about_a_point_keeps_the_point_and_composes() {
        let g = Axes::about([10.0, 0.0, 5.0], [1.1, 0.9, 1.0]);
        assert_eq!(g.point([10.0, 0.0, 5.0]), [10.0, 0.0, 5.0]);
        assert_eq!(g.point([20.0, 10.0, 5.0]), [21.0, 9.0, 5.0]);
        let both = Axes::uniform(10.0).then(&g);
        let p = [2.0, 1.0, 0.5];
        let q = g.point(Axes::uniform(10.0).point(p));
        let r = both.point(p);
        for k in 0..3 {
            assert!((q[k] - r[k]).abs() < 1e-12);
        }
    }

    #[test]
    fn primitives_refuse_scales_that_would_change_their_kind() {
        let mut s = SurfaceDef::Cylinder {
            base: [0.0; 3],
            radius: 10.0,
            height: 50.0,
        };
        map_surface(&mut s, &Axes::about([0.0; 3], [2.0, 2.0, 3.0]), false).unwrap();
        assert_eq!(
            s,
            SurfaceDef::Cylinder {
                base: [0.0; 3],
                radius: 20.0,
                height: 150.0
            }
        );
        let e = map_surface(&mut s, &Axes::about([0.0; 3], [2.0, 1.0, 1.0]), false).unwrap_err();
        assert!(
            e.contains("cylinder") && e.contains("its own design"),
            "{e}"
        );
    }
}
