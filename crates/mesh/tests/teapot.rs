//! Newell's Utah teapot (patterns/teapot/newell.txt): the 32 bicubic patches weld into
//! manifold meshes with no crack along any shared patch side, to the chordal tolerance.

use std::collections::BTreeMap;

use flatcut_geom::{DVec3, Tolerances};
use flatcut_mesh::tessellate::{TessOptions, tessellate_with};
use flatcut_mesh::{Topology, TriMesh};
use flatcut_surface::ParamSurface;
use flatcut_surface::patch::BezierPatch;

/// The data set's unit is taken as an inch (as the design files do).
const MM_PER_UNIT: f64 = 25.4;

/// Patch index lists and control points (mm) of newell.txt.
fn read_newell(text: &str) -> (Vec<Vec<usize>>, Vec<DVec3>) {
    let (mut patches, mut verts, mut in_patches) = (Vec::new(), Vec::new(), false);
    for line in text.lines().map(str::trim) {
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if line == "PATCHES" || line == "VERTICES" {
            in_patches = line == "PATCHES";
            continue;
        }
        let nums = line.split(',').map(str::trim);
        if in_patches {
            patches.push(
                nums.map(|s| s.parse::<usize>().unwrap())
                    .collect::<Vec<_>>(),
            );
        } else {
            let c: Vec<f64> = nums.map(|s| s.parse().unwrap()).collect();
            verts.push(DVec3::new(c[0], c[1], c[2]) * MM_PER_UNIT);
        }
    }
    assert_eq!((patches.len(), verts.len()), (32, 306));
    (patches, verts)
}

/// The 32 patches in mm, in data-set order.
fn teapot() -> Vec<BezierPatch> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../patterns/teapot/newell.txt"
    );
    let (idx, verts) = read_newell(&std::fs::read_to_string(path).expect("newell.txt"));
    idx.iter()
        .map(|i| BezierPatch::new(3, 3, i.iter().map(|&k| verts[k]).collect()).unwrap())
        .collect()
}

/// The patches tessellated jointly at [`CHORD_MM`].
fn mesh_of(patches: &[BezierPatch]) -> TriMesh {
    let surfs: Vec<&dyn ParamSurface> = patches.iter().map(|p| p as &dyn ParamSurface).collect();
    tessellate_with(
        &surfs,
        &Tolerances::DEFAULT.with_chord_mm(CHORD_MM),
        &TessOptions::DEFAULT.with_max_vertices(400_000),
    )
    .unwrap()
}

/// Chordal tolerance of the tests (mm): the one the notes quote.
const CHORD_MM: f64 = 0.1;
/// A vertex lies on a sampled curve when closer than this to the polyline of
/// [`SIDE_SAMPLES`] points: the polyline's own sag on the teapot's sides is < 2e-5 mm.
const ON_SIDE_MM: f64 = 1e-4;
/// Samples along a patch side for the crack test.
const SIDE_SAMPLES: usize = 1024;
/// Cell size of the spatial index of the Hausdorff test (mm).
const CELL_MM: f64 = 2.0;

/// Side `s` (u = 0, u = 1, v = 0, v = 1) of a patch's control net as data-set indices.
fn side_indices(idx: &[usize], s: usize) -> [usize; 4] {
    std::array::from_fn(|k| match s {
        0 => idx[k],
        1 => idx[12 + k],
        2 => idx[4 * k],
        _ => idx[4 * k + 3],
    })
}

/// The pairs of patch sides with the same control points (either direction), collapsed sides
/// left out: (patch, side) twice.
fn shared_sides(idx: &[Vec<usize>], verts: &[DVec3]) -> Vec<((usize, usize), (usize, usize))> {
    let pts = |p: usize, s: usize| side_indices(&idx[p], s).map(|k| verts[k]);
    let mut all = Vec::new();
    for p in 0..idx.len() {
        for s in 0..4 {
            let c = pts(p, s);
            if c.iter().any(|q| *q != c[0]) {
                all.push((p, s, c));
            }
        }
    }
    let mut out = Vec::new();
    for i in 0..all.len() {
        for j in i + 1..all.len() {
            let (a, mut b) = (all[i].2, all[j].2);
            let same = a == b || {
                b.reverse();
                a == b
            };
            if same {
                out.push(((all[i].0, all[i].1), (all[j].0, all[j].1)));
            }
        }
    }
    out
}

