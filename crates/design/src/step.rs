//! STEP models in a design: `type = "step"` pieces, and a `.step`/`.stp` file loaded as a design.
//!
//! ```toml
//! [[piece]]
//! name = "hull"
//! [piece.surface]
//! type = "step"
//! file = "hull.step"        # relative to the design file; lengths in the STEP file's own unit
//! faces = [0, 1]            # or "all" (the default); numbers as `flatcut inspect` lists them
//! group = "smooth"          # "face" (default): each face a piece; "smooth": faces meeting
//!                           # tangent-continuously form one piece
//! ```
//!
//! When the design is loaded, such a piece expands into its pieces: one per face or per smooth
//! group (named `<name>-f<first face>` when there are several), each carrying the model it was
//! read from, so the file is read once. Seams, marks and grain need a piece that stays one.
//!
//! The faces all the pieces of one model take are tessellated together, once per chordal
//! tolerance and healing limit ([`StepSource::tessellation`]): every edge is sampled once, so two
//! pieces along a shared edge have the very same points there, and the edge is a mating seam of
//! its full length ([`crate::step_seams`]).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use flatcut_geom::{DVec3, Tolerances};
use flatcut_mesh::TriMesh;
use flatcut_mesh::tessellate::TessOptions;
use flatcut_step::heal::HealOptions;
use flatcut_step::{Model, StepError, StepFile, Tessellation};
use serde::Deserialize;

use crate::error::Ctx;
use crate::{DesignError, PieceDef, SurfaceDef};

/// Which faces of the model: `"all"` or a list of face numbers.
#[derive(Clone, Debug, PartialEq, Eq, Deserialize)]
#[serde(untagged)]
pub enum StepFaces {
    /// Only `"all"` is accepted.
    Keyword(String),
    /// Face numbers as `flatcut inspect` lists them (0-based), each less than the model's face
    /// count.
    List(Vec<usize>),
}

impl Default for StepFaces {
    fn default() -> Self {
        StepFaces::Keyword("all".into())
    }
}

/// How the chosen faces become pieces.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum StepGroup {
    /// Each face is a piece.
    #[default]
    Face,
    /// Faces that meet smoothly (tangent-continuously) form one piece.
    Smooth,
}

/// A model and its tessellation at one chordal tolerance and healing limit.
type Tessellated = Result<(Arc<Model>, Arc<Tessellation>), StepError>;

/// A STEP file read once for a design: the indexed file, the model read with the default
/// healing, the faces the design's pieces take from it, and their tessellations.
#[derive(Debug)]
pub struct StepSource {
    file: StepFile,
    /// The model read with the default healing limit.
    pub model: Arc<Model>,
    /// The faces the design's pieces take from the model, ascending.
    pub faces: Vec<usize>,
    /// Tessellations by (chordal tolerance, healing limit) bits.
    cache: Mutex<BTreeMap<(u64, u64), Tessellated>>,
}

impl StepSource {
    fn new(file: StepFile, model: Model, faces: Vec<usize>) -> Self {
        Self {
            file,
            model: Arc::new(model),
            faces,
            cache: Mutex::new(BTreeMap::new()),
        }
    }

    /// The model healed within `heal` mm (`None`: the default limit).
    pub fn model_for(&self, heal: Option<f64>) -> Result<Arc<Model>, StepError> {
        match heal {
            None => Ok(self.model.clone()),
            Some(h) => {
                Model::from_file_with(&self.file, &HealOptions { limit_mm: Some(h) }).map(Arc::new)
            }
        }
    }

    /// The model (healed within `tol.heal_mm`) and the tessellation of all the faces the design
    /// takes from it at `tol.chord_mm`, made once.
    pub fn tessellation(&self, tol: &Tolerances) -> Tessellated {
        let key = (
            tol.chord_mm.to_bits(),
            tol.heal_mm.map_or(u64::MAX, f64::to_bits),
        );
        if let Ok(cache) = self.cache.lock()
            && let Some(t) = cache.get(&key)
        {
            return t.clone();
        }
        let made = self.model_for(tol.heal_mm).and_then(|m| {
            Tessellation::new(&m, &self.faces, tol, &TessOptions::DEFAULT)
                .map(|t| (m.clone(), Arc::new(t)))
        });
        if let Ok(mut cache) = self.cache.lock() {
            cache.insert(key, made.clone());
        }
        made
    }
}

