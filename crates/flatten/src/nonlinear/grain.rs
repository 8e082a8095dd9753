//! The orthotropic flattening (`--method orthotropic`): where the grain runs on every triangle,
//! the solve of [`Orthotropic`] from the isometric map, and `grain = "auto"`.
//!
//! The warp is a straight thread of the cut piece: a direction u of the pattern plane. On the
//! surface it runs along J⁻¹u in each triangle (J: the triangle's map), so the solve starts from
//! the isometric (δ2) map, takes each triangle's warp from it ([`grain_frames`]) and minimises
//! the orthotropic energy; the warp directions are then taken again from that result and the
//! energy minimised once more, so the frames agree with the map they measure to the order of
//! its strain. The result is turned so that the warp runs along +x (the pattern's grain line).
//!
//! `Grain::Auto` samples [`AUTO_SAMPLES`] warp angles over half a turn (a thread has no sign),
//! then narrows the best bracket by golden-section search to [`AUTO_TOLERANCE_RAD`]; each angle
//! is scored by the largest excess over the material's limits of any triangle's warp, weft or
//! bias strain (the energy when no limits are given). Deterministic: fixed samples, fixed
//! order, ties to the smaller angle.

use flatcut_geom::{DVec2, DVec3};
use flatcut_mesh::TriMesh;
use flatcut_mesh::grain_strain::{
    GrainStrain, grain_strain_of, pattern_direction_near, warp_in_frame,
};

use super::kernel::RestTri;
use super::newton::{Budget, EarlyStop};
use super::orthotropic::{Orthotropic, grain_frames};
use super::{isometric_run, newton_solve, time_limit_warning};
use crate::anisotropy::{Anisotropy, DirectionalLimits, Grain, grain_dir};
use crate::{FlattenError, FlattenInfo, FlattenParams, Flattening, Method};

/// Warp angles sampled over [0, π) before the golden-section search of `Grain::Auto`.
pub const AUTO_SAMPLES: usize = 12;
/// Width of the angle bracket (radians, ≈ 0.25°) at which the golden-section search stops.
pub const AUTO_TOLERANCE_RAD: f64 = 0.0044;
/// Passes of "warp from the map, then solve" (see the module's documentation).
const FRAME_PASSES: usize = 2;

/// The orthotropic flattening of `mesh` with `params.anisotropy`, the warp along +x.
pub(crate) fn orthotropic(
    mesh: &TriMesh,
    rest: &[RestTri],
    x0: Vec<DVec2>,
    params: &FlattenParams,
    budget: &Budget,
) -> Result<Flattening, FlattenError> {
    let aniso = params.anisotropy.ok_or_else(|| {
        FlattenError::Anisotropy(
            "the orthotropic method needs a material (stiffness and grain)".into(),
        )
    })?;
    aniso
        .stiffness
        .validate()
        .map_err(FlattenError::Anisotropy)?;
    let n = mesh.positions.len();
    let start_stage = budget.next("isometric start", params.time_limit);
    let iso = isometric_run(rest, n, x0, params, Method::Orthotropic, &start_stage)?;
    let mut iterations = iso.iterations;
    let mut early = iso.early;
    let start = iso.x;
    // The grain's search and the solves along the chosen grain: one stage.
    let stage = budget.next("orthotropic", params.time_limit);
    let solve = |from: &[DVec2], u: DVec2, passes: usize, b: &Budget| {
        solve_with_grain(rest, n, &aniso, from, u, passes, params, b)
    };
    let best = match aniso.grain {
        Grain::Angle(a) => solve(&start, grain_dir(a), FRAME_PASSES, &stage)?,
        Grain::Line(l) => solve(
            &start,
            grain_dir(line_angle(mesh, &start, l)?),
            FRAME_PASSES,
            &stage,
        )?,
        Grain::Auto => {
            let score = |s: &Solved| match &aniso.limits {
                Some(l) => limit_excess(rest, &s.x, s.warp, l),
                None => s.energy,
            };
            // Angles are compared after one pass; the chosen one gets the others from its map.
            let first = search_angle(&stage, |a, b| {
                solve(&start, grain_dir(a), 1, b).map(|s| (score(&s), s))
            })?
            .1;
            let rest_passes = solve(&first.x, first.warp, FRAME_PASSES - 1, &stage)?;
            iterations += first.iterations;
            early = early.or(first.early);
            rest_passes
        }
    };
    iterations += best.iterations;
    early = early.or(best.early);
    let mut x = best.x;
    turn_warp_to_x(&mut x, best.warp);
    let mut warnings = Vec::new();
    if early == Some(EarlyStop::TimeLimit) {
        warnings.push(time_limit_warning(Method::Orthotropic, iterations));
    }
    Ok(Flattening {
        info: FlattenInfo {
            iterations: start_stage.used() + stage.used(),
            final_energy: best.energy / super::total_area(rest),
            warnings,
            stages: vec![start_stage.count(), stage.count()],
            ..Default::default()
        },
        uv: x,
    })
}

