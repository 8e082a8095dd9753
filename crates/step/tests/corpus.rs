//! The corpus of real STEP files (tests/corpus, listed with source and licence in its
//! manifest.json) against OpenCASCADE as the oracle: tools/step/make_corpus.py wrote what OCCT's
//! STEPControl_Reader gives for every file (after its own healing) into reference.json.
//!
//! Every file is either read whole, or refused with a message naming the entity (`#id`): never
//! read wrong. A file read must match OCCT's total area within 0.1 % (the tessellation's own
//! per-face checks, Green's integral on the trim and each closed shell welding closed, run
//! inside [`Tessellation::new`]), and its closed shells must weld to 0 open edges. The manifest
//! says which files are expected to be refused today; one that starts being read must then
//! pass the same checks (and the manifest be updated).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use flatcut_geom::{DVec3, Tolerances};
use flatcut_mesh::tessellate::TessOptions;
use flatcut_step::{Model, StepError, Tessellation, face_area};
use serde::Deserialize;

/// The chordal tolerance of the run (mm), the deflection OCCT meshed at for its time.
const CHORD_MM: f64 = 0.1;
/// The largest relative disagreement with OCCT's area.
const AREA_REL: f64 = 1e-3;

/// What OpenCASCADE gives for a file.
#[derive(Debug, Deserialize)]
struct Reference {
    read: bool,
    #[serde(default)]
    faces: usize,
    #[serde(default)]
    area_mm2: f64,
    #[serde(default)]
    centroid: Option<[f64; 3]>,
    #[serde(default)]
    occt_seconds: f64,
}

/// One file of the manifest.
#[derive(Debug, Deserialize)]
struct Entry {
    file: String,
    system: String,
    /// Why flatcut refuses the file today (`None`: it must be read).
    #[serde(default)]
    refused: Option<String>,
}

#[derive(Debug, Deserialize)]
struct Manifest {
    files: Vec<Entry>,
}

fn corpus_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus")
}

/// What flatcut makes of a file.
struct Imported {
    faces: usize,
    area: f64,
    repairs: usize,
    open: usize,
    /// The centre of area of the triangles, and the size of their bounding box.
    centroid: DVec3,
    size: f64,
}

/// The centre of area of the tessellation's triangles and the diagonal of their bounding box.
fn centre_of_area(t: &Tessellation) -> (DVec3, f64) {
    let (mut moment, mut area) = (DVec3::ZERO, 0.0);
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for f in &t.faces {
        for k in 0..f.mesh.triangles.len() {
            let [a, b, c] = f.mesh.corners(k);
            let w = f.mesh.triangle_area(k);
            moment += (a + b + c) / 3.0 * w;
            area += w;
            lo = lo.min(a).min(b).min(c);
            hi = hi.max(a).max(b).max(c);
        }
    }
    (moment / area.max(f64::MIN_POSITIVE), lo.distance(hi))
}

/// Reads and tessellates the whole file: the area, the faces' repairs and the open edges.
fn import(path: &Path) -> Result<Imported, StepError> {
    let model = Model::read(path)?;
    let all: Vec<usize> = (0..model.faces.len()).collect();
    let tol = Tolerances::DEFAULT.with_chord_mm(CHORD_MM);
    let t = Tessellation::new(&model, &all, &tol, &TessOptions::DEFAULT)?;
    let mut area = 0.0;
    for f in &all {
        area += face_area(&model, *f)?;
    }
    let (centroid, size) = centre_of_area(&t);
    Ok(Imported {
        faces: model.faces.len(),
        area,
        repairs: t.faces.iter().map(|f| f.repairs.len()).sum(),
        open: t.open_edges(&model),
        centroid,
        size,
    })
}

#[test]
fn every_corpus_file_is_read_right_or_refused_by_name() {
    let dir = corpus_dir();
    let manifest: Manifest =
        serde_json::from_str(&std::fs::read_to_string(dir.join("manifest.json")).unwrap()).unwrap();
    let reference: BTreeMap<String, Reference> =
        serde_json::from_str(&std::fs::read_to_string(dir.join("reference.json")).unwrap())
            .unwrap();
    // Every STEP file in the folder is in the manifest and has a reference.
    for f in std::fs::read_dir(&dir).unwrap() {
        let name = f.unwrap().file_name().to_string_lossy().into_owned();
        if flatcut_step::is_step_path(Path::new(&name)) {
            assert!(
                manifest.files.iter().any(|e| e.file == name),
                "{name} is not in manifest.json"
            );
        }
    }
    let mut failures = Vec::new();
    let (mut read, mut refused) = (0, 0);
    eprintln!(
        "{:<36} {:<28} {:>5} {:>10} {:>5} {:>5} {:>8} {:>8}",
        "file", "system", "faces", "area err", "rep.", "open", "ours s", "OCCT s"
    );
    for e in &manifest.files {
        let r = reference
            .get(&e.file)
            .unwrap_or_else(|| panic!("{}: no reference (tools/step/make_corpus.py)", e.file));
        let t0 = std::time::Instant::now();
        let got = import(&dir.join(&e.file));
        let secs = t0.elapsed().as_secs_f64();
        match (got, &e.refused) {
            (Ok(got), _) => {
                let Imported {
                    faces,
                    area,
                    repairs,
                    open,
                    centroid,
                    size,
                } = got;
                read += 1;
                let rel = (area - r.area_mm2).abs() / r.area_mm2.abs().max(1e-12);
                eprintln!(
                    "{:<36} {:<28} {faces:>5} {rel:>10.2e} {repairs:>5} {open:>5} {secs:>8.3} {:>8.3}",
                    e.file, e.system, r.occt_seconds
                );
                if !r.read {
                    failures.push(format!("{}: OCCT cannot read it, flatcut does", e.file));
                }
                if faces != r.faces {
                    failures.push(format!("{}: {faces} faces, OCCT {}", e.file, r.faces));
                }
                if rel > AREA_REL {
                    failures.push(format!(
                        "{}: area {area:.4} mm², OCCT {:.4} ({rel:.2e})",
                        e.file, r.area_mm2
                    ));
                }
                // Where the area sits: the assemblies' placements and each face's region.
                if let Some(c) = r.centroid {
                    let off = centroid.distance(DVec3::from_array(c));
                    if off > 1e-3 * size + CHORD_MM {
                        failures.push(format!(
                            "{}: centre of area {centroid:.3?}, OCCT {c:?} ({off:.3} mm off)",
                            e.file
                        ));
                    }
                }
                if open != 0 {
                    failures.push(format!("{}: {open} open edges on closed shells", e.file));
                }
                if let Some(why) = &e.refused {
                    failures.push(format!(
                        "{}: now read right; drop `refused` ({why}) from the manifest",
                        e.file
                    ));
                }
            }
            (Err(err), Some(_)) => {
                refused += 1;
                let msg = err.to_string();
                eprintln!("{:<36} {:<28} refused: {msg}", e.file, e.system);
                let named =
                    msg.contains('#') || msg.contains("line ") || msg.contains("holds no shell");
                if !named {
                    failures.push(format!(
                        "{}: refused without naming the entity or line: {msg}",
                        e.file
                    ));
                }
            }
            (Err(err), None) => failures.push(format!("{}: refused: {err}", e.file)),
        }
    }
    eprintln!("{read} read, {refused} refused");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
