//! Mirror symmetry of a triangle mesh: the plane a surface is its own mirror image across, and
//! how far it is from being one.
//!
//! Method:
//! 1. **Candidates.** The planes through the surface's area centroid normal to its principal
//!    axes (the eigenvectors of its area second moment): a shape symmetric across a plane has
//!    that plane's normal as a principal axis, whatever its pose. A normal given by the caller
//!    (an axis the user names) replaces them.
//! 2. **Refinement.** ICP on the reflection: every sample point `p` is reflected, the nearest
//!    point `c` of the surface to its image found ([`crate::nearest::Bvh`]), and the plane
//!    refitted as the one that maps each `p` to its `c` best (its normal the principal direction
//!    of the `p − c`, its offset the mean of the midpoints), until it settles.
//! 3. **Deviation.** The distance from the reflection of every vertex and face centroid to the
//!    surface: its largest value is the symmetric Hausdorff distance between the surface and its
//!    mirror image, sampled at those points (the reflection is an isometry, so one direction
//!    measures both), and its root mean square. The candidate of least RMS wins; it is accepted
//!    when the largest deviation is within the tolerance, a share of the bounding box diagonal.
//!
//! A plane the caller gives whole (a point and a normal: a design whose plane is known, off the
//! principal axes or the centroid) is measured as it is ([`mirror_across`]), step 3 alone: the
//! refinement would move it by the triangulation's own asymmetry, and the caller's plane is the
//! one the pattern must be mirrored across.
//!
//! The samples are points of the surface, not its vertices matched to vertices, so a
//! triangulation that is not itself symmetric still finds its plane (its deviation is then the
//! chordal error of the triangles, far inside the tolerance).

use flatcut_geom::DVec3;

use crate::TriMesh;
use crate::nearest::Bvh;

/// Default tolerance: the largest deviation accepted, as a share of the bounding box diagonal
/// (1 %: 3 mm on a 300 mm toy, under a seam allowance). A coarse mesh deviates by its chordal
/// error alone: 1.6 mm on a 250 mm body of 1,280 faces triangulated unsymmetrically.
pub const DEFAULT_TOLERANCE: f64 = 0.01;
/// Refinement steps at most per candidate.
const ICP_STEPS: usize = 30;
/// Sample points used by the refinement at most (evenly strided); the deviation uses all.
const ICP_SAMPLES: usize = 3000;
/// The refinement stops when the normal turns by less than this (radians) and the plane moves
/// by less than this share of the diagonal.
const SETTLED: f64 = 1e-9;

/// A plane a surface may be mirrored across.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MirrorPlane {
    /// A point of the plane (mm).
    pub point: DVec3,
    /// Its unit normal; the side it points to is the first (left) side.
    pub normal: DVec3,
}

impl MirrorPlane {
    /// The plane through `point` normal to `normal`; `None` when the normal is zero or not finite.
    pub fn new(point: DVec3, normal: DVec3) -> Option<Self> {
        let normal = normal.try_normalize()?;
        point.is_finite().then_some(Self { point, normal })
    }

    /// Signed distance of `p` from the plane (positive on the normal's side).
    pub fn distance(&self, p: DVec3) -> f64 {
        (p - self.point).dot(self.normal)
    }

    /// The mirror image of `p`.
    pub fn reflect(&self, p: DVec3) -> DVec3 {
        p - 2.0 * self.distance(p) * self.normal
    }

    /// The nearest point of the plane to `p`.
    pub fn project(&self, p: DVec3) -> DVec3 {
        p - self.distance(p) * self.normal
    }
}

/// What to look for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SymmetryOptions {
    /// Largest deviation accepted, as a share of the bounding box diagonal.
    pub tolerance: f64,
    /// The plane's normal when the caller names it (an axis); `None`: the principal axes.
    pub normal: Option<DVec3>,
}

impl Default for SymmetryOptions {
    fn default() -> Self {
        Self {
            tolerance: DEFAULT_TOLERANCE,
            normal: None,
        }
    }
}

/// The best mirror plane found and how far the surface is from its mirror image across it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Symmetry {
    /// The plane.
    pub plane: MirrorPlane,
    /// Largest distance (mm) from a reflected sample point to the surface.
    pub max_mm: f64,
    /// Root mean square of those distances (mm).
    pub rms_mm: f64,
    /// The bounding box diagonal (mm), the size the tolerance is a share of.
    pub size_mm: f64,
    /// True when `max_mm` is within the tolerance.
    pub accepted: bool,
}

/// The best mirror plane of `mesh` (see the module documentation); `None` for a mesh without
/// area or with coordinates that are not finite.
pub fn find_mirror(mesh: &TriMesh, opts: &SymmetryOptions) -> Option<Symmetry> {
    let (centroid, axes) = principal_axes(mesh)?;
    let size_mm = mesh.bbox().diagonal();
    if !(size_mm.is_finite() && size_mm > 0.0) {
        return None;
    }
    let bvh = Bvh::new(&mesh.positions, &mesh.triangles);
    let samples = sample_points(mesh);
    let stride = samples.len().div_ceil(ICP_SAMPLES).max(1);
    let few: Vec<DVec3> = samples.iter().step_by(stride).copied().collect();
    let normals: Vec<DVec3> = match opts.normal {
        Some(n) => vec![n],
        None => axes.to_vec(),
    };
    let mut best: Option<Symmetry> = None;
    for n in normals {
        let Some(start) = MirrorPlane::new(centroid, n) else {
            continue;
        };
        let plane = refine(mesh, &bvh, &few, start, size_mm);
        let s = measured(mesh, &bvh, &samples, plane, opts.tolerance);
        if best.is_none_or(|b| s.rms_mm < b.rms_mm) {
            best = Some(s);
        }
    }
    best
}