/// One orthotropic solve: the map, its energy, the pattern direction of its warp.
struct Solved {
    x: Vec<DVec2>,
    energy: f64,
    warp: DVec2,
    iterations: usize,
    early: Option<EarlyStop>,
}

/// Solves the orthotropic energy from the map `start` with the warp along `u` there, taking the
/// warp from the map and solving again `passes` times.
fn solve_with_grain(
    rest: &[RestTri],
    n: usize,
    aniso: &Anisotropy,
    start: &[DVec2],
    u: DVec2,
    passes: usize,
    params: &FlattenParams,
    budget: &Budget,
) -> Result<Solved, FlattenError> {
    let energy = Orthotropic::new(aniso.stiffness);
    let (mut x, mut u, mut iterations, mut early, mut e) =
        (start.to_vec(), u, 0, None, f64::INFINITY);
    for _ in 0..passes {
        let warp = warps(rest, &x, u)?;
        let frames = grain_frames(rest, &warp);
        let run = newton_solve(
            &frames,
            n,
            energy,
            super::newton::to_flat(&x),
            params,
            Method::Orthotropic,
            budget,
        )?;
        iterations += run.iterations;
        early = early.or(run.early);
        e = run.energy;
        u = mean_image(&frames, &run.x);
        x = run.x;
    }
    Ok(Solved {
        x,
        energy: e,
        warp: u,
        iterations,
        early,
    })
}

/// Each triangle's warp in its rest frame for the pattern grain `u` of map `x`.
fn warps(rest: &[RestTri], x: &[DVec2], u: DVec2) -> Result<Vec<DVec2>, FlattenError> {
    rest.iter()
        .enumerate()
        .map(|(t, r)| {
            warp_in_frame(r.jacobian(x), u).ok_or_else(|| FlattenError::NoConvergence {
                method: Method::Orthotropic,
                reason: format!("triangle {t} is degenerate in the map the grain is taken from"),
            })
        })
        .collect()
}

/// The area-weighted mean direction of the images of the frames' x axes (the warp) in map `x`.
fn mean_image(frames: &[RestTri], x: &[DVec2]) -> DVec2 {
    let s: DVec2 = frames
        .iter()
        .map(|r| r.area * r.jacobian(x).x_axis.normalize_or_zero())
        .sum();
    s.normalize_or(DVec2::X)
}

/// The pattern angle of the grain line `[a, b]` in map `x`, measured where it is drawn.
fn line_angle(mesh: &TriMesh, x: &[DVec2], [a, b]: [DVec3; 2]) -> Result<f64, FlattenError> {
    let d = b - a;
    let u = pattern_direction_near(mesh, x, d, 0.5 * (a + b), d.length()).ok_or_else(|| {
        FlattenError::Anisotropy(format!(
            "the grain line from ({}, {}, {}) to ({}, {}, {}) is normal to the surface where it is drawn",
            a.x, a.y, a.z, b.x, b.y, b.z
        ))
    })?;
    Ok(u.y.atan2(u.x))
}

