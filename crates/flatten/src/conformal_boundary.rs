//! Duncan's f2: a conformal map that is locally isometric along the boundary, computed the
//! boundary-first-flattening way (Sawhney & Crane 2017) with zero boundary scale factors.
//!
//! 1. Solve the discrete Yamabe equation `Δu = K` for the log scale factor `u = log σ`, with
//!    `u = 0` on the boundary: `L u = −Ω` at interior vertices (`L` the positive semi-definite
//!    cotangent Laplacian, `Ω` the angle defects). The metric `e^{2u} g` is flat.
//! 2. The boundary curvature of the flat metric is `κ̃ = κ + (L u)_B` (`κ` = π − angle sum at a
//!    boundary vertex); its sum is exactly 2π by discrete Gauss–Bonnet. Boundary edges keep
//!    their 3D lengths since `u = 0` there.
//! 3. Integrate the boundary polygon from these turning angles and lengths. Discretisation
//!    leaves a small gap; it is closed by the smallest change of the lengths in the norm
//!    `Σ (l̃ − l)²/l` (BFF's closing step).
//! 4. Extend the boundary harmonically (cotangent weights) into the interior: conformal maps are
//!    harmonic, so this reproduces the conformal map up to discretisation.
//!
//! The result is at true scale with no rescaling: the boundary has its 3D length. The image
//! boundary may self-overlap on strongly curved pieces (Duncan's caveat); flips are reported as
//! warnings, not hidden.

use crate::internal::InternalError;
use flatcut_geom::DVec2;
use flatcut_mesh::{Topology, TriMesh};

use crate::ops::{
    angle_sums, boundary_mask, corner_angles, corner_cotans, count_flips, fit_rigid_to_pins,
    laplace, mean_delta2, used_mask,
};
use crate::{FlattenError, FlattenInfo, FlattenParams, Flattening, Method};

/// Log scale factors `u = log σ` of the flat conformal metric with `u = 0` on the boundary.
pub fn log_scale_factors(mesh: &TriMesh, topo: &Topology) -> Result<Vec<f64>, FlattenError> {
    let n = mesh.positions.len();
    let sums = angle_sums(mesh, &corner_angles(mesh));
    let bnd = boundary_mask(n, topo);
    let used = used_mask(mesh);
    let fixed: Vec<bool> = (0..n).map(|v| bnd[v] || !used[v]).collect();
    let mut u = vec![vec![0.0; n]];
    if fixed.iter().all(|&f| f) {
        return Ok(u.pop().unwrap_or_default());
    }
    let w = half_cotans(mesh);
    let sys = laplace(
        &mesh.triangles,
        &w,
        &fixed,
        "conformal-boundary: Yamabe equation",
    )?;
    // L u = −Ω with Ω = 2π − angle sum at the free (interior) vertices.
    let source: Vec<f64> = sums.iter().map(|s| s - std::f64::consts::TAU).collect();
    sys.solve(&mut u, Some(&[source]))?;
    Ok(u.pop().unwrap_or_default())
}

/// Cotangent Laplacian weights per corner: `L_ab = −½(cot α + cot β)`.
fn half_cotans(mesh: &TriMesh) -> Vec<[f64; 3]> {
    corner_cotans(&mesh.positions, &mesh.triangles)
        .into_iter()
        .map(|c| c.map(|x| 0.5 * x))
        .collect()
}

/// How the boundary polygon integrated from the flat metric's turning angles is closed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Closing {
    /// BFF's step: the smallest change of the edge lengths (the turns kept).
    Lengths,
    /// The smallest change of the turning angles, every edge at its 3D length: the outline
    /// Duncan's f1 holds ([`crate::nonlinear::boundary`]).
    Turns,
}

