//! `inspect`: what a design or mesh file contains — per piece its area, bounding box, curvature
//! ranges (the extremes and the 1st–99th percentiles, which a pole or a spike does not set),
//! developability, patch, vertex and triangle counts.
//!
//! For parametric pieces area and mean Gaussian curvature are integrated on the exact surface
//! (Gauss–Legendre on a grid of cells), and curvature ranges are sampled at the tessellation's
//! vertices with the exact differential geometry; for mesh pieces they come from the discrete
//! estimates (angle defect, cotangent Laplacian).

use std::path::Path;

use flatcut_design::{Design, DesignError, PieceGeometry};
use flatcut_geom::{Aabb3, DVec3, Tolerances};
use flatcut_mesh::{MeshStats, TriMesh};
use flatcut_surface::diffgeom::{self, FundamentalForms};
use flatcut_surface::{DomainKind, ParamSurface};
use serde::Serialize;

pub use crate::inspect_figures::{
    DEVELOPABLE_ANGLE_DEFECT, DEVELOPABLE_SCALED_K, PieceSummary, Range2, Range3, forms_at, p1_p99,
    percentiles_text,
};

/// Grid of sample cells per patch side for curvature extremes and the developability test.
const SAMPLES_PER_SIDE: usize = 24;
/// Quadrature cells per patch side (each with a 16×16 Gauss–Legendre rule).
const QUAD_CELLS: usize = 6;

#[derive(Clone, Debug, PartialEq, Serialize)]
/// What `inspect --json` reports for a design or mesh file (keys are a stable contract).
pub struct InspectReport {
    /// The file inspected.
    pub source: String,
    /// One summary per piece, in the design's order.
    pub pieces: Vec<PieceSummary>,
    /// For a STEP file: its unit, shells, faces and edges (keys `unit`, `schemas`, `shells`,
    /// `faces`, `edges` beside `pieces`).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub step: Option<crate::inspect_step::StepSummary>,
}