fn side_uv(s: usize, t: f64) -> (f64, f64) {
    match s {
        0 => (0.0, t),
        1 => (1.0, t),
        2 => (t, 0.0),
        _ => (t, 1.0),
    }
}

fn point_segment_distance(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + ab * t)
}

fn point_triangle_distance(p: DVec3, [a, b, c]: [DVec3; 3]) -> f64 {
    let n = (b - a).cross(c - a);
    if n.length_squared() > 0.0 {
        let n = n.normalize();
        let q = p - n * (p - a).dot(n);
        let inside = [(a, b), (b, c), (c, a)]
            .iter()
            .all(|&(x, y)| (y - x).cross(q - x).dot(n) >= 0.0);
        if inside {
            return p.distance(q);
        }
    }
    point_segment_distance(p, a, b)
        .min(point_segment_distance(p, b, c))
        .min(point_segment_distance(p, c, a))
}

/// Largest distance from a grid of surface samples of every patch to the mesh (triangles
/// found through a uniform grid of [`CELL_MM`] cells; a sample farther than `limit` from every
/// triangle counts as `f64::INFINITY`).
fn surface_to_mesh(m: &TriMesh, patches: &[BezierPatch], n: usize, limit: f64) -> f64 {
    let cell = |p: DVec3| {
        let c = (p / CELL_MM).floor();
        (c.x as i64, c.y as i64, c.z as i64)
    };
    let mut grid: BTreeMap<(i64, i64, i64), Vec<usize>> = BTreeMap::new();
    for t in 0..m.triangles.len() {
        let c = m.corners(t);
        let lo = cell(c[0].min(c[1]).min(c[2]) - DVec3::splat(limit));
        let hi = cell(c[0].max(c[1]).max(c[2]) + DVec3::splat(limit));
        for x in lo.0..=hi.0 {
            for y in lo.1..=hi.1 {
                for z in lo.2..=hi.2 {
                    grid.entry((x, y, z)).or_default().push(t);
                }
            }
        }
    }
    let mut worst: f64 = 0.0;
    for s in patches {
        for i in 0..=n {
            for j in 0..=n {
                let p = s.eval(i as f64 / n as f64, j as f64 / n as f64);
                let d = grid.get(&cell(p)).map_or(f64::INFINITY, |ts| {
                    ts.iter()
                        .map(|&t| point_triangle_distance(p, m.corners(t)))
                        .fold(f64::INFINITY, f64::min)
                });
                worst = worst.max(d);
            }
        }
    }
    worst
}

/// Distance from `q` to the patch, from a Gauss–Newton search for the nearest point started at
/// `uv` (clamped to the unit square); every iterate is a surface point, so the smallest
/// distance seen bounds the true distance from above.
fn distance_near(s: &BezierPatch, q: DVec3, uv: flatcut_geom::DVec2) -> f64 {
    let (mut u, mut v) = (uv.x, uv.y);
    let mut best = s.eval(u, v).distance(q);
    for _ in 0..12 {
        let (p, su, sv) = s.deriv1(u, v);
        let r = q - p;
        let (a, b, c) = (su.dot(su), su.dot(sv), sv.dot(sv));
        let det = a * c - b * b;
        if det.abs() <= 1e-300 {
            break;
        }
        let (ru, rv) = (su.dot(r), sv.dot(r));
        u = (u + (c * ru - b * rv) / det).clamp(0.0, 1.0);
        v = (v + (a * rv - b * ru) / det).clamp(0.0, 1.0);
        best = best.min(s.eval(u, v).distance(q));
    }
    best
}