/// The conformal map with an isometric boundary (steps 2–4 of the module docs) of the log
/// scale factors `u` ([`log_scale_factors`]), its boundary closed as `closing` says. No pins
/// are applied.
pub fn conformal_map(
    mesh: &TriMesh,
    topo: &Topology,
    u: &[f64],
    closing: Closing,
) -> Result<Vec<DVec2>, FlattenError> {
    let n = mesh.positions.len();
    let lp = topo.boundary_loops.first().ok_or(FlattenError::Internal(
        InternalError::ConformalBoundaryNoLoop,
    ))?;
    let sums = angle_sums(mesh, &corner_angles(mesh));
    let w = half_cotans(mesh);
    // (L u) at every vertex.
    let mut lu = vec![0.0; n];
    for (tri, wt) in mesh.triangles.iter().zip(&w) {
        for k in 0..3 {
            let (a, b) = (tri[(k + 1) % 3] as usize, tri[(k + 2) % 3] as usize);
            let d = wt[k] * (u[a] - u[b]);
            lu[a] += d;
            lu[b] -= d;
        }
    }
    let m = lp.len();
    let turn: Vec<f64> = lp
        .iter()
        .map(|&v| std::f64::consts::PI - sums[v as usize] + lu[v as usize])
        .collect();
    let len: Vec<f64> = (0..m)
        .map(|i| {
            (mesh.positions[lp[(i + 1) % m] as usize] - mesh.positions[lp[i] as usize]).length()
        })
        .collect();
    let (closed, tangents) = match closing {
        Closing::Lengths => {
            let t = tangents(&turn);
            (close_lengths(&len, &t)?, t)
        }
        Closing::Turns => (len.clone(), tangents(&close_turns(&len, &turn)?)),
    };
    let mut gamma = Vec::with_capacity(m);
    let mut p = DVec2::ZERO;
    for i in 0..m {
        gamma.push(p);
        p += closed[i] * tangents[i];
    }
    // Harmonic extension of both coordinates.
    let used = used_mask(mesh);
    let bnd = boundary_mask(n, topo);
    let fixed: Vec<bool> = (0..n).map(|v| bnd[v] || !used[v]).collect();
    let mut x = vec![0.0; n];
    let mut y = vec![0.0; n];
    for (i, &v) in lp.iter().enumerate() {
        x[v as usize] = gamma[i].x;
        y[v as usize] = gamma[i].y;
    }
    let mut fields = vec![x, y];
    if !fixed.iter().all(|&f| f) {
        let sys = laplace(
            &mesh.triangles,
            &w,
            &fixed,
            "conformal-boundary: harmonic extension",
        )?;
        sys.solve(&mut fields, None)?;
    }
    Ok(fields[0]
        .iter()
        .zip(&fields[1])
        .map(|(&x, &y)| DVec2::new(x, y))
        .collect())
}

/// Tangent of each boundary edge i (from `lp[i]` to `lp[i + 1]`): the turns at `lp[1..=i]`
/// accumulated (edge 0 along +x).
fn tangents(turn: &[f64]) -> Vec<DVec2> {
    let mut phi = 0.0;
    (0..turn.len())
        .map(|i| {
            if i > 0 {
                phi += turn[i];
            }
            DVec2::from_angle(phi)
        })
        .collect()
}

/// Flattens the disk `mesh` conformally with an isometric boundary (see the module docs).
/// Pins are met by the best rigid motion (the map has no other freedom); a pin that cannot be
/// met is a warning.
pub fn conformal_boundary(
    mesh: &TriMesh,
    topo: &Topology,
    params: &FlattenParams,
) -> Result<Flattening, FlattenError> {
    let u = log_scale_factors(mesh, topo)?;
    let mut uv = conformal_map(mesh, topo, &u, Closing::Lengths)?;
    let mut warnings = Vec::new();
    let flips = count_flips(&mesh.triangles, &uv);
    if flips > 0 {
        warnings.push(format!(
            "conformal-boundary: {flips} triangle(s) flipped by the harmonic extension; the isometric method is flip-free"
        ));
    }
    let miss = fit_rigid_to_pins(&mut uv, &params.pins);
    if params.pins.len() >= 2 && miss > 1e-6 * mesh.bbox().diagonal() {
        warnings.push(format!(
            "conformal-boundary: the pins cannot all be met by a rigid motion (largest miss {miss:.3} mm)"
        ));
    }
    let energy = if flips == 0 {
        mean_delta2(mesh, &uv)
    } else {
        f64::INFINITY
    };
    tracing::debug!(
        target: "flatcut_flatten",
        method = "conformal-boundary",
        energy,
        "solved"
    );
    Ok(Flattening {
        uv,
        info: FlattenInfo {
            iterations: 1,
            final_energy: energy,
            warnings,
            ..Default::default()
        },
    })
}

/// BFF's closing step: lengths `l̃` nearest to `l` in `Σ (l̃ − l)²/l` with `Σ l̃ T = 0`.
fn close_lengths(len: &[f64], t: &[DVec2]) -> Result<Vec<f64>, FlattenError> {
    // λ = (T N⁻¹ Tᵀ)⁻¹ T l with N⁻¹ = diag(l); l̃ = l − N⁻¹ Tᵀ λ.
    let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
    let mut r = DVec2::ZERO;
    for (l, ti) in len.iter().zip(t) {
        a += l * ti.x * ti.x;
        b += l * ti.x * ti.y;
        c += l * ti.y * ti.y;
        r += *l * *ti;
    }
    let det = a * c - b * b;
    if det.is_nan() || det <= 0.0 {
        return Err(FlattenError::NoConvergence {
            method: Method::ConformalBoundary,
            reason: "the boundary tangents do not span the plane; the boundary cannot be closed"
                .into(),
        });
    }
    let lam = DVec2::new(c * r.x - b * r.y, a * r.y - b * r.x) / det;
    let out: Vec<f64> = len
        .iter()
        .zip(t)
        .map(|(l, ti)| l - l * ti.dot(lam))
        .collect();
    if let Some(i) = out.iter().position(|l| l.is_nan() || *l <= 0.0) {
        return Err(FlattenError::NoConvergence {
            method: Method::ConformalBoundary,
            reason: format!(
                "closing the boundary would give boundary edge {i} a non-positive length; the mesh is too coarse for its curvature"
            ),
        });
    }
    Ok(out)
}