/// A STEP model read once and shared by the pieces expanded from it (compared by identity).
#[derive(Clone, Debug)]
pub struct StepModel(pub Arc<StepSource>);

impl PartialEq for StepModel {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// The geometry of a STEP piece: faces of a model, meshed with all the faces the design takes
/// from it.
#[derive(Clone, Debug)]
pub struct StepPiece {
    /// The STEP file the faces come from, read once and shared with the design's other STEP pieces.
    pub source: Arc<StepSource>,
    /// The piece's faces: 0-based face numbers, sorted and distinct.
    pub faces: Vec<usize>,
}

impl StepPiece {
    /// The piece's mesh to `tol.chord_mm`: its faces welded at their shared edges, cut to a disk
    /// where they can be (see [`Tessellation::piece_mesh`]).
    pub fn mesh(&self, tol: &Tolerances) -> Result<TriMesh, StepError> {
        let (m, t) = self.source.tessellation(tol)?;
        Ok(t.piece_mesh(&m, &self.faces))
    }
}

pub(crate) fn check_faces(ctx: &Ctx, faces: &StepFaces) -> Result<(), DesignError> {
    match faces {
        StepFaces::Keyword(k) if k == "all" => Ok(()),
        StepFaces::Keyword(k) => Err(ctx.err(format!(
            "step: faces must be \"all\" or a list of face numbers, got \"{k}\""
        ))),
        StepFaces::List(l) if l.is_empty() => Err(ctx.err("step: the face list is empty".into())),
        StepFaces::List(_) => Ok(()),
    }
}

fn read_file(ctx: &Ctx, path: &Path) -> Result<(StepFile, Model), DesignError> {
    let file = StepFile::read(path).map_err(|e| ctx.step_read(path, e))?;
    let model = Model::from_file(&file).map_err(|e| ctx.step_read(path, e))?;
    Ok((file, model))
}

/// The face numbers a selection names, checked against the model.
fn selected(ctx: &Ctx, model: &Model, faces: &StepFaces) -> Result<Vec<usize>, DesignError> {
    match faces {
        StepFaces::List(l) => {
            if let Some(&bad) = l.iter().find(|&&f| f >= model.faces.len()) {
                return Err(ctx.err(format!(
                    "step: face {bad} does not exist (the model has {} faces, 0 to {})",
                    model.faces.len(),
                    model.faces.len().saturating_sub(1)
                )));
            }
            let mut l = l.clone();
            l.sort_unstable();
            l.dedup();
            Ok(l)
        }
        StepFaces::Keyword(_) => Ok((0..model.faces.len()).collect()),
    }
}

/// Expands every `type = "step"` piece into its pieces (see the module documentation); STEP
/// files are resolved against `base_dir` and each is read once.
pub(crate) fn expand(pieces: Vec<PieceDef>, base_dir: &Path) -> Result<Vec<PieceDef>, DesignError> {
    // Read every file once and find the faces each piece takes.
    let mut read: BTreeMap<PathBuf, (StepFile, Model)> = BTreeMap::new();
    let mut chosen: Vec<Option<(PathBuf, Vec<usize>)>> = Vec::with_capacity(pieces.len());
    for p in &pieces {
        let SurfaceDef::Step {
            file,
            faces,
            model: None,
            ..
        } = &p.surface
        else {
            chosen.push(None);
            continue;
        };
        let ctx = Ctx::of(p);
        let path = base_dir.join(file);
        if !read.contains_key(&path) {
            let r = read_file(&ctx, &path)?;
            read.insert(path.clone(), r);
        }
        let model = &read[&path].1;
        chosen.push(Some((path, selected(&ctx, model, faces)?)));
    }
    // One source per file, with the union of the faces its pieces take.
    let mut sources: BTreeMap<PathBuf, Arc<StepSource>> = BTreeMap::new();
    for (path, (file, model)) in read {
        let mut faces: Vec<usize> = chosen
            .iter()
            .flatten()
            .filter(|(p, _)| *p == path)
            .flat_map(|(_, f)| f.iter().copied())
            .collect();
        faces.sort_unstable();
        faces.dedup();
        sources.insert(path, Arc::new(StepSource::new(file, model, faces)));
    }
    let mut out = Vec::with_capacity(pieces.len());
    for (p, ch) in pieces.into_iter().zip(chosen) {
        let (Some((path, chosen)), SurfaceDef::Step { file, group, .. }) = (ch, &p.surface) else {
            out.push(p);
            continue;
        };
        let ctx = Ctx::of(&p);
        let source = sources[&path].clone();
        let groups: Vec<Vec<usize>> = match group {
            StepGroup::Face => chosen.iter().map(|&f| vec![f]).collect(),
            StepGroup::Smooth => source.model.smooth_groups(&chosen),
        };
        let several = groups.len() > 1;
        if several
            && (!p.seams.is_empty()
                || !p.marks.is_empty()
                || p.grain.is_some_and(|g| g.line().is_some()))
        {
            return Err(ctx.err(format!(
                "step: the faces make {} pieces, but seams, marks and grain need one piece: choose faces that form one",
                groups.len()
            )));
        }
        let file = file.clone();
        for g in groups {
            let mut q = p.clone();
            if several {
                q.name = format!("{}-f{}", p.name, g[0]);
            }
            q.surface = SurfaceDef::Step {
                file: file.clone(),
                faces: StepFaces::List(g),
                group: StepGroup::Face,
                model: Some(StepModel(source.clone())),
            };
            out.push(q);
        }
    }
    Ok(out)
}

/// A `.step`/`.stp` file as a design: every face a piece named `<file stem>-f<face>`.
pub(crate) fn design_pieces(path: &Path) -> Result<Vec<PieceDef>, DesignError> {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "model".into());
    let file = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let piece = PieceDef::of_surface(
        stem,
        SurfaceDef::Step {
            file,
            faces: StepFaces::default(),
            group: StepGroup::Face,
            model: None,
        },
        path.display().to_string(),
    );
    expand(vec![piece], path.parent().unwrap_or(Path::new(".")))
}