/// How far `mesh` is from its mirror image across `plane`, the plane taken as it is (not
/// refined), accepted when within `tolerance` (a share of the bounding box diagonal); `None`
/// for a mesh whose bounding box has no size or is not finite.
pub fn mirror_across(mesh: &TriMesh, plane: MirrorPlane, tolerance: f64) -> Option<Symmetry> {
    let size_mm = mesh.bbox().diagonal();
    if !(size_mm.is_finite() && size_mm > 0.0) {
        return None;
    }
    let bvh = Bvh::new(&mesh.positions, &mesh.triangles);
    Some(measured(mesh, &bvh, &sample_points(mesh), plane, tolerance))
}

/// `plane` with the deviation of `mesh` across it, measured at `samples`, and whether it is
/// within `tolerance` of the bounding box diagonal.
fn measured(
    mesh: &TriMesh,
    bvh: &Bvh,
    samples: &[DVec3],
    plane: MirrorPlane,
    tolerance: f64,
) -> Symmetry {
    let size_mm = mesh.bbox().diagonal();
    let (max_mm, rms_mm) = deviation(mesh, bvh, samples, &plane);
    Symmetry {
        plane,
        max_mm,
        rms_mm,
        size_mm,
        accepted: max_mm <= tolerance * size_mm,
    }
}

/// Largest and root-mean-square distance from the reflections of `samples` to the surface.
pub fn deviation(mesh: &TriMesh, bvh: &Bvh, samples: &[DVec3], plane: &MirrorPlane) -> (f64, f64) {
    let (mut max, mut sum) = (0.0f64, 0.0);
    for &p in samples {
        let d = bvh
            .nearest(&mesh.positions, &mesh.triangles, plane.reflect(p))
            .map_or(f64::INFINITY, |(_, _, d)| d);
        max = max.max(d);
        sum += d * d;
    }
    (max, (sum / samples.len().max(1) as f64).sqrt())
}

/// The points the deviation is measured at: every vertex and every face centroid.
pub fn sample_points(mesh: &TriMesh) -> Vec<DVec3> {
    let mut s = mesh.positions.clone();
    s.extend((0..mesh.triangles.len()).map(|t| mesh.corners(t).iter().sum::<DVec3>() / 3.0));
    s
}

/// ICP refinement of `plane` (see the module documentation).
fn refine(
    mesh: &TriMesh,
    bvh: &Bvh,
    samples: &[DVec3],
    mut plane: MirrorPlane,
    size: f64,
) -> MirrorPlane {
    for _ in 0..ICP_STEPS {
        let mut scatter = nalgebra::Matrix3::<f64>::zeros();
        let mut offsets = 0.0;
        let mut count = 0usize;
        for &p in samples {
            let Some((t, b, _)) = bvh.nearest(&mesh.positions, &mesh.triangles, plane.reflect(p))
            else {
                continue;
            };
            let [x, y, z] = mesh.corners(t);
            let c = x * b.x + y * b.y + z * b.z;
            let d = p - c;
            let v = nalgebra::Vector3::new(d.x, d.y, d.z);
            scatter += v * v.transpose();
            offsets += (0.5 * (p + c)).dot(plane.normal);
            count += 1;
        }
        if count == 0 {
            break;
        }
        let eig = nalgebra::SymmetricEigen::new(scatter);
        let k = eig.eigenvalues.imax();
        let e = eig.eigenvectors.column(k);
        let mut n = DVec3::new(e[0], e[1], e[2]);
        if n.dot(plane.normal) < 0.0 {
            n = -n;
        }
        // The offset is measured along the old normal; the new plane passes through the old
        // plane's point moved to it.
        let offset = offsets / count as f64 - plane.point.dot(plane.normal);
        let point = plane.point + offset * plane.normal;
        let Some(next) = MirrorPlane::new(point, n) else {
            break;
        };
        let turned = next.normal.angle_between(plane.normal);
        let moved = next.distance(plane.point).abs();
        plane = next;
        if turned < SETTLED && moved < SETTLED * size {
            break;
        }
    }
    plane
}

/// The area centroid of the surface and its principal axes (unit eigenvectors of the area
/// second moment about the centroid), largest moment first.
fn principal_axes(mesh: &TriMesh) -> Option<(DVec3, [DVec3; 3])> {
    let mut area = 0.0;
    let mut first = DVec3::ZERO;
    for t in 0..mesh.triangles.len() {
        let a = mesh.triangle_area(t);
        area += a;
        first += a * mesh.corners(t).iter().sum::<DVec3>() / 3.0;
    }
    if !(area.is_finite() && area > 0.0) {
        return None;
    }
    let centroid = first / area;
    // ∫ x xᵀ dA over a triangle = A/12 (Σ vᵢvᵢᵀ + s sᵀ), s = Σ vᵢ.
    let outer = |v: DVec3| {
        let v = nalgebra::Vector3::new(v.x, v.y, v.z);
        v * v.transpose()
    };
    let mut m = nalgebra::Matrix3::<f64>::zeros();
    for t in 0..mesh.triangles.len() {
        let c = mesh.corners(t).map(|p| p - centroid);
        let s = c[0] + c[1] + c[2];
        m += (outer(c[0]) + outer(c[1]) + outer(c[2]) + outer(s)) * (mesh.triangle_area(t) / 12.0);
    }
    if !m.iter().all(|x| x.is_finite()) {
        return None;
    }
    let eig = nalgebra::SymmetricEigen::new(m);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let axes = order.map(|k| {
        let e = eig.eigenvectors.column(k);
        DVec3::new(e[0], e[1], e[2])
    });
    Some((centroid, axes))
}

#[cfg(test)]
#[path = "symmetry_tests.rs"]
mod tests;
