//! `inspect` of STEP models: the unit the file states, its shells, every face (surface type,
//! area, bounding box, curvature range, developable or not, or why it cannot be used) and every
//! edge (curve type, length, the faces it joins); and the summary of a piece made of STEP faces.
//!
//! Areas are integrated on the exact trimmed surfaces ([`flatcut_step::face_area`]); curvatures
//! are the exact differential geometry at the vertices of the tessellation.

use flatcut_design::StepPiece;
use flatcut_geom::{Aabb3, Tolerances};
use flatcut_mesh::tessellate::TessOptions;
use flatcut_mesh::{MeshStats, TriMesh};
use flatcut_step::heal::Repair;
use flatcut_step::{Model, Tessellation, face_area};
use flatcut_surface::ParamSurface;
use serde::Serialize;

use crate::inspect_figures::{
    DEVELOPABLE_SCALED_K, PieceSummary, Range2, Range3, forms_at, p1_p99,
};

/// The length unit a STEP file states.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StepUnit {
    /// As the file names it (`millimetre`, `metre`, `inch`, …).
    pub name: String,
    /// Millimetres per unit (every figure here is already in mm).
    pub mm: f64,
    /// False when the file states no length unit (millimetres assumed).
    pub stated: bool,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
/// One shell of a STEP model (keys are a stable contract).
pub struct StepShell {
    /// 0-based index of the shell.
    pub index: usize,
    /// The shell's instance number (`#id`).
    pub entity: u64,
    /// True for a closed shell (it bounds a solid).
    pub closed: bool,
    /// The shell's faces (0-based face indices).
    pub faces: Vec<usize>,
}

/// A body (a solid or surface model) and how many times the assembly places it: the instances
/// of one body are one part cut `quantity` times.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StepBody {
    /// The body's instance number (`#id`).
    pub entity: u64,
    /// The body's name in the file.
    pub name: String,
    /// How many times the assembly places it.
    pub quantity: usize,
    /// The shells of its instances.
    pub shells: Vec<usize>,
}

/// One face (keys are a stable contract). Without `error`, all figures are present.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StepFace {
    /// 0-based index of the face, as designs name it.
    pub index: usize,
    /// The face's instance number (`#id`).
    pub entity: u64,
    /// The shell it belongs to (0-based).
    pub shell: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    /// The surface's kind, e.g. `plane`, `cylinder`, `bspline`.
    pub surface: Option<&'static str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    /// Area of the face (mm²).
    pub area_mm2: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    /// Bounding box: lowest corner, then highest (mm).
    pub bbox_mm: Option<[[f64; 3]; 2]>,
    /// Gaussian curvature range (1/mm²).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gaussian_curvature: Option<Range2>,
    #[serde(skip_serializing_if = "Option::is_none")]
    /// True when the face flattens without distortion within the developability threshold.
    pub developable: Option<bool>,
    /// What healing repaired in the face, its loops and its edges (empty for a clean face).
    pub repairs: Vec<Repair>,
    /// Why the face cannot be used.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
/// One edge of a STEP model (keys are a stable contract).
pub struct StepEdge {
    /// 0-based index of the edge.
    pub index: usize,
    /// The edge's instance number (`#id`).
    pub entity: u64,
    #[serde(skip_serializing_if = "Option::is_none")]
    /// The curve's kind, e.g. `line`, `circle`, `bspline`.
    pub curve: Option<&'static str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    /// Length of the edge (mm).
    pub length_mm: Option<f64>,
    /// The faces whose loops use the edge (a face twice for its seam).
    pub faces: Vec<usize>,
    /// The edge (index) this one was sewn into: its faces use that edge instead.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sewn_into: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    /// Why the edge cannot be used; the figures are absent then.
    pub error: Option<String>,
}

