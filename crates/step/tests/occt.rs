//! flatcut-step against OpenCASCADE: the models tools/step/make_models.py wrote with OCCT
//! (cadquery-ocp), and the figures OCCT gave for them (face areas by BRepGProp, points sampled on
//! its surfaces inside the trims). Every face's area must agree within 0.1 %, and every OCCT
//! point must lie within the chordal tolerance of flatcut's tessellation.

mod common;

use common::{MODELS, MeshDistance, centroid, data_dir, reference};
use flatcut_geom::{DVec3, Tolerances};
use flatcut_mesh::tessellate::TessOptions;
use flatcut_step::{Model, Tessellation, face_area};

const CHORD_MM: f64 = 0.05;

#[test]
fn areas_and_surfaces_match_opencascade() {
    let tol = Tolerances::DEFAULT.with_chord_mm(CHORD_MM);
    for name in MODELS {
        let r = reference(name);
        let model = Model::read(&data_dir().join(format!("{name}.step"))).unwrap();
        assert_eq!(model.faces.len(), r.faces.len(), "{name}: face count");
        let all: Vec<usize> = (0..model.faces.len()).collect();
        let t0 = std::time::Instant::now();
        let t = Tessellation::new(&model, &all, &tol, &TessOptions::DEFAULT)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        eprintln!("{name}: tessellated in {:.3} s", t0.elapsed().as_secs_f64());
        let t0 = std::time::Instant::now();
        for f in 0..model.faces.len() {
            face_area(&model, f).unwrap();
        }
        eprintln!("{name}: areas in {:.3} s", t0.elapsed().as_secs_f64());
        for rf in &r.faces {
            // The face whose centroid is nearest OCCT's centre of area.
            let c = DVec3::from_array(rf.centroid);
            let fm = t
                .faces
                .iter()
                .min_by(|a, b| {
                    centroid(&a.mesh)
                        .distance(c)
                        .total_cmp(&centroid(&b.mesh).distance(c))
                })
                .unwrap();
            let area = face_area(&model, fm.face).unwrap();
            let rel = (area - rf.area_mm2).abs() / rf.area_mm2;
            let md = MeshDistance::new(&fm.mesh);
            let worst = rf
                .samples
                .iter()
                .map(|p| md.distance(DVec3::from_array(*p)))
                .fold(0.0, f64::max);
            eprintln!(
                "{name} face {} ({}): area {area:.4} vs OCCT {:.4} ({:.2e}), mesh {:.4}, {} points, worst {worst:.5} mm, {} triangles",
                fm.face,
                rf.kind,
                rf.area_mm2,
                rel,
                fm.mesh.area(),
                rf.samples.len(),
                fm.mesh.triangles.len()
            );
            assert!(
                rel < 1e-3,
                "{name} face {}: area {area} vs {}",
                fm.face,
                rf.area_mm2
            );
            assert!(
                worst <= CHORD_MM + 1e-6,
                "{name} face {}: an OCCT point is {worst} mm off",
                fm.face
            );
        }
    }
}

/// The other half of the Hausdorff check: every point of flatcut's triangles (centroids and edge
/// midpoints) lies within the chordal tolerance of OCCT's exact face, measured by OCCT
/// (tools/step/check_mesh.py). Skipped, saying so, without cadquery-ocp.
#[test]
fn tessellation_lies_on_opencascade_surfaces() {
    let Some(py) = common::python_with_occt() else {
        return;
    };
    let script =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/step/check_mesh.py");
    let tol = Tolerances::DEFAULT.with_chord_mm(CHORD_MM);
    let dir = tempfile::tempdir().unwrap();
    for name in MODELS {
        let model = Model::read(&data_dir().join(format!("{name}.step"))).unwrap();
        let all: Vec<usize> = (0..model.faces.len()).collect();
        let t = Tessellation::new(&model, &all, &tol, &TessOptions::DEFAULT).unwrap();
        let faces: Vec<serde_json::Value> = t
            .faces
            .iter()
            .map(|fm| {
                let m = &fm.mesh;
                let mut pts = Vec::new();
                // At most ~2000 probes per face: every k-th triangle.
                let step = (m.triangles.len() / 500).max(1);
                for k in (0..m.triangles.len()).step_by(step) {
                    let [a, b, c] = m.corners(k);
                    for p in [
                        (a + b + c) / 3.0,
                        (a + b) / 2.0,
                        (b + c) / 2.0,
                        (c + a) / 2.0,
                    ] {
                        pts.push(p.to_array());
                    }
                }
                serde_json::json!({"centroid": centroid(m).to_array(), "points": pts})
            })
            .collect();
        let probes = dir.path().join(format!("{name}.json"));
        std::fs::write(&probes, serde_json::json!({ "faces": faces }).to_string()).unwrap();
        let out = std::process::Command::new(&py)
            .arg(&script)
            .arg(data_dir().join(format!("{name}.step")))
            .arg(&probes)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let worst = r["worst_mm"].as_f64().unwrap();
        eprintln!("{name}: flatcut's triangles within {worst:.5} mm of OCCT's faces");
        assert!(worst <= CHORD_MM + 1e-6, "{name}: {worst} mm");
    }
}
