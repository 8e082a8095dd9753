//! What the page is sent to draw, as JSON: a part's surface with its lines and regions, and the
//! flattened pieces with their heat maps, figures and mating seams. Geometry goes as flat number
//! lists (x, y, z, x, y, z, …), rounded to a micrometre.

use flatcut::design::{Design, PartDef, PartRegions};
use flatcut::flat::Flat;
use flatcut::geom::{DVec2, DVec3};
use flatcut::mesh::TriMesh;
use flatcut::report::{MatingSeamReport, Measure};
use serde::Serialize;
use serde_json::{Value as Json, json};

/// Coordinates sent to the page, rounded to 1 µm (far below any cutter's resolution).
fn r3(x: f64) -> f64 {
    (x * 1000.0).round() / 1000.0
}

fn positions(p: &[DVec3]) -> Vec<f64> {
    p.iter().flat_map(|v| [r3(v.x), r3(v.y), r3(v.z)]).collect()
}

fn flat(p: &[DVec2]) -> Vec<f64> {
    p.iter().flat_map(|v| [r3(v.x), r3(v.y)]).collect()
}

fn triangles(m: &TriMesh) -> Vec<u32> {
    m.triangles.iter().flatten().copied().collect()
}

fn mesh_json(m: &TriMesh) -> Json {
    json!({ "positions": positions(&m.positions), "triangles": triangles(m) })
}

fn point(p: DVec3) -> [f64; 3] {
    [r3(p.x), r3(p.y), r3(p.z)]
}

/// One part as the page draws and picks it: its surface split by its lines, each region with
/// the piece that names it, the lines as traced, the surface boundary, and how close to the
/// boundary or a line a line's end must be to close on it (mm).
pub fn part_view(design: &Design, k: usize, regions: &PartRegions) -> Json {
    let part = &design.parts[k];
    let m = &regions.mesh;
    let diag = m.bbox().diagonal();
    let topo = flatcut::mesh::Topology::build(m).ok();
    let boundary: Vec<Vec<[f64; 3]>> = topo
        .map(|t| {
            t.boundary_loops
                .iter()
                .map(|l| l.iter().map(|&v| point(m.positions[v as usize])).collect())
                .collect()
        })
        .unwrap_or_default();
    let lines: Vec<Json> = part
        .lines
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let path: Vec<[f64; 3]> = regions.lines[i]
                .iter()
                .map(|&v| point(m.positions[v as usize]))
                .collect();
            json!({ "name": l.name, "points": l.points, "notches": l.notches, "path": path })
        })
        .collect();
    let reg: Vec<Json> = (0..regions.split.regions.len())
        .map(|r| {
            let names: Vec<&str> = regions.pieces_of_region[r]
                .iter()
                .map(|&p| part.pieces[p].name.as_str())
                .collect();
            json!({
                "piece": names.first(),
                "pieces": names,
                "inner": point(regions.inner_point(r)),
                "area_mm2": r3(regions.split.regions[r].mesh.area()),
            })
        })
        .collect();
    let edges: Vec<Json> = regions
        .edges
        .iter()
        .map(|e| {
            let path: Vec<[f64; 3]> = e.points.iter().map(|&p| point(p)).collect();
            json!({
                "name": e.name,
                "kind": e.kind.name(),
                "allowance_mm": e.allowance_mm,
                "closed": e.closed,
                "path": path,
            })
        })
        .collect();
    let grain: Vec<Json> = part
        .pieces
        .iter()
        .filter_map(|p| {
            let [a, b] = p.grain.as_ref()?.line()?;
            Some(json!({ "piece": p.name, "from": a, "to": b }))
        })
        .collect();
    json!({
        "index": k,
        "name": part.name,
        "grain": grain,
        "mm_per_unit": design.units.mm(),
        "end_tolerance_mm": flatcut::mesh::lines::END_REL * diag,
        "mesh": mesh_json(m),
        "region_of_face": regions.split.region_of_face,
        "regions": reg,
        "lines": lines,
        "edges": edges,
        "boundary": boundary,
        "error": null,
    })
}

/// A part whose lines cannot be traced: its bare surface (for drawing and picking) and the
/// loader's error.
pub fn part_error_view(
    part: &PartDef,
    k: usize,
    surface: Option<&PartRegions>,
    error: &str,
) -> Json {
    let mut v = match surface {
        Some(r) => {
            let mut bare = Design {
                units: flatcut::design::Units::Mm,
                pieces: Vec::new(),
                parts: vec![part.clone()],
                joins: Vec::new(),
                grading: None,
                source: String::new(),
            };
            bare.parts[0].lines.clear();
            part_view(&bare, 0, r)
        }
        None => {
            json!({ "name": part.name, "mesh": null, "regions": [], "lines": [], "boundary": [] })
        }
    };
    v["index"] = json!(k);
    v["error"] = json!(error);
    // The lines as given, so the page can show and edit the one that fails.
    v["lines"] = part
        .lines
        .iter()
        .map(|l| json!({ "name": l.name, "points": l.points, "notches": l.notches, "path": [] }))
        .collect();
    v
}