/// What `inspect` adds for a STEP file.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StepSummary {
    /// The length unit the file states.
    pub unit: StepUnit,
    /// The schemas the file names (AP203, AP214, AP242).
    pub schemas: Vec<String>,
    /// The largest defect healed (mm): `--heal-tolerance`, or a fraction of the model's size.
    pub heal_limit_mm: f64,
    /// The shells, in model order.
    pub shells: Vec<StepShell>,
    /// The bodies and their quantities (an assembly places a body once per instance).
    pub bodies: Vec<StepBody>,
    /// The faces, in model order.
    pub faces: Vec<StepFace>,
    /// The edges, in model order.
    pub edges: Vec<StepEdge>,
}

/// The model's bodies in file order, each with the number of its instances.
fn bodies(model: &Model) -> Vec<StepBody> {
    let mut out: Vec<StepBody> = Vec::new();
    for inst in &model.instances {
        if !out.iter().any(|b| b.entity == inst.body) {
            out.push(StepBody {
                entity: inst.body,
                name: inst.name.clone(),
                quantity: 0,
                shells: Vec::new(),
            });
        }
    }
    for b in &mut out {
        b.quantity = model
            .instances
            .iter()
            .filter(|i| i.body == b.entity)
            .count();
        b.shells = (0..model.shells.len())
            .filter(|&s| model.instances[model.shells[s].instance].body == b.entity)
            .collect();
    }
    out
}

/// Figures of a set of faces from their tessellation: bounding box, Gaussian and mean curvature
/// ranges, the area-weighted mean Gaussian curvature and the developability measure.
struct Sampled {
    bbox: Aabb3,
    k: (f64, f64),
    h: (f64, f64),
    k_integral: f64,
    area: f64,
    worst_scaled_k: f64,
    /// Every sample's Gaussian and mean curvature, for the robust ranges.
    ks: Vec<f64>,
    hs: Vec<f64>,
}

impl Sampled {
    fn none() -> Self {
        Sampled {
            bbox: Aabb3::EMPTY,
            k: (0.0, 0.0),
            h: (0.0, 0.0),
            k_integral: 0.0,
            area: 0.0,
            worst_scaled_k: 0.0,
            ks: Vec::new(),
            hs: Vec::new(),
        }
    }
}

fn sample(model: &Model, t: &Tessellation) -> Sampled {
    let mut s = Sampled {
        k: (f64::INFINITY, f64::NEG_INFINITY),
        h: (f64::INFINITY, f64::NEG_INFINITY),
        ..Sampled::none()
    };
    for fm in &t.faces {
        let Ok(g) = model.face(fm.face) else { continue };
        let surf: &dyn ParamSurface = g.surface.as_ref();
        let uv = fm.mesh.params.as_deref().unwrap_or(&[]);
        let diag = fm.mesh.bbox().diagonal();
        let ks: Vec<Option<(f64, f64)>> = uv
            .iter()
            .map(|q| forms_at(surf, q.x, q.y).map(|ff| (ff.gaussian(), ff.mean())))
            .collect();
        s.bbox = s.bbox.union(&fm.mesh.bbox());
        for (k, h) in ks.iter().flatten() {
            s.k = (s.k.0.min(*k), s.k.1.max(*k));
            s.h = (s.h.0.min(*h), s.h.1.max(*h));
            s.ks.push(*k);
            s.hs.push(*h);
            if !g.surface.is_ruled_developable() {
                s.worst_scaled_k = s.worst_scaled_k.max(k.abs() * diag * diag);
            }
        }
        for (t, tri) in fm.mesh.triangles.iter().enumerate() {
            let a = fm.mesh.triangle_area(t);
            let kk: Vec<f64> = tri
                .iter()
                .filter_map(|&v| ks[v as usize].map(|x| x.0))
                .collect();
            if !kk.is_empty() {
                s.k_integral += a * kk.iter().sum::<f64>() / kk.len() as f64;
            }
            s.area += a;
        }
    }
    let fin = |(a, b): (f64, f64)| if a <= b { (a, b) } else { (0.0, 0.0) };
    s.k = fin(s.k);
    s.h = fin(s.h);
    s
}