/// Loads a design or mesh file and summarises every piece (a part's too: the regions between its
/// style lines).
pub fn inspect_file(path: &Path, tol: &Tolerances) -> Result<InspectReport, DesignError> {
    let design = Design::load(path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let mut pieces = Vec::new();
    for def in &design.pieces {
        let geom = def.build(base)?;
        let mesh = def.mesh(base, tol)?;
        pieces.push(match &geom {
            PieceGeometry::Step(sp) => {
                crate::inspect_step::summarise_piece(&def.name, def.quantity, sp, &mesh, tol)
            }
            g => summarise(&def.name, def.quantity, g, &mesh),
        });
    }
    if !design.parts.is_empty() {
        // A part's pieces are regions of its surface: summarised as the meshes they are.
        let asm = design.assemble(base, tol)?;
        for p in asm.pieces.iter().filter(|p| p.part.is_some()) {
            let geom = PieceGeometry::Mesh(p.mesh.clone());
            pieces.push(summarise(&p.def.name, p.def.quantity, &geom, &p.mesh));
        }
    }
    // A STEP file: the model the pieces were expanded from.
    let step = design.pieces.iter().find_map(|p| match &p.surface {
        flatcut_design::SurfaceDef::Step { model: Some(m), .. }
            if flatcut_step::is_step_path(path) =>
        {
            let model =
                m.0.model_for(tol.heal_mm)
                    .unwrap_or_else(|_| m.0.model.clone());
            Some(crate::inspect_step::summarise_model(&model, tol))
        }
        _ => None,
    });
    Ok(InspectReport {
        source: design.source.clone(),
        pieces,
        step,
    })
}

fn bbox_arr(b: &Aabb3) -> [[f64; 3]; 2] {
    [b.min.to_array(), b.max.to_array()]
}

/// The summary of one built piece and its mesh.
pub fn summarise(name: &str, quantity: u32, geom: &PieceGeometry, mesh: &TriMesh) -> PieceSummary {
    let stats = MeshStats::of(mesh);
    match geom {
        PieceGeometry::Step(sp) => {
            crate::inspect_step::summarise_piece(name, quantity, sp, mesh, &Tolerances::DEFAULT)
        }
        PieceGeometry::Mesh(_) => summarise_mesh(name, quantity, mesh, &stats),
        PieceGeometry::Patches(patches) => summarise_patches(name, quantity, patches, mesh, &stats),
    }
}

/// The summary of a mesh piece: discrete curvature estimates at its interior vertices.
fn summarise_mesh(name: &str, quantity: u32, mesh: &TriMesh, stats: &MeshStats) -> PieceSummary {
    let worst_defect = max_interior_angle_defect(mesh);
    let (kmin, kmax) = stats.gaussian_range.unwrap_or((0.0, 0.0));
    let (hmin, hmax) = stats.mean_range.unwrap_or((0.0, 0.0));
    let interior = |v: Vec<Option<f64>>| v.into_iter().flatten().collect::<Vec<f64>>();
    let ks = interior(flatcut_mesh::stats::gaussian_curvature(mesh));
    let hs = interior(flatcut_mesh::stats::mean_curvature(mesh));
    let kmean = if stats.area > 0.0 {
        stats.total_angle_defect / stats.area
    } else {
        0.0
    };
    PieceSummary {
        name: name.to_string(),
        kind: "mesh",
        quantity,
        area_mm2: stats.area,
        bbox_mm: bbox_arr(&stats.bbox),
        gaussian_curvature: Range3 {
            min: kmin,
            max: kmax,
            mean: kmean,
            p1_p99: p1_p99(&ks),
        },
        mean_curvature: Range2 {
            min: hmin,
            max: hmax,
            p1_p99: p1_p99(&hs),
        },
        developable: worst_defect < DEVELOPABLE_ANGLE_DEFECT,
        developability_measure: worst_defect,
        patches: 0,
        vertices: stats.vertices,
        triangles: stats.triangles,
        boundary_loops: stats.boundary_loops,
        boundary_length_mm: stats.boundary_length,
    }
}

/// The summary of a parametric piece: area and mean curvature integrated on the exact surface,
/// curvature ranges sampled on a grid of each patch.
fn summarise_patches(
    name: &str,
    quantity: u32,
    patches: &[std::sync::Arc<dyn ParamSurface>],
    mesh: &TriMesh,
    stats: &MeshStats,
) -> PieceSummary {
    let (mut area, mut total_k) = (0.0, 0.0);
    let (mut kmin, mut kmax, mut hmin, mut hmax) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    let mut worst_scaled: f64 = 0.0;
    let mut bbox = Aabb3::EMPTY;
    let (mut ks, mut hs) = (Vec::new(), Vec::new());
    for p in patches {
        let (a, k) = integrate_area_and_curvature(p.as_ref());
        area += a;
        total_k += k;
        worst_scaled =
            worst_scaled.max(diffgeom::developability(p.as_ref(), SAMPLES_PER_SIDE).max_scaled_k);
        for_each_sample(p.as_ref(), SAMPLES_PER_SIDE, |pt, ff| {
            bbox.add(pt);
            if let Some(ff) = ff {
                let (k, h) = (ff.gaussian(), ff.mean());
                kmin = kmin.min(k);
                kmax = kmax.max(k);
                hmin = hmin.min(h);
                hmax = hmax.max(h);
                ks.push(k);
                hs.push(h);
            }
        });
    }
    // The tessellation's vertices lie on the surface: they complete the bounding box.
    bbox = bbox.union(&mesh.bbox());
    let fin = |v: f64| if v.is_finite() { v } else { 0.0 };
    PieceSummary {
        name: name.to_string(),
        kind: "patches",
        quantity,
        area_mm2: area,
        bbox_mm: bbox_arr(&bbox),
        gaussian_curvature: Range3 {
            min: fin(kmin),
            max: fin(kmax),
            mean: if area > 0.0 { total_k / area } else { 0.0 },
            p1_p99: p1_p99(&ks),
        },
        mean_curvature: Range2 {
            min: fin(hmin),
            max: fin(hmax),
            p1_p99: p1_p99(&hs),
        },
        developable: worst_scaled < DEVELOPABLE_SCALED_K,
        developability_measure: worst_scaled,
        patches: patches.len(),
        vertices: stats.vertices,
        triangles: stats.triangles,
        boundary_loops: stats.boundary_loops,
        boundary_length_mm: stats.boundary_length,
    }
}

/// The largest |2π − Σ angles| over interior vertices (rad): zero for a polyhedral developable.
fn max_interior_angle_defect(mesh: &TriMesh) -> f64 {
    let bnd = flatcut_mesh::stats::boundary_vertices(mesh);
    let mut sum = vec![0.0f64; mesh.positions.len()];
    let mut used = vec![false; mesh.positions.len()];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let p = mesh.corners(t);
        for k in 0..3 {
            sum[tri[k] as usize] += (p[(k + 1) % 3] - p[k]).angle_between(p[(k + 2) % 3] - p[k]);
            used[tri[k] as usize] = true;
        }
    }
    (0..sum.len())
        .filter(|&v| used[v] && !bnd[v])
        .map(|v| (std::f64::consts::TAU - sum[v]).abs())
        .filter(|d| d.is_finite())
        .fold(0.0, f64::max)
}