/// Whether the side u = `x` (`along_v`) or v = `x` of the patch is one point.
fn collapsed(s: &BezierPatch, x: f64, along_v: bool) -> bool {
    let at = |t: f64| if along_v { s.eval(x, t) } else { s.eval(t, x) };
    (1..=8).all(|i| at(i as f64 / 8.0).distance(at(0.0)) < 1e-9)
}

/// Largest distance from points of the triangles (barycentric grid of step 1/n) to the surface
/// (the nearest point found from the same interpolated parameters), over triangles whose corners share their home
/// patch (an upper bound of the distance to the surface there).
fn mesh_to_surface(m: &TriMesh, patches: &[BezierPatch], n: usize) -> (f64, usize) {
    let (params, home) = (
        m.params.as_ref().unwrap(),
        m.patch_of_vertex.as_ref().unwrap(),
    );
    let (mut worst, mut checked): (f64, usize) = (0.0, 0);
    for (t, tri) in m.triangles.iter().enumerate() {
        let p = home[tri[0] as usize];
        if tri.iter().any(|&v| home[v as usize] != p) {
            continue;
        }
        checked += 1;
        let (c, mut uv) = (m.corners(t), tri.map(|v| params[v as usize]));
        // A pole corner (on a collapsed side) names the whole side: put it on the mean
        // meridian of the two other corners, as the tessellator does.
        let s = &patches[p as usize];
        for k in 0..3 {
            let (i, j) = ((k + 1) % 3, (k + 2) % 3);
            let mid = 0.5 * (uv[i] + uv[j]);
            if (uv[k].x == 0.0 || uv[k].x == 1.0) && collapsed(s, uv[k].x, true) {
                uv[k].y = mid.y;
            } else if (uv[k].y == 0.0 || uv[k].y == 1.0) && collapsed(s, uv[k].y, false) {
                uv[k].x = mid.x;
            }
        }
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (a, b) = (i as f64 / n as f64, j as f64 / n as f64);
                let l = [1.0 - a - b, a, b];
                let q = c[0] * l[0] + c[1] * l[1] + c[2] * l[2];
                let w = uv[0] * l[0] + uv[1] * l[1] + uv[2] * l[2];
                worst = worst.max(distance_near(s, q, w));
            }
        }
    }
    (worst, checked)
}

/// Checks every component is a manifold: at most two consistently oriented triangles per edge
/// (the topology build), no duplicate or zero-area triangle, and around every vertex its
/// triangles form one fan (connected through the edges at the vertex). Returns the topology.
fn check_manifold(m: &TriMesh) -> Topology {
    let topo = Topology::build(m).unwrap();
    let mut keys: Vec<[u32; 3]> = m
        .triangles
        .iter()
        .map(|t| {
            let mut k = *t;
            k.sort_unstable();
            k
        })
        .collect();
    keys.sort_unstable();
    assert!(keys.windows(2).all(|w| w[0] != w[1]), "duplicate triangle");
    for t in 0..m.triangles.len() {
        let [a, b, c] = m.corners(t);
        assert!(
            (b - a).cross(c - a).length() > 0.0,
            "zero-area triangle {t}"
        );
    }
    let mut around: Vec<Vec<usize>> = vec![Vec::new(); m.positions.len()];
    for (t, tri) in m.triangles.iter().enumerate() {
        for &v in tri {
            around[v as usize].push(t);
        }
    }
    for (v, ts) in around.iter().enumerate() {
        if ts.is_empty() {
            continue;
        }
        // Union the triangles at v that share a second vertex.
        let mut parent: Vec<usize> = (0..ts.len()).collect();
        fn find(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                x = p[x];
            }
            x
        }
        for i in 0..ts.len() {
            for j in i + 1..ts.len() {
                let (a, b) = (m.triangles[ts[i]], m.triangles[ts[j]]);
                let shared = a
                    .iter()
                    .filter(|&&x| x != v as u32 && b.contains(&x))
                    .count();
                if shared > 0 {
                    let (ri, rj) = (find(&mut parent, i), find(&mut parent, j));
                    parent[ri.max(rj)] = ri.min(rj);
                }
            }
        }
        let fans = (0..ts.len()).filter(|&i| find(&mut parent, i) == i).count();
        assert_eq!(
            fans, 1,
            "vertex {v} at {} joins {fans} fans",
            m.positions[v]
        );
    }
    topo
}