/// The STEP part of an `inspect` report.
pub fn summarise_model(model: &Model, tol: &Tolerances) -> StepSummary {
    // Faces that tessellate on their own: one failing face must not hide the others' figures.
    let mut faces = Vec::with_capacity(model.faces.len());
    for (i, f) in model.faces.iter().enumerate() {
        let mut out = StepFace {
            index: i,
            entity: f.entity,
            shell: f.shell,
            surface: None,
            area_mm2: None,
            bbox_mm: None,
            gaussian_curvature: None,
            developable: None,
            repairs: f.repairs.clone(),
            error: None,
        };
        let figures = (|| -> Result<(), String> {
            let g = model.face(i).map_err(|e| e.to_string())?;
            out.surface = Some(g.surface.name());
            let t = Tessellation::new(model, &[i], tol, &TessOptions::DEFAULT)
                .map_err(|e| e.to_string())?;
            if let Some(fm) = t.faces.first() {
                out.repairs.clone_from(&fm.repairs);
            }
            let s = sample(model, &t);
            out.area_mm2 = Some(face_area(model, i).map_err(|e| e.to_string())?);
            out.bbox_mm = Some([s.bbox.min.to_array(), s.bbox.max.to_array()]);
            out.gaussian_curvature = Some(Range2 {
                min: s.k.0,
                max: s.k.1,
                p1_p99: p1_p99(&s.ks),
            });
            out.developable = Some(s.worst_scaled_k < DEVELOPABLE_SCALED_K);
            Ok(())
        })();
        if let Err(e) = figures {
            out.error = Some(e);
        }
        faces.push(out);
    }
    let edges = model
        .edges
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let (curve, length_mm, error) = match &e.geometry {
                Ok(g) => {
                    let c: &dyn flatcut_surface::ParamCurve = g.curve.as_ref();
                    let (a, b) = (g.t0.min(g.t1), g.t0.max(g.t1));
                    let len = flatcut_surface::curve::CurveExt::arclen_range(c, a, b, 1e-9);
                    (Some(g.curve.name()), Some(len), None)
                }
                Err(err) => (None, None, Some(err.to_string())),
            };
            StepEdge {
                index: i,
                entity: e.entity,
                curve,
                length_mm,
                faces: e.faces.clone(),
                sewn_into: e.sewn_into,
                error,
            }
        })
        .collect();
    StepSummary {
        unit: StepUnit {
            name: model.units.length.clone(),
            mm: model.units.mm,
            stated: model.units.stated,
        },
        schemas: model.schemas.clone(),
        heal_limit_mm: model.heal_mm,
        shells: model
            .shells
            .iter()
            .enumerate()
            .map(|(i, s)| StepShell {
                index: i,
                entity: s.entity,
                closed: s.closed,
                faces: s.faces.clone(),
            })
            .collect(),
        bodies: bodies(model),
        faces,
        edges,
    }
}

