//! Property: for random style lines on the bundled surfaces (the helmet dome, the lampshade cone,
//! the sail panel, the hull plate), the pieces on either side of the line flatten together with
//! the seam's two flat sides equally long to 0.1 mm and every notch at the same distance from the
//! seam's start on both to 0.05 mm, both sides carry the same 3D points, and the pieces' 3D areas
//! add up to the part's.
//!
//! A line runs from one boundary point through a random interior point to another boundary point
//! a third of the way or more round the boundary (along the surface), with two notches between
//! them; the points are drawn from a seeded generator, so every run checks the same lines.

use std::path::{Path, PathBuf};

use flatcut::design::Design;
use flatcut::flatten::assembly::flatten_assembly;
use flatcut::flatten::{FlattenParams, Method};
use flatcut::geom::{DVec3, Tolerances};
use flatcut::mesh::lines::{LineSpec, embed_lines};
use flatcut::mesh::mating::{MatingSeam, SeamNotch};
use flatcut::mesh::regions::split_along_lines;
use flatcut::mesh::seams::{edge_path, vertex_neighbours};
use flatcut::mesh::{Topology, TriMesh};

/// Lines per surface.
const LINES: usize = 6;

fn patterns() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../patterns")
}

/// The first piece of a bundled design, tessellated coarsely (the property does not depend on
/// the resolution; the run time does).
fn surface(folder: &str) -> TriMesh {
    let dir = patterns().join(folder);
    let d = Design::load(&dir.join("design.toml")).unwrap();
    let size = d.pieces[0]
        .mesh(&dir, &Tolerances::DEFAULT.with_chord_mm(1.0))
        .unwrap()
        .bbox()
        .diagonal();
    // About 2,000–4,000 triangles whatever the size.
    d.pieces[0]
        .mesh(&dir, &Tolerances::DEFAULT.with_chord_mm(size / 600.0))
        .unwrap()
}

/// A small deterministic generator (SplitMix64).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// A random line across the surface: from a boundary point through a random interior point to
/// another boundary point, as points every few vertices along the shortest edge paths between
/// them (so the line stays on the surface however it curves), with two notches at points of the
/// line.
fn random_line(m: &TriMesh, rng: &mut Rng) -> LineSpec {
    let topo = Topology::build(m).unwrap();
    let lp = &topo.boundary_loops[0];
    let n = lp.len();
    let i = rng.below(n);
    let j = (i + n / 3 + rng.below(n / 3)) % n;
    let mut on_boundary = vec![false; m.positions.len()];
    lp.iter().for_each(|&v| on_boundary[v as usize] = true);
    let (a, b) = (lp[i], lp[j]);
    // An interior vertex among the tenth nearest to the middle of the two ends.
    let mid = 0.5 * (m.positions[a as usize] + m.positions[b as usize]);
    let mut inner: Vec<u32> = (0..m.positions.len() as u32)
        .filter(|&v| !on_boundary[v as usize])
        .collect();
    inner.sort_by(|&x, &y| {
        m.positions[x as usize]
            .distance(mid)
            .total_cmp(&m.positions[y as usize].distance(mid))
    });
    let c = inner[rng.below(inner.len() / 10 + 1)];
    let adj = vertex_neighbours(m);
    let mut path = edge_path(m, &adj, a, c).unwrap();
    path.extend(&edge_path(m, &adj, c, b).unwrap()[1..]);
    // A shortest path may run along the boundary before turning inwards: a style line does not
    // (it would separate nothing there), so it starts where the path leaves the boundary.
    while path.len() > 2 && on_boundary[path[1] as usize] {
        path.remove(0);
    }
    while path.len() > 2 && on_boundary[path[path.len() - 2] as usize] {
        path.pop();
    }
    let at = |k: usize| m.positions[path[k] as usize];
    let last = path.len() - 1;
    // Every fourth vertex, and every vertex of the first and last few steps: the line leaves
    // and meets the boundary along the path, not at a grazing angle a walk could not follow.
    let mut points: Vec<DVec3> = (0..=last)
        .filter(|&k| k % 4 == 0 || k < 3 || k + 3 > last)
        .map(at)
        .collect();
    points.dedup();
    let k = points.len() - 1;
    let notches = vec![points[(k * 3 / 10).max(1)], points[(k * 7 / 10).max(1)]];
    LineSpec { points, notches }
}