/// Most Gauss–Newton steps of [`close_turns`].
const CLOSE_TURN_STEPS: usize = 20;
/// Gap (relative to the outline's length) at which [`close_turns`] has closed the polygon: the
/// round-off of summing the edges.
const CLOSE_TURN_GAP: f64 = 1e-13;
/// Largest gap (relative) [`close_turns`] accepts when round-off stops it short of
/// [`CLOSE_TURN_GAP`]: a billionth of the outline.
const CLOSE_TURN_ACCEPT: f64 = 1e-9;

/// The turns nearest to `turn` in `Σ (θ̃ − θ)²/ℓ` (ℓ the mean length of a vertex's two edges:
/// the change is spread as a change of curvature) whose polygon, with the edge lengths `len`
/// kept, closes: `Σ l_i T(φ_i) = 0`. The closure is two equations in the turns; each
/// Gauss–Newton step solves their linearisation for the least such change, a 2 × 2 system.
fn close_turns(len: &[f64], turn: &[f64]) -> Result<Vec<f64>, FlattenError> {
    let m = len.len();
    let total: f64 = len.iter().sum();
    let weight: Vec<f64> = (0..m)
        .map(|j| 0.5 * (len[(j + m - 1) % m] + len[j]))
        .collect();
    let gap_of = |t: &[DVec2]| -> DVec2 { len.iter().zip(t).map(|(l, ti)| *l * *ti).sum() };
    let mut turn = turn.to_vec();
    for _ in 0..CLOSE_TURN_STEPS {
        let t = tangents(&turn);
        let gap = gap_of(&t);
        if gap.length() <= CLOSE_TURN_GAP * total {
            return Ok(turn);
        }
        // ∂gap/∂θ_j = Σ_{i ≥ j} l_i T(φ_i)⊥ (θ_0 turns nothing: edge 0 is the reference).
        let mut jac = vec![DVec2::ZERO; m];
        let mut acc = DVec2::ZERO;
        for i in (1..m).rev() {
            acc += len[i] * t[i].perp();
            jac[i] = acc;
        }
        let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
        for j in 1..m {
            let (jx, jy, w) = (jac[j].x, jac[j].y, weight[j]);
            a += w * jx * jx;
            b += w * jx * jy;
            c += w * jy * jy;
        }
        let det = a * c - b * b;
        if det.is_nan() || det <= 0.0 {
            break;
        }
        // Δθ = −W J^T (J W J^T)^{-1} gap.
        let lam = DVec2::new(c * gap.x - b * gap.y, a * gap.y - b * gap.x) / det;
        for j in 1..m {
            turn[j] -= weight[j] * jac[j].dot(lam);
        }
    }
    if gap_of(&tangents(&turn)).length() <= CLOSE_TURN_ACCEPT * total {
        return Ok(turn);
    }
    Err(FlattenError::NoConvergence {
        method: Method::BoundaryIsometric,
        reason:
            "the outline of the conformal map cannot be closed with its edges at their 3D lengths"
                .into(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gap(len: &[f64], turn: &[f64]) -> f64 {
        len.iter()
            .zip(tangents(turn))
            .map(|(l, t)| *l * t)
            .sum::<DVec2>()
            .length()
    }

    /// An outline whose turns do not close (a 40-gon's, each off by up to 0.01 rad) is closed
    /// by turns that change least, its lengths untouched; a closed one is left as it is.
    #[test]
    fn turns_close_an_outline_at_its_lengths() {
        let m = 40;
        let len: Vec<f64> = (0..m).map(|i| 2.0 + (i as f64 * 0.9).sin()).collect();
        let mut turn: Vec<f64> = (0..m)
            .map(|i| std::f64::consts::TAU / m as f64 + 0.01 * (i as f64 * 2.3).cos())
            .collect();
        let total: f64 = len.iter().sum();
        assert!(gap(&len, &turn) > 1e-2 * total);
        let closed = close_turns(&len, &turn).unwrap();
        assert!(gap(&len, &closed) <= CLOSE_TURN_GAP * total);
        let change = closed
            .iter()
            .zip(&turn)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(change < 0.05, "turns changed by {change}");
        // A closed outline: its turns come back unchanged.
        turn = closed;
        assert_eq!(close_turns(&len, &turn).unwrap(), turn);
    }
}