/// The summary of a piece made of STEP faces: exact area, curvature at the vertices of its
/// faces' tessellation, developable when every face is (ruled developable surfaces by their
/// kind, others by `max |K| · diag²`).
pub fn summarise_piece(
    name: &str,
    quantity: u32,
    sp: &StepPiece,
    mesh: &TriMesh,
    tol: &Tolerances,
) -> PieceSummary {
    let stats = MeshStats::of(mesh);
    let (area, s) = match sp.source.tessellation(tol) {
        Ok((model, t)) => {
            let area = sp
                .faces
                .iter()
                .map(|&f| face_area(&model, f).unwrap_or(0.0))
                .sum();
            let mut mine = t.as_ref().clone();
            mine.faces.retain(|f| sp.faces.contains(&f.face));
            (area, sample(&model, &mine))
        }
        Err(_) => (0.0, Sampled::none()),
    };
    let bbox = s.bbox.union(&mesh.bbox());
    PieceSummary {
        name: name.to_string(),
        kind: "step",
        quantity,
        area_mm2: area,
        bbox_mm: [bbox.min.to_array(), bbox.max.to_array()],
        gaussian_curvature: Range3 {
            min: s.k.0,
            max: s.k.1,
            mean: if s.area > 0.0 {
                s.k_integral / s.area
            } else {
                0.0
            },
            p1_p99: p1_p99(&s.ks),
        },
        mean_curvature: Range2 {
            min: s.h.0,
            max: s.h.1,
            p1_p99: p1_p99(&s.hs),
        },
        developable: s.worst_scaled_k < DEVELOPABLE_SCALED_K,
        developability_measure: s.worst_scaled_k,
        patches: sp.faces.len(),
        vertices: stats.vertices,
        triangles: stats.triangles,
        boundary_loops: stats.boundary_loops,
        boundary_length_mm: stats.boundary_length,
    }
}

impl std::fmt::Display for StepSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f)?;
        let stated = if self.unit.stated {
            ""
        } else {
            " (not stated; assumed)"
        };
        writeln!(
            f,
            "STEP model: unit {} ({} mm){stated}; schema {}",
            self.unit.name,
            self.unit.mm,
            self.schemas.join(", ")
        )?;
        for s in &self.shells {
            writeln!(
                f,
                "  shell {} (#{}, {}): {} face(s)",
                s.index,
                s.entity,
                if s.closed { "closed" } else { "open" },
                s.faces.len()
            )?;
        }
        for b in self.bodies.iter().filter(|b| b.quantity > 1) {
            let name = if b.name.is_empty() { "body" } else { &b.name };
            writeln!(
                f,
                "  {name} (#{}): placed {} times (shells {:?})",
                b.entity, b.quantity, b.shells
            )?;
        }
        writeln!(f, "  faces")?;
        for x in &self.faces {
            match (
                &x.error,
                x.surface,
                x.area_mm2,
                x.bbox_mm,
                &x.gaussian_curvature,
            ) {
                (None, Some(kind), Some(area), Some([lo, hi]), Some(k)) => writeln!(
                    f,
                    "    {:>4} #{:<7} {:<10} area {:>12.3} mm²  box {:.2} × {:.2} × {:.2} mm  K {:.3e} .. {:.3e}  developable {}",
                    x.index,
                    x.entity,
                    kind,
                    area,
                    hi[0] - lo[0],
                    hi[1] - lo[1],
                    hi[2] - lo[2],
                    k.min,
                    k.max,
                    if x.developable == Some(true) {
                        "yes"
                    } else {
                        "no"
                    }
                )?,
                (err, ..) => writeln!(
                    f,
                    "    {:>4} #{:<7} error: {}",
                    x.index,
                    x.entity,
                    err.as_deref().unwrap_or("incomplete figures")
                )?,
            }
        }
        writeln!(f, "  edges")?;
        for e in &self.edges {
            let faces: Vec<String> = e.faces.iter().map(|x| x.to_string()).collect();
            let uses = match e.sewn_into {
                Some(k) => match self.edges.iter().find(|x| x.index == k) {
                    Some(into) => format!("sewn into {k} (#{})", into.entity),
                    None => format!("sewn into {k}"),
                },
                None => format!("faces {}", faces.join(", ")),
            };
            match (&e.error, e.curve, e.length_mm) {
                (None, Some(c), Some(l)) => writeln!(
                    f,
                    "    {:>4} #{:<7} {:<9} {:>10.3} mm  {uses}",
                    e.index, e.entity, c, l
                )?,
                (err, ..) => writeln!(
                    f,
                    "    {:>4} #{:<7} error: {}",
                    e.index,
                    e.entity,
                    err.as_deref().unwrap_or("incomplete figures")
                )?,
            }
        }
        Ok(())
    }
}
