//! Splitting seams, checked independently of the crate's own measures: on a saddle, where no
//! dart can help (the flat piece is too short at the rim), the parts are each within the limits
//! (principal stretches computed here from the 3D triangles and the maps), unflipped, disks that
//! tile the piece, and sewn along seams whose two sides have equal flat lengths edge by edge; a
//! developable piece within the limits is not cut; limits no split can meet are reported, not
//! faked.

use flatcut_darts::limits::Band;
use flatcut_darts::split::{SplitOptions, split, split_surface};
use flatcut_flatten::testmesh::{cylinder_patch, saddle, spherical_cap};
use flatcut_flatten::{FlattenParams, Method, flatten};
use flatcut_geom::{DVec2, DVec3};
use flatcut_mesh::test_shapes::{star_shaped, torus, turn};
use flatcut_mesh::{Topology, TriMesh, check_disk};

/// Principal stretches (σ1 ≥ σ2) and the sign of the map's orientation of triangle `t`.
fn stretches(mesh: &TriMesh, x: &[DVec2], t: usize) -> (f64, f64, f64) {
    let [a, b, c] = mesh.triangles[t].map(|v| mesh.positions[v as usize]);
    let [p, q, r] = mesh.triangles[t].map(|v| x[v as usize]);
    // An orthonormal frame of the 3D triangle: e1 along ab, e2 in its plane.
    let e1 = (b - a).normalize();
    let n = (b - a).cross(c - a);
    let e2 = n.cross(e1).normalize();
    let (u1, u2) = (
        DVec2::new((b - a).dot(e1), (b - a).dot(e2)),
        DVec2::new((c - a).dot(e1), (c - a).dot(e2)),
    );
    let (w1, w2) = (q - p, r - p);
    // J [u1 u2] = [w1 w2]
    let det_u = u1.perp_dot(u2);
    let j = [
        [
            (w1.x * u2.y - w2.x * u1.y) / det_u,
            (w2.x * u1.x - w1.x * u2.x) / det_u,
        ],
        [
            (w1.y * u2.y - w2.y * u1.y) / det_u,
            (w2.y * u1.x - w1.y * u2.x) / det_u,
        ],
    ];
    let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
    let fro2 = j[0][0].powi(2) + j[0][1].powi(2) + j[1][0].powi(2) + j[1][1].powi(2);
    let disc = (fro2 * fro2 - 4.0 * det * det).max(0.0).sqrt();
    let s1 = ((fro2 + disc) / 2.0).sqrt();
    let s2 = ((fro2 - disc) / 2.0).max(0.0).sqrt();
    (s1, s2, det)
}

/// Every face of part `k` in its flat map turned the right way, its principal stretches within
/// `pct` % either way.
fn assert_faces_within(k: usize, p: &TriMesh, pct: f64) {
    let x = p.flat.as_deref().unwrap();
    for t in 0..p.triangles.len() {
        let (s1, s2, det) = stretches(p, x, t);
        assert!(
            det > 0.0 && s1 <= 1.0 + pct / 100.0 + 1e-9 && s2 >= 1.0 - pct / 100.0 - 1e-9,
            "part {k} face {t}: {s1} {s2} (orientation {det})"
        );
    }
}

fn isometric(mesh: &TriMesh) -> Vec<DVec2> {
    flatten(mesh, &FlattenParams::new(Method::Isometric))
        .unwrap()
        .uv
}

fn options(pct: f64, max_pieces: usize) -> SplitOptions {
    SplitOptions {
        band: Band::from_pct(Some(pct), Some(pct)),
        max_pieces,
        keep_out: None,
        visibility: Default::default(),
        time_limit: None,
        seam_allowance_mm: 0.0,
    }
}