/// Turns the map about the origin so that the pattern direction `u` becomes +x.
fn turn_warp_to_x(x: &mut [DVec2], u: DVec2) {
    let rot = flatcut_geom::DMat2::from_angle(-u.y.atan2(u.x));
    for p in x.iter_mut() {
        *p = rot * *p;
    }
}

/// The strain of every triangle of map `x` in the material's directions for the grain `u`.
pub fn grain_strains(rest: &[RestTri], x: &[DVec2], u: DVec2) -> Vec<Option<GrainStrain>> {
    rest.iter()
        .map(|r| grain_strain_of(r.jacobian(x), u))
        .collect()
}

/// The largest excess (percentage points) of any triangle's warp, weft or bias strain over the
/// limits; negative when every triangle is within them (by the smallest margin).
pub fn limit_excess(rest: &[RestTri], x: &[DVec2], u: DVec2, l: &DirectionalLimits) -> f64 {
    grain_strains(rest, x, u)
        .iter()
        .map(|g| match g {
            Some(g) => g.excess(l),
            None => f64::INFINITY,
        })
        .fold(f64::NEG_INFINITY, f64::max)
}

/// Minimises `f` over angles in [0, π): [`AUTO_SAMPLES`] samples, then golden-section search in
/// the bracket around the best sample. Returns the best angle's score and value. The samples,
/// and the bracket's first two points, are independent solves: they run side by side (the
/// 20k-face hemisphere in woven cotton: 71.9 s instead of 89.8 s on two cores), each on
/// `budget` as if one after the other ([`Budget::map_in_order`]), and are compared in the order
/// of the sequential search, so the answer is the same.
pub fn search_angle<T: Send, E: Send>(
    budget: &Budget,
    f: impl Fn(f64, &Budget) -> Result<(f64, T), E> + Sync,
) -> Result<(f64, T), E> {
    let step = std::f64::consts::PI / AUTO_SAMPLES as f64;
    let angles: Vec<f64> = (0..AUTO_SAMPLES).map(|i| i as f64 * step).collect();
    let samples: Vec<Result<(f64, T), E>> = budget.map_in_order(&angles, |&a, b| f(a, b));
    let mut best: Option<(f64, f64, T)> = None;
    for (i, r) in samples.into_iter().enumerate() {
        let (s, v) = r?;
        if best.as_ref().is_none_or(|b| s < b.1) {
            best = Some((i as f64 * step, s, v));
        }
    }
    let Some(mut best) = best else {
        unreachable!("AUTO_SAMPLES is not zero")
    };
    let a0 = best.0;
    let inv_phi = (5f64.sqrt() - 1.0) / 2.0;
    let (mut lo, mut hi) = (a0 - step, a0 + step);
    let mut c = hi - inv_phi * (hi - lo);
    let mut d = lo + inv_phi * (hi - lo);
    let mut pair = budget.map_in_order(&[c, d], |&a, b| f(a, b)).into_iter();
    let (Some(rc), Some(rd)) = (pair.next(), pair.next()) else {
        unreachable!("two angles give two results")
    };
    let ((mut fc, vc), (mut fd, vd)) = (rc?, rd?);
    for (a, s, v) in [(c, fc, vc), (d, fd, vd)] {
        if s < best.1 {
            best = (a, s, v);
        }
    }
    while hi - lo > AUTO_TOLERANCE_RAD {
        let next = if fc <= fd {
            hi = d;
            d = c;
            fd = fc;
            c = hi - inv_phi * (hi - lo);
            c
        } else {
            lo = c;
            c = d;
            fc = fd;
            d = lo + inv_phi * (hi - lo);
            d
        };
        let (s, v) = f(next, budget)?;
        if next == c {
            fc = s;
        } else {
            fd = s;
        }
        if s < best.1 {
            best = (next, s, v);
        }
    }
    Ok((best.1, best.2))
}