/// One flattened piece's figures (the keys of the report and of `summary.json`), its heat map
/// and its meshes.
#[derive(Serialize)]
pub struct PieceView<'a> {
    /// The piece's name (`<piece> <size>` for a graded design's sizes).
    pub name: &'a str,
    /// The name of the design part the piece belongs to (`None` when no part lists it).
    pub part: Option<String>,
    /// The size of a graded design's piece.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub size: Option<String>,
    /// How many to cut as drawn.
    pub quantity: u32,
    /// How many mirror images to cut besides.
    pub mirrored: u32,
    /// Number of triangles.
    pub faces: usize,
    /// Triangles whose flat image is reversed or degenerate.
    pub flipped: usize,
    /// Surface area (mm²).
    pub area_3d_mm2: f64,
    /// Flat area (mm²).
    pub area_2d_mm2: f64,
    /// Area-weighted mean of Duncan's isometric distortion δ2 (dimensionless).
    pub delta2_mean: f64,
    /// Largest stretch of any face (percent).
    pub stretch_max_pct: f64,
    /// Largest compression of any face (percent, positive).
    pub compress_max_pct: f64,
    /// The project's stretch limit (percent), if it sets one.
    pub limit_stretch_pct: Option<f64>,
    /// The project's compression limit (percent, positive), if it sets one.
    pub limit_compress_pct: Option<f64>,
    /// True when no region exceeds the limits, no face is flipped and the material's grain
    /// limits hold.
    pub within_limits: bool,
    /// Regions beyond the limits, worst first.
    pub regions: &'a [flatcut::report::Region],
    /// The darts cut into the piece.
    pub darts: &'a [flatcut::report::DartReport],
    /// The strain along the material's grain, with a material.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grain: Option<&'a flatcut::report::GrainReport>,
    /// The flattening's warnings for this piece.
    pub warnings: Vec<String>,
    /// positions (3D), triangles, flat (2D, mm) and per face the signed strain drawn by the
    /// report's stretch heat map (% ; + stretch, − compression).
    pub mesh: Json,
}

/// The flattening of a design as the page shows it (`POST /api/flatten`).
pub fn flatten_view(
    design: &Design,
    flats: &[Flat],
    mating: &[MatingSeamReport],
    limits: (Option<f64>, Option<f64>),
    revision: u64,
    elapsed_s: f64,
) -> Json {
    // A graded design's pieces are named `<piece> <size>`: their part is the design piece's.
    let part_of = |f: &Flat| {
        let name = f
            .def
            .as_ref()
            .and_then(|d| d.size.as_ref())
            .map_or(f.name.as_str(), |s| s.piece.as_str());
        design
            .parts
            .iter()
            .find(|p| p.pieces.iter().any(|q| q.name == name))
            .map(|p| p.name.clone())
    };
    let pieces: Vec<PieceView<'_>> = flats
        .iter()
        .map(|f| {
            let strain: Vec<f64> = f
                .report
                .per_face
                .iter()
                .map(|x| (Measure::Stretch.drawn(x) * 1e4).round() / 1e4)
                .collect();
            let mesh = json!({
                "positions": positions(&f.mesh.positions),
                "triangles": triangles(&f.mesh),
                "flat": f.mesh.flat.as_deref().map(flat).unwrap_or_default(),
                "strain": strain,
            });
            PieceView {
                name: &f.name,
                part: part_of(f),
                size: f
                    .def
                    .as_ref()
                    .and_then(|d| d.size.as_ref())
                    .map(|s| s.size.clone()),
                quantity: f.quantity,
                mirrored: f.mirrored,
                faces: f.report.faces,
                flipped: f.report.flipped,
                area_3d_mm2: f.report.area_3d_mm2,
                area_2d_mm2: f.report.area_2d_mm2,
                delta2_mean: f.report.delta2_mean,
                stretch_max_pct: f.report.stretch_max_pct,
                compress_max_pct: f.report.compress_max_pct,
                limit_stretch_pct: limits.0,
                limit_compress_pct: limits.1,
                within_limits: f.report.within_limits(),
                regions: &f.report.regions,
                darts: &f.report.darts,
                grain: f.report.grain.as_ref(),
                warnings: f
                    .info
                    .as_ref()
                    .map(|i| i.warnings.clone())
                    .unwrap_or_default(),
                mesh,
            }
        })
        .collect();
    json!({
        "revision": revision,
        "elapsed_s": elapsed_s,
        "pieces": pieces,
        "mating_seams": mating,
        "colour_map": flatcut::report::DIVERGING_STOPS,
    })
}