fn side(meshes: &[TriMesh], s: &MatingSeam, k: usize) -> Vec<DVec3> {
    let sd = &s.sides[k];
    sd.vertices
        .iter()
        .map(|&v| meshes[sd.piece].positions[v as usize])
        .collect()
}

#[test]
fn random_style_lines_on_bundled_surfaces_give_seams_that_match() {
    let mut checked = 0;
    let mut tried = 0;
    for (k, folder) in ["helmet", "lampshade", "sail", "hull"].iter().enumerate() {
        let m = surface(folder);
        let mut rng = Rng(0x5EED + k as u64);
        for _ in 0..LINES {
            tried += 1;
            let line = random_line(&m, &mut rng);
            let e = match embed_lines(&m, std::slice::from_ref(&line)) {
                Ok(e) => e,
                Err(err) => {
                    eprintln!("{folder}: {err}");
                    continue;
                }
            };
            let split = split_along_lines(&e.mesh, &e.lines).unwrap();
            let meshes: Vec<TriMesh> = split.regions.iter().map(|r| r.mesh.clone()).collect();
            let area: f64 = meshes.iter().map(TriMesh::area).sum();
            // The regions tile the part exactly; the part is the surface with the mesh around
            // the line tidied, which moves it by far less than its chordal tolerance: at a chord
            // of size/600 on these surfaces (radii of a third of the size or more) the
            // tessellation's own area error is ~3e-3; the tidying changes the area by < 1e-4.
            assert!(
                (area - e.mesh.area()).abs() < 1e-9 * m.area(),
                "{folder}: areas {area} vs {}",
                e.mesh.area()
            );
            assert!(
                (e.mesh.area() - m.area()).abs() < 1e-4 * m.area(),
                "{folder}: areas {} vs {}",
                e.mesh.area(),
                m.area()
            );
            if let Some(err) = split
                .regions
                .iter()
                .find_map(|r| flatcut::mesh::check_disk(&r.mesh).err())
            {
                eprintln!("{folder}: region {err}");
                continue;
            }
            let seams: Vec<MatingSeam> = split
                .seams
                .iter()
                .map(|run| MatingSeam {
                    name: "line".into(),
                    sides: run.sides.clone(),
                    notches: e.notches[0]
                        .iter()
                        .enumerate()
                        .filter_map(|(j, &v)| {
                            let index = run.path_index.iter().position(|&p| e.lines[0][p] == v)?;
                            Some(SeamNotch {
                                name: format!("n{j}"),
                                index,
                            })
                        })
                        .collect(),
                })
                .collect();
            let refs: Vec<&TriMesh> = meshes.iter().collect();
            let flats = flatten_assembly(&refs, &seams, &FlattenParams::new(Method::Isometric))
                .unwrap_or_else(|err| panic!("{folder}: {err}"));
            let mut flat_meshes = meshes.clone();
            for (fm, f) in flat_meshes.iter_mut().zip(flats) {
                fm.flat = Some(f.uv);
            }
            let frefs: Vec<&TriMesh> = flat_meshes.iter().collect();
            let names: Vec<String> = (0..meshes.len()).map(|r| format!("r{r}")).collect();
            let nrefs: Vec<&str> = names.iter().map(String::as_str).collect();
            let mut notches = 0;
            for s in &seams {
                assert_eq!(side(&meshes, s, 0), side(&meshes, s, 1), "{folder}");
                let r = flatcut::report::measure_seam(s, &frefs, &nrefs).unwrap();
                assert!(r.mismatch_mm <= 0.1, "{folder}: {r:?}");
                for n in &r.notches {
                    assert!(
                        (n.offset_mm[0] - n.offset_mm[1]).abs() <= 0.05,
                        "{folder}: {r:?}"
                    );
                }
                notches += r.notches.len();
            }
            assert_eq!(notches, 2, "{folder}: both notches on a seam");
            checked += 1;
        }
    }
    eprintln!("{checked} of {tried} random lines checked");
    assert_eq!(
        checked, tried,
        "every random line embeds and splits its surface in two disks"
    );
}