/// Visits an (n+1)×(n+1) grid of the patch's domain (the lower-left triangle for triangular
/// patches) with the point and the fundamental forms (their limit at a pole, see [`forms_at`]).
fn for_each_sample(
    s: &dyn ParamSurface,
    n: usize,
    mut f: impl FnMut(DVec3, Option<FundamentalForms>),
) {
    let d = s.domain();
    let tri = s.domain_kind() == DomainKind::Triangle;
    for i in 0..=n {
        for j in 0..=n {
            let (a, b) = (i as f64 / n as f64, j as f64 / n as f64);
            if tri && a + b > 1.0 + 1e-12 {
                continue;
            }
            let (u, v) = (d.u.0 + a * (d.u.1 - d.u.0), d.v.0 + b * (d.v.1 - d.v.0));
            f(s.eval(u, v), forms_at(s, u, v));
        }
    }
}

/// ∬ √(EG − F²) du dv and ∬ K √(EG − F²) du dv over the patch's domain.
fn integrate_area_and_curvature(s: &dyn ParamSurface) -> (f64, f64) {
    let d = s.domain();
    let tri = s.domain_kind() == DomainKind::Triangle;
    let (du, dv) = (
        (d.u.1 - d.u.0) / QUAD_CELLS as f64,
        (d.v.1 - d.v.0) / QUAD_CELLS as f64,
    );
    let (mut area, mut curv) = (0.0, 0.0);
    for i in 0..QUAD_CELLS {
        for j in 0..QUAD_CELLS {
            let (u0, v0) = (d.u.0 + i as f64 * du, d.v.0 + j as f64 * dv);
            let cell = |g: &mut dyn FnMut(f64, f64) -> f64| {
                flatcut_geom::num::gauss16(
                    |u| flatcut_geom::num::gauss16(|v| g(u, v), v0, v0 + dv),
                    u0,
                    u0 + du,
                )
            };
            if tri {
                // Map the cell of the unit square onto the triangle by the Duffy transform
                // (u, v) = (a, (1 − a) b), Jacobian (1 − a).
                area += cell(&mut |a, b| {
                    let (u, v) = (a, (1.0 - a) * b);
                    let dd = s.deriv2(u, v);
                    dd.su.cross(dd.sv).length() * (1.0 - a)
                });
                curv += cell(&mut |a, b| {
                    let (u, v) = (a, (1.0 - a) * b);
                    let dd = s.deriv2(u, v);
                    FundamentalForms::from_derivs(&dd).map_or(0.0, |ff| ff.gaussian())
                        * dd.su.cross(dd.sv).length()
                        * (1.0 - a)
                });
            } else {
                area += cell(&mut |u, v| {
                    let (_, su, sv) = s.deriv1(u, v);
                    su.cross(sv).length()
                });
                curv += cell(&mut |u, v| {
                    let dd = s.deriv2(u, v);
                    FundamentalForms::from_derivs(&dd).map_or(0.0, |ff| ff.gaussian())
                        * dd.su.cross(dd.sv).length()
                });
            }
        }
    }
    (area, curv)
}