#[test]
fn a_saddle_is_split_into_parts_within_the_limits_that_sew_back_together() {
    let mesh = saddle(200.0, 24);
    let x0 = isometric(&mesh);
    // Within 3 % the limits solve holds the whole saddle (see below); within 1.5 % it cannot.
    let pct = 1.5;
    // Beyond the limits whole.
    let worst = (0..mesh.triangles.len())
        .map(|t| {
            let (s1, s2, _) = stretches(&mesh, &x0, t);
            (s1 - 1.0).max(1.0 - s2)
        })
        .fold(0.0, f64::max);
    assert!(worst > 0.04, "the whole saddle flattens within {worst}");
    let params = FlattenParams::new(Method::Isometric);
    let s = split(&mesh, &x0, &params, &options(pct, 8)).unwrap();
    assert!(s.feasible, "excess {}", s.excess);
    assert!(
        s.pieces.len() >= 2 && s.pieces.len() <= 8,
        "{} parts",
        s.pieces.len()
    );
    assert_eq!(s.cuts.len(), s.pieces.len() - 1);
    let mut area = 0.0;
    for (k, p) in s.pieces.iter().enumerate() {
        check_disk(p).unwrap_or_else(|e| panic!("part {k}: {e}"));
        assert_faces_within(k, p, pct);
        // No sliver: no part under the stated share of the whole surface.
        assert!(
            p.area() >= flatcut_darts::split::MIN_SURFACE_SHARE * mesh.area(),
            "part {k}: {} mm² of {}",
            p.area(),
            mesh.area()
        );
        area += p.area();
    }
    assert!(
        (area - mesh.area()).abs() < 1e-6 * mesh.area(),
        "{area} vs {}",
        mesh.area()
    );
    // Every seam: its sides' edges equally long in the plane, one to one, at equal 3D points.
    assert!(!s.seams.is_empty());
    let mut sewn = 0.0;
    for seam in &s.seams {
        let [a, b] = &seam.sides;
        let (xa, xb) = (
            s.pieces[a.piece].flat.as_deref().unwrap(),
            s.pieces[b.piece].flat.as_deref().unwrap(),
        );
        assert_eq!(a.vertices.len(), b.vertices.len());
        for k in 1..a.vertices.len() {
            let (pa, pb) = (a.vertices[k - 1] as usize, a.vertices[k] as usize);
            let (qa, qb) = (b.vertices[k - 1] as usize, b.vertices[k] as usize);
            assert_eq!(
                s.pieces[a.piece].positions[pa],
                s.pieces[b.piece].positions[qa]
            );
            let (la, lb) = (xa[pa].distance(xa[pb]), xb[qa].distance(xb[qb]));
            assert!(
                (la - lb).abs() < 1e-6,
                "seam {}: edge {k} {la} vs {lb}",
                seam.name
            );
            sewn += s.pieces[a.piece].positions[pa].distance(s.pieces[a.piece].positions[pb]);
        }
    }
    assert!(
        (sewn - s.total_cut_mm()).abs() < 1e-6 * sewn,
        "{sewn} vs {}",
        s.total_cut_mm()
    );
    // Each cut runs from the piece's outline to its outline.
    let topo = Topology::build(&mesh).unwrap();
    let rim: Vec<[DVec3; 2]> = topo.boundary_loops[0]
        .iter()
        .zip(topo.boundary_loops[0].iter().cycle().skip(1))
        .map(|(&a, &b)| [mesh.positions[a as usize], mesh.positions[b as usize]])
        .collect();
    let off_rim = |p: DVec3| {
        rim.iter()
            .map(|[a, b]| {
                let d = *b - *a;
                let t = ((p - *a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
                (*a + d * t).distance(p)
            })
            .fold(f64::INFINITY, f64::min)
    };
    let first = &s.cuts[0];
    assert!(off_rim(first[0]) < 1e-6 && off_rim(*first.last().unwrap()) < 1e-6);
    eprintln!(
        "saddle: {} parts, {:.1} mm of seams, worst whole {:.2} %",
        s.pieces.len(),
        s.total_cut_mm(),
        100.0 * worst
    );
}

/// The fewest pieces: within ±3 % the saddle's isometric map is beyond the limits, but the
/// limits solve holds the whole of it; the parts the chords make are merged back into one.
#[test]
fn parts_whose_union_holds_the_limits_are_merged_back() {
    let mesh = saddle(200.0, 24);
    let x0 = isometric(&mesh);
    let s = split(
        &mesh,
        &x0,
        &FlattenParams::new(Method::Isometric),
        &options(3.0, 8),
    )
    .unwrap();
    assert!(s.feasible, "excess {}", s.excess);
    assert_eq!(s.pieces.len(), 1);
    assert!(s.seams.is_empty() && s.cuts.is_empty());
    let p = &s.pieces[0];
    check_disk(p).unwrap();
    assert!((p.area() - mesh.area()).abs() < 1e-6 * mesh.area());
    assert_faces_within(0, p, 3.0);
}

#[test]
fn a_merged_part_keeps_no_neck_narrower_than_twice_the_seam_allowance() {
    use flatcut_darts::split::{MERGED_NECK, merged_neck};
    // 0.15 √area, or twice the allowance where that is wider.
    assert_eq!(merged_neck(40_000.0, 0.0), MERGED_NECK * 200.0);
    assert_eq!(merged_neck(40_000.0, 10.0), MERGED_NECK * 200.0);
    assert_eq!(merged_neck(40_000.0, 16.0), 32.0);
}

#[test]
fn a_developable_piece_within_the_limits_is_not_cut() {
    let mesh = cylinder_patch(40.0, 2.0, 80.0, 16, 12);
    let x0 = isometric(&mesh);
    let s = split(
        &mesh,
        &x0,
        &FlattenParams::new(Method::Isometric),
        &options(1.0, 8),
    )
    .unwrap();
    assert!(s.feasible);
    assert_eq!(s.pieces.len(), 1);
    assert!(s.cuts.is_empty() && s.seams.is_empty());
}

#[test]
fn limits_no_split_meets_are_reported_with_what_was_reached() {
    let mesh = spherical_cap(50.0, 1.0, 10);
    let x0 = isometric(&mesh);
    let s = split(
        &mesh,
        &x0,
        &FlattenParams::new(Method::Isometric),
        &options(0.0, 2),
    )
    .unwrap();
    assert!(!s.feasible);
    assert!(s.excess > 0.0);
    assert!(s.pieces.len() <= 2);
}

#[test]
fn cuts_keep_out_of_no_cut_regions_and_marks() {
    let mesh = saddle(200.0, 24);
    let x0 = isometric(&mesh);
    let params = FlattenParams::new(Method::Isometric);
    let free = split(&mesh, &x0, &params, &options(1.5, 8)).unwrap();
    // Block a disc around the middle of the first cut the free split made.
    let path = &free.cuts[0];
    let mid = path[path.len() / 2];
    let mut keep = flatcut_darts::KeepOut::none(&mesh);
    keep.block_points(&mesh, &[mid], 20.0);
    let mut opts = options(1.5, 8);
    opts.keep_out = Some(keep.clone());
    let s = split(&mesh, &x0, &params, &opts).unwrap();
    assert!(s.feasible, "excess {}", s.excess);
    for cut in &s.cuts {
        for &p in cut {
            let v = flatcut_mesh::seams::nearest_vertex(&mesh.positions, p);
            assert!(!keep.is_blocked(v), "a cut passes the kept-out disc at {p}");
        }
    }
}

/// A helical ramp of `turns` turns between radii `r0` and `r1` (mm), rising `rise` mm a turn, of
/// `n` × `m` quads: nearly developable (its Gaussian curvature is tiny), and laid flat it winds
/// round more than a full turn, so its flat outline crosses itself.
fn ramp(r0: f64, r1: f64, rise: f64, turns: f64, n: usize, m: usize) -> TriMesh {
    let mut positions = Vec::new();
    for i in 0..=n {
        let a = std::f64::consts::TAU * turns * i as f64 / n as f64;
        for j in 0..=m {
            let r = r0 + (r1 - r0) * j as f64 / m as f64;
            positions.push(DVec3::new(
                r * a.cos(),
                r * a.sin(),
                rise * a / std::f64::consts::TAU,
            ));
        }
    }
    let id = |i: usize, j: usize| (i * (m + 1) + j) as u32;
    let mut triangles = Vec::new();
    for i in 0..n {
        for j in 0..m {
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    TriMesh::new(positions, triangles)
}

/// Pairs of non-adjacent boundary edges of the map `x` that cross (by orientation signs,
/// independently of the crate's sweep).
fn outline_crossings(mesh: &TriMesh, x: &[DVec2]) -> usize {
    let topo = Topology::build(mesh).unwrap();
    let edges: Vec<(u32, u32)> = topo
        .boundary_loops
        .iter()
        .flat_map(|l| (0..l.len()).map(move |i| (l[i], l[(i + 1) % l.len()])))
        .collect();
    let orient = |a: DVec2, b: DVec2, c: DVec2| (b - a).perp_dot(c - a);
    let mut n = 0;
    for (i, &(a, b)) in edges.iter().enumerate() {
        for &(c, d) in &edges[i + 1..] {
            if a == c || a == d || b == c || b == d {
                continue;
            }
            let [pa, pb, pc, pd] = [a, b, c, d].map(|v| x[v as usize]);
            if orient(pc, pd, pa) * orient(pc, pd, pb) < 0.0
                && orient(pa, pb, pc) * orient(pa, pb, pd) < 0.0
            {
                n += 1;
            }
        }
    }
    n
}

#[test]
fn a_piece_that_overlaps_itself_flat_is_cut_until_no_part_does() {
    let mesh = ramp(40.0, 52.0, 20.0, 1.4, 84, 3);
    let x0 = isometric(&mesh);
    assert!(
        outline_crossings(&mesh, &x0) > 0,
        "the ramp laid flat does not overlap itself"
    );
    let params = FlattenParams::new(Method::Isometric);
    let s = split(&mesh, &x0, &params, &options(5.0, 8)).unwrap();
    assert!(s.feasible, "excess {}", s.excess);
    assert!(s.pieces.len() >= 2);
    let mut area = 0.0;
    for (k, p) in s.pieces.iter().enumerate() {
        let x = p.flat.as_deref().unwrap();
        assert_eq!(outline_crossings(p, x), 0, "part {k} overlaps itself");
        assert_faces_within(k, p, 5.0);
        area += p.area();
    }
    assert!((area - mesh.area()).abs() < 1e-9 * mesh.area());
    // Refused, not returned, when one piece is all the split may make.
    let e = split(&mesh, &x0, &params, &options(5.0, 1)).unwrap_err();
    assert!(
        matches!(e, flatcut_darts::DartError::SplitOverlap { parts: 1, .. }),
        "{e}"
    );
}

#[test]
fn a_cancelled_split_stops_with_the_cancel_error() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    let mesh = saddle(200.0, 24);
    let x0 = isometric(&mesh);
    // The flag is set at the split's first progress report, before any chord is judged.
    let flag = Arc::new(AtomicBool::new(false));
    let set = flag.clone();
    let hooks = flatcut_flatten::FlattenHooks::default()
        .with_cancel(flag.clone())
        .with_progress(Arc::new(move |p: &flatcut_flatten::FlattenProgress| {
            if p.stage == "split" {
                set.store(true, Ordering::Relaxed);
            }
        }));
    let params = FlattenParams::new(Method::Isometric).with_hooks(hooks);
    let e = split(&mesh, &x0, &params, &options(3.0, 8)).unwrap_err();
    assert!(
        matches!(
            e,
            flatcut_darts::DartError::Flatten(flatcut_flatten::FlattenError::Cancelled { .. })
        ),
        "{e}"
    );
}

/// An hourglass cut from the saddle `z = (x² − y²)/(2c)`: `length` mm along x, its half-width
/// `ends` mm at both ends narrowing smoothly (as sin²) to `waist / 2` at x = 0; `nu × nv` quads.
fn hourglass(length: f64, ends: f64, waist: f64, c: f64, nu: usize, nv: usize) -> TriMesh {
    flatcut_mesh::test_grid::grid_mesh_split(
        nu,
        nv,
        flatcut_mesh::test_grid::Diagonal::Alternating,
        |i, j| {
            let x = length * (i as f64 / nu as f64 - 0.5);
            let s = (std::f64::consts::PI * x / length).sin();
            let half = 0.5 * waist + (ends - 0.5 * waist) * s * s;
            let y = half * (2.0 * j as f64 / nv as f64 - 1.0);
            DVec3::new(x, y, (x * x - y * y) / (2.0 * c))
        },
    )
}

/// The narrowest neck of a flat outline, measured here: the least distance between two outline
/// vertices at least three times as far apart round the outline and a tenth of it.
fn neck(mesh: &TriMesh) -> f64 {
    let topo = Topology::build(mesh).unwrap();
    let rim = topo.boundary_loops.iter().max_by_key(|l| l.len()).unwrap();
    let x = mesh.flat.as_deref().unwrap();
    let p: Vec<DVec2> = rim.iter().map(|&v| x[v as usize]).collect();
    let n = p.len();
    let edge = |i: usize| p[i].distance(p[(i + 1) % n]);
    let round: f64 = (0..n).map(edge).sum();
    let mut best = f64::INFINITY;
    for i in 0..n {
        let mut along = 0.0;
        for j in i + 1..n {
            along += edge(j - 1);
            let a = along.min(round - along);
            let d = p[i].distance(p[j]);
            if a >= 3.0 * d && a >= 0.1 * round {
                best = best.min(d);
            }
        }
    }
    best
}

/// The neck guard on a shape with a waist: an hourglass from a saddle, 240 mm long, 120 mm wide
/// at its ends and 12 mm at its waist. Within ±1.5 % its isometric map is beyond the limits
/// (2 %), but the limits solve holds the whole of it: the limits alone would let the split's
/// parts merge back into the hourglass (as the square saddle's do above). Its waist is narrower
/// than a merged part may have (0.15 √area, 22 mm), so the merge is refused and the parts stay
/// apart, each within the limits, together the whole surface. Without the guard the parts
/// come back as the one hourglass.
#[test]
fn a_merge_that_would_leave_a_thin_waist_is_refused() {
    use flatcut_darts::split::merged_neck;
    let pct = 1.5;
    let mesh = hourglass(240.0, 60.0, 12.0, 100.0, 48, 16);
    let x0 = isometric(&mesh);
    let worst = |m: &TriMesh, x: &[DVec2]| {
        (0..m.triangles.len())
            .map(|t| {
                let (s1, s2, _) = stretches(m, x, t);
                (s1 - 1.0).max(1.0 - s2)
            })
            .fold(0.0, f64::max)
    };
    assert!(worst(&mesh, &x0) > 0.019, "{}", worst(&mesh, &x0));
    let held = flatten(
        &mesh,
        &FlattenParams::new(Method::Isometric)
            .with_max_stretch_pct(Some(pct))
            .with_max_compress_pct(Some(pct)),
    )
    .unwrap();
    assert!(worst(&mesh, &held.uv) <= pct / 100.0 + 1e-9);
    let mut whole = mesh.clone();
    whole.flat = Some(held.uv);
    let waist = neck(&whole);
    assert!(
        (waist - 12.0).abs() < 0.1 && waist < merged_neck(mesh.area(), 0.0),
        "{waist} against {}",
        merged_neck(mesh.area(), 0.0)
    );
    let s = split(
        &mesh,
        &x0,
        &FlattenParams::new(Method::Isometric),
        &options(pct, 8),
    )
    .unwrap();
    assert!(s.feasible, "excess {}", s.excess);
    assert!(s.pieces.len() >= 2, "{} part(s)", s.pieces.len());
    let mut area = 0.0;
    for (k, p) in s.pieces.iter().enumerate() {
        assert!(
            p.area() < 0.95 * mesh.area(),
            "part {k} is the hourglass again"
        );
        assert!(worst(p, p.flat.as_deref().unwrap()) <= pct / 100.0 + 1e-9);
        area += p.area();
    }
    assert!((area - mesh.area()).abs() < 1e-6 * mesh.area());
}

/// Where the excess is spread, the worst face is one of many and a chord through it or through
/// the piece's middle passes beside most of them: a fat ring (tube radius half the ring's) at
/// ±10 % opens into a disk beyond the limits all along its inner equator, and the chords through
/// the middle of that excess part it in few pieces. Through the worst face and the middle alone
/// the same ring came in 10 parts.
#[test]
fn spread_excess_is_cut_through_its_middle_into_few_parts() {
    let mesh = torus(50.0, 25.0, 48, 24);
    let pct = 10.0;
    let s = split_surface(
        &mesh,
        &FlattenParams::new(Method::Isometric),
        &options(pct, 16),
    )
    .unwrap();
    assert!(s.feasible, "excess {}", s.excess);
    assert!(s.pieces.len() <= 5, "{} parts", s.pieces.len());
    let mut area = 0.0;
    for (k, p) in s.pieces.iter().enumerate() {
        check_disk(p).unwrap();
        assert_faces_within(k, p, pct);
        area += p.area();
    }
    // The parts tile the surface (to the tolerance of the command-line torus test).
    assert!(
        (area - mesh.area()).abs() < 1e-5 * mesh.area(),
        "{area} mm² of parts, {} mm² of surface",
        mesh.area()
    );
}

/// The fewest pieces for the limits: a ball within ±10 % comes as the two halves of a tennis
/// ball. The split cuts it in quarters, and the two unions across the diagonals are the halves;
/// judged by the split's capped solve, one of them came out a hair beyond the limits (0.02 %),
/// and the ball came in three parts. Two poses of the 320-face ball the cuts took there.
#[test]
fn a_ball_within_ten_percent_comes_as_the_two_halves_of_a_tennis_ball() {
    let pct = 10.0;
    for (axis, angle) in [(DVec3::Z, 0.5), (DVec3::X, 0.8)] {
        let mesh = star_shaped(2, turn(axis, angle), |_| 100.0);
        let s = split_surface(
            &mesh,
            &FlattenParams::new(Method::Isometric),
            &options(pct, 8),
        )
        .unwrap();
        assert!(s.feasible, "excess {}", s.excess);
        assert_eq!(s.pieces.len(), 2, "turned {angle} about {axis}");
        let mut area = 0.0;
        for (k, p) in s.pieces.iter().enumerate() {
            check_disk(p).unwrap_or_else(|e| panic!("part {k}: {e}"));
            assert_faces_within(k, p, pct);
            // Halves, not a cap and the rest.
            assert!(
                (p.area() - mesh.area() / 2.0).abs() < 0.05 * mesh.area(),
                "part {k}: {} of {} mm²",
                p.area(),
                mesh.area()
            );
            area += p.area();
        }
        // The halves tile the ball, to the tolerance of the traced cuts (as for the ring).
        assert!(
            (area - mesh.area()).abs() < 1e-4 * mesh.area(),
            "{area} vs {}",
            mesh.area()
        );
        // One seam, its two sides equally long in the plane edge by edge.
        assert_eq!(s.seams.len(), 1);
        let [a, b] = &s.seams[0].sides;
        let (xa, xb) = (
            s.pieces[a.piece].flat.as_deref().unwrap(),
            s.pieces[b.piece].flat.as_deref().unwrap(),
        );
        for k in 1..a.vertices.len() {
            let la = xa[a.vertices[k - 1] as usize].distance(xa[a.vertices[k] as usize]);
            let lb = xb[b.vertices[k - 1] as usize].distance(xb[b.vertices[k] as usize]);
            assert!((la - lb).abs() < 1e-6, "edge {k}: {la} vs {lb}");
        }
    }
}

/// A flat 60 mm square (5 mm grid) with one face raised into a spike of three faces round a
/// point `h` above its centroid (a raw scan's spike): the spike's vertex is the last.
fn spiked_square(h: f64) -> TriMesh {
    let mut m = flatcut_mesh::test_grid::grid_mesh(12, 12, |i, j| {
        DVec3::new(5.0 * i as f64, 5.0 * j as f64, 0.0)
    });
    let t = 2 * (12 * 5 + 4);
    let [a, b, c] = m.triangles[t];
    let top = (m.positions[a as usize] + m.positions[b as usize] + m.positions[c as usize]) / 3.0
        + DVec3::new(0.0, 0.0, h);
    let s = m.positions.len() as u32;
    m.positions.push(top);
    m.triangles[t] = [a, b, s];
    m.triangles.push([b, c, s]);
    m.triangles.push([c, a, s]);
    m
}

/// A spike whose angle defect its three faces cannot absorb within ±10 % (more than 3 × 0.2
/// rad) is named as a vertex beyond reach, and, where the split meets the limits, it is on a
/// part's outline; a lower bump and a smooth saddle have none.
#[test]
fn a_spike_no_part_can_hold_inside_is_named_and_left_on_a_seam() {
    let pct = 10.0;
    let params = FlattenParams::new(Method::Isometric);
    for (h, beyond) in [(0.2, false), (3.0, true)] {
        let mesh = spiked_square(h);
        let top = *mesh.positions.last().unwrap();
        let s = split(&mesh, &isometric(&mesh), &params, &options(pct, 6)).unwrap();
        assert_eq!(
            s.beyond_reach,
            if beyond { vec![top] } else { vec![] },
            "h = {h}"
        );
        if s.feasible {
            for (k, p) in s.pieces.iter().enumerate() {
                assert_faces_within(k, p, pct);
                let topo = Topology::build(p).unwrap();
                let inside = p.positions.iter().enumerate().any(|(v, &q)| {
                    q == top
                        && !topo
                            .boundary_loops
                            .iter()
                            .flatten()
                            .any(|&r| r as usize == v)
                });
                assert!(!(beyond && inside), "part {k} holds the spike inside");
            }
        } else {
            assert!(beyond, "h = {h}: excess {}", s.excess);
        }
    }
    let saddle = saddle(200.0, 24);
    let s = split(&saddle, &isometric(&saddle), &params, &options(pct, 8)).unwrap();
    assert!(s.beyond_reach.is_empty());
}