/// The geometry of a STEP piece (reading the model if the piece was not expanded at load).
pub(crate) fn build(p: &PieceDef, base_dir: &Path) -> Result<StepPiece, DesignError> {
    let ctx = Ctx::of(p);
    let SurfaceDef::Step {
        file, faces, model, ..
    } = &p.surface
    else {
        return Err(ctx.err("not a STEP piece".into()));
    };
    let source = match model {
        Some(m) => m.0.clone(),
        None => {
            let (f, m) = read_file(&ctx, &base_dir.join(file))?;
            let chosen = selected(&ctx, &m, faces)?;
            Arc::new(StepSource::new(f, m, chosen))
        }
    };
    let faces = selected(&ctx, &source.model, faces)?;
    for &f in &faces {
        source
            .model
            .face(f)
            .map_err(|e| ctx.err(format!("step: face {f}: {e}")))?;
    }
    Ok(StepPiece { source, faces })
}

/// The polyline of the edge with STEP entity number `entity` as the surface of `p` (a `step`
/// surface) is meshed to `tol`: the vertices both its faces share.
pub(crate) fn edge_points(
    p: &PieceDef,
    base_dir: &Path,
    tol: &Tolerances,
    entity: u64,
) -> Result<Vec<DVec3>, String> {
    let sp = build(p, base_dir).map_err(|e| e.to_string())?;
    let index = sp
        .source
        .model
        .edges
        .iter()
        .position(|e| e.entity == entity)
        .ok_or_else(|| {
            format!("#{entity} is not an edge of the model (`flatcut inspect` lists its edges)")
        })?;
    let (_, t) = sp.source.tessellation(tol).map_err(|e| e.to_string())?;
    t.edge_polyline(index)
        .ok_or_else(|| format!("edge #{entity} bounds none of the chosen faces"))
}