impl std::fmt::Display for InspectReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "{}: {} piece(s)", self.source, self.pieces.len())?;
        for p in &self.pieces {
            let [lo, hi] = p.bbox_mm;
            writeln!(f)?;
            writeln!(f, "piece {} ({}, quantity {})", p.name, p.kind, p.quantity)?;
            writeln!(f, "  area              {:.3} mm²", p.area_mm2)?;
            writeln!(
                f,
                "  bounding box      {:.3} × {:.3} × {:.3} mm",
                hi[0] - lo[0],
                hi[1] - lo[1],
                hi[2] - lo[2]
            )?;
            writeln!(
                f,
                "  Gaussian K        {:.4e} .. {:.4e} 1/mm²{} (area mean {:.4e})",
                p.gaussian_curvature.min,
                p.gaussian_curvature.max,
                percentiles_text(p.gaussian_curvature.p1_p99),
                p.gaussian_curvature.mean
            )?;
            writeln!(
                f,
                "  mean H            {:.4e} .. {:.4e} 1/mm{}",
                p.mean_curvature.min,
                p.mean_curvature.max,
                percentiles_text(p.mean_curvature.p1_p99)
            )?;
            writeln!(
                f,
                "  developable       {} (measure {:.2e})",
                if p.developable { "yes" } else { "no" },
                p.developability_measure
            )?;
            if p.patches > 0 {
                writeln!(f, "  patches           {}", p.patches)?;
            }
            writeln!(
                f,
                "  mesh              {} vertices, {} triangles",
                p.vertices, p.triangles
            )?;
            match p.boundary_loops {
                Some(n) => writeln!(
                    f,
                    "  boundary          {n} loop(s), {:.3} mm",
                    p.boundary_length_mm
                )?,
                None => writeln!(f, "  boundary          invalid topology")?,
            }
        }
        if let Some(step) = &self.step {
            write!(f, "{step}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_surface::patch::BezierPatch;

    const MM: f64 = 25.4;

    fn teapot_patches() -> Vec<std::sync::Arc<dyn ParamSurface>> {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../patterns/teapot");
        let design = Design::load(&dir.join("design.toml")).unwrap();
        match design.pieces[0].build(&dir).unwrap() {
            PieceGeometry::Patches(p) => p,
            _ => panic!("the teapot is a patch list"),
        }
    }

    #[test]
    fn curvature_at_the_bottom_pole_is_the_limit_of_the_surface_of_revolution() {
        // Bottom patch (data-set patch 28): near the centre z = a·r² with, from the control
        // net, r ≈ 3·1.425·u and z ≈ 3·0.075·u², so both principal curvatures are 2a.
        let row = |r: f64, z: f64| {
            [
                DVec3::new(r, 0.0, z),
                DVec3::new(r, 0.56 * r, z),
                DVec3::new(0.56 * r, r, z),
                DVec3::new(0.0, r, z),
            ]
        };
        let mut pts = vec![DVec3::ZERO; 4];
        pts.extend(row(1.425, 0.0));
        pts.extend(row(1.5, 0.075));
        pts.extend(row(1.5, 0.15));
        let pts = pts.into_iter().map(|p| p * MM).collect();
        let s = BezierPatch::new(3, 3, pts).unwrap();
        let a = 3.0 * 0.075 / (3.0f64 * 1.425).powi(2) / MM;
        let ff = forms_at(&s, 0.0, 0.37).unwrap();
        let k = ff.gaussian();
        assert!(
            ((k - 4.0 * a * a) / (4.0 * a * a)).abs() < 1e-2,
            "{k} vs {}",
            4.0 * a * a
        );
        // Another meridian gives nearly the same limit: a Bézier pole patch is not exactly C² at
        // its pole (the quarter circle is not a circle), so the limit moves by a few percent.
        let k2 = forms_at(&s, 0.0, 0.9).unwrap().gaussian();
        assert!(((k2 - k) / k).abs() < 5e-2, "{k2} vs {k}");
        let near = FundamentalForms::from_derivs(&s.deriv2(1e-3, 0.5))
            .unwrap()
            .gaussian();
        assert!(((near - k) / k).abs() < 1e-2, "{near} vs {k}");
    }

    #[test]
    fn one_spike_sets_the_extremes_but_not_the_percentiles_of_a_plane() {
        // A 40 × 40 grid of the plane z = 0 with one vertex lifted by 5 mm: the spike and its
        // six neighbours are curved, the other 1,514 interior vertices are flat (K = H = 0).
        let mesh = flatcut_mesh::test_grid::grid_mesh(40, 40, |i, j| {
            let z = if (i, j) == (20, 20) { 5.0 } else { 0.0 };
            DVec3::new(i as f64, j as f64, z)
        });
        let sum = summarise("spike", 1, &PieceGeometry::Mesh(mesh.clone()), &mesh);
        let (k, h) = (&sum.gaussian_curvature, &sum.mean_curvature);
        assert!(k.max > 0.1 && k.min < -0.01, "{k:?}");
        assert!(h.max.abs().max(h.min.abs()) > 0.1, "{h:?}");
        // Flat up to the rounding of the angle sums (2π − Σ angles ~ 1e-15).
        for [lo, hi] in [k.p1_p99.unwrap(), h.p1_p99.unwrap()] {
            assert!(lo.abs() < 1e-12 && hi.abs() < 1e-12, "{lo} {hi}");
        }
        let text = InspectReport {
            source: "spike".into(),
            pieces: vec![sum],
            step: None,
        }
        .to_string();
        assert!(text.contains("1/mm² (1st–99th percentile "), "{text}");
    }

    #[test]
    fn teapot_curvature_range_matches_sampling_away_from_the_poles() {
        let patches = teapot_patches();
        // Reference: a finer grid that keeps 1e-3 of the domain away from every side.
        let (mut rmin, mut rmax) = (f64::INFINITY, f64::NEG_INFINITY);
        let n = 60;
        for p in &patches {
            for i in 0..=n {
                for j in 0..=n {
                    let u = 1e-3 + (1.0 - 2e-3) * i as f64 / n as f64;
                    let v = 1e-3 + (1.0 - 2e-3) * j as f64 / n as f64;
                    if let Some(ff) = FundamentalForms::from_derivs(&p.deriv2(u, v)) {
                        rmin = rmin.min(ff.gaussian());
                        rmax = rmax.max(ff.gaussian());
                    }
                }
            }
        }
        let mesh = TriMesh::new(Vec::new(), Vec::new());
        let sum = summarise("teapot", 1, &PieceGeometry::Patches(patches), &mesh);
        let k = &sum.gaussian_curvature;
        eprintln!("K {} .. {} (reference {rmin} .. {rmax})", k.min, k.max);
        assert!(k.min.is_finite() && k.max.is_finite());
        // The pole samples no longer blow up: within 10 % of the reference extremes.
        assert!(
            k.min >= 1.1 * rmin && k.max <= 1.1 * rmax,
            "{} .. {}",
            k.min,
            k.max
        );
        assert!(k.min < 0.0 && k.max > 0.0);
    }
}