/// Euler characteristic V − E + F per component.
fn euler_per_component(m: &TriMesh, topo: &Topology) -> Vec<i64> {
    let n = topo.component_count;
    let (mut v, mut e, mut f) = (vec![0i64; n], vec![0i64; n], vec![0i64; n]);
    let mut comp_of_vertex = vec![u32::MAX; m.positions.len()];
    for (t, tri) in m.triangles.iter().enumerate() {
        let c = topo.component_of_triangle[t];
        f[c as usize] += 1;
        for &x in tri {
            comp_of_vertex[x as usize] = c;
        }
    }
    for &c in comp_of_vertex.iter().filter(|&&c| c != u32::MAX) {
        v[c as usize] += 1;
    }
    for &(a, _) in topo.edges.keys() {
        e[comp_of_vertex[a as usize] as usize] += 1;
    }
    (0..n).map(|c| v[c] - e[c] + f[c]).collect()
}

#[test]
fn lid_welds_into_one_disk_with_the_pole_an_ordinary_vertex() {
    let patches = teapot();
    let m = mesh_of(&patches[20..28]);
    let topo = check_manifold(&m);
    assert_eq!(topo.component_count, 1);
    assert_eq!(topo.boundary_loops.len(), 1, "the lid's lower edge");
    assert_eq!(euler_per_component(&m, &topo), vec![1], "a disk");
    // The knob's top (the pole of four patches) is one interior vertex.
    let top = DVec3::new(0.0, 0.0, 3.15 * MM_PER_UNIT);
    let at_top: Vec<usize> = (0..m.positions.len())
        .filter(|&v| m.positions[v].distance(top) < 1e-9)
        .collect();
    assert_eq!(at_top.len(), 1);
    assert!(!topo.boundary_loops[0].contains(&(at_top[0] as u32)));
    let valence = m
        .triangles
        .iter()
        .filter(|t| t.contains(&(at_top[0] as u32)))
        .count();
    assert!(valence >= 8, "fan of {valence} triangles");
}

#[test]
fn whole_teapot_is_manifold_crack_free_and_within_tolerance() {
    let patches = teapot();
    let t0 = std::time::Instant::now();
    let m = mesh_of(&patches);
    let secs = t0.elapsed().as_secs_f64();
    assert_eq!(m, mesh_of(&patches), "same input, same mesh");
    let topo = check_manifold(&m);
    // Pot (rim, body, bottom), lid, handle and spout: the handle and spout pierce the body
    // untrimmed and the lid leaves a gap to the rim, so the four parts share no edge.
    assert_eq!(topo.component_count, 4);
    let mut chi = euler_per_component(&m, &topo);
    chi.sort_unstable();
    // Handle and spout are tubes (χ = 0), pot and lid disks (χ = 1).
    assert_eq!(chi, vec![0, 0, 1, 1]);
    assert_eq!(topo.boundary_loops.len(), 6);
    // No crack: no boundary edge runs along any of the 52 sides two patches share.
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../patterns/teapot/newell.txt"
    );
    let (idx, verts) = read_newell(&std::fs::read_to_string(path).unwrap());
    let shared = shared_sides(&idx, &verts);
    assert_eq!(shared.len(), 52);
    let boundary_edges: Vec<(u32, u32)> = topo
        .edges
        .iter()
        .filter(|(_, e)| e.is_boundary())
        .map(|(&k, _)| k)
        .collect();
    for &((p, s), _) in &shared {
        let curve: Vec<DVec3> = (0..=SIDE_SAMPLES)
            .map(|i| {
                let (u, v) = side_uv(s, i as f64 / SIDE_SAMPLES as f64);
                patches[p].eval(u, v)
            })
            .collect();
        let on = |x: DVec3| {
            curve
                .windows(2)
                .any(|w| point_segment_distance(x, w[0], w[1]) < ON_SIDE_MM)
        };
        for &(a, b) in &boundary_edges {
            let (pa, pb) = (m.positions[a as usize], m.positions[b as usize]);
            assert!(
                !(on(pa) && on(pb)),
                "crack along side {s} of patch {p}: boundary edge {pa} - {pb}"
            );
        }
    }
    // Hausdorff distance within the chordal tolerance, both ways.
    let d1 = surface_to_mesh(&m, &patches, 48, CHORD_MM);
    let (d2, checked) = mesh_to_surface(&m, &patches, 4);
    eprintln!(
        "teapot at {CHORD_MM} mm: {} vertices, {} triangles in {secs:.2} s; surface->mesh {d1:.4} mm, mesh->surface {d2:.4} mm ({checked} triangles)",
        m.positions.len(),
        m.triangles.len()
    );
    assert!(d1 <= CHORD_MM, "surface->mesh {d1}");
    assert!(d2 <= CHORD_MM, "mesh->surface {d2}");
    assert!(checked * 10 > m.triangles.len() * 9);
}

#[test]
fn pot_cut_along_its_seam_is_one_disk() {
    // The seam of patterns/teapot/body.toml (data units): from the rim's inner edge (the pot's
    // only boundary) over the lip and down the side to the bottom centre.
    const SEAM: [[f64; 3]; 8] = [
        [0.0, -1.4, 2.4],
        [0.0, -1.403125, 2.4984375],
        [0.0, -1.5, 2.4],
        [0.0, -2.0, 1.35],
        [0.0, -2.0, 0.9],
        [0.0, -1.5, 0.15],
        [0.0, -0.75, 0.0],
        [0.0, 0.0, 0.0],
    ];
    let patches = teapot();
    let pot: Vec<BezierPatch> = (0..12).chain(28..32).map(|p| patches[p].clone()).collect();
    let m = mesh_of(&pot);
    let topo = flatcut_mesh::check_disk(&m).unwrap();
    assert_eq!(
        topo.boundary_loops.len(),
        1,
        "uncut, the pot is already a disk"
    );
    let pts: Vec<DVec3> = SEAM
        .iter()
        .map(|&[x, y, z]| DVec3::new(x, y, z) * MM_PER_UNIT)
        .collect();
    let seam = flatcut_mesh::seam_from_points(&m, &pts).unwrap();
    // The seam runs from the boundary to the bottom centre.
    assert!(topo.boundary_loops[0].contains(&seam[0]));
    assert!(m.positions[*seam.last().unwrap() as usize].length() < 1e-9);
    let cut = flatcut_mesh::cut_along_seams(&m, std::slice::from_ref(&seam)).unwrap();
    let topo = flatcut_mesh::check_disk(&cut).unwrap();
    assert_eq!(topo.boundary_loops.len(), 1);
    // Every seam vertex but the bottom centre (the slit's end) is doubled.
    assert_eq!(cut.vertex_count(), m.vertex_count() + seam.len() - 1);
    // A seam from an interior point (the old one started on the rim's outer edge) cuts a slit:
    // a second boundary loop.
    let slit = flatcut_mesh::seam_from_points(&m, &pts[2..]).unwrap();
    let cut = flatcut_mesh::cut_along_seams(&m, &[slit]).unwrap();
    assert_eq!(Topology::build(&cut).unwrap().boundary_loops.len(), 2);
}
