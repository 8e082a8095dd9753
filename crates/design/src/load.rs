//! Reading a design: the file (TOML, JSON or a bare mesh) to a checked `Design` in millimetres.

use std::path::Path;

use flatcut_mesh::io::is_mesh_path;

use crate::check::check_piece;
use crate::part::{check_join, check_part, map_join, map_part};
use crate::schema::DesignFile;
use crate::units::{Axes, map_piece};
use crate::{DesignError, GradingDef, JoinDef, PartDef, PieceDef, SurfaceDef, Units};

/// A loaded design: pieces with every length in mm.
#[derive(Clone, Debug, PartialEq)]
pub struct Design {
    /// Units the file was written in (lengths are already converted).
    pub units: Units,
    /// The `[[piece]]` definitions in file order (their `index` is the position here).
    pub pieces: Vec<PieceDef>,
    /// Surfaces cut into pieces by style lines.
    pub parts: Vec<PartDef>,
    /// Mating seams between edges of separate pieces.
    pub joins: Vec<JoinDef>,
    /// The size run ([`Design::sizes`]); its origin in mm.
    pub grading: Option<GradingDef>,
    /// Name of the source (file path or the name given to `from_*_str`).
    pub source: String,
}

fn line_col(src: &str, offset: usize) -> (usize, usize) {
    let before = &src[..offset.min(src.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

impl Design {
    /// Loads a design from a `.toml` or `.json` file, a mesh file (`.obj`, `.stl`, `.ply`) as a
    /// one-piece design named after the file, or a STEP file (`.step`, `.stp`) with a piece per
    /// face. `type = "step"` pieces are expanded into their pieces (see the `step` module).
    pub fn load(path: &Path) -> Result<Design, DesignError> {
        let name = path.display().to_string();
        if flatcut_step::is_step_path(path) {
            return Ok(Design {
                units: Units::Mm,
                pieces: crate::step::design_pieces(path)?,
                parts: Vec::new(),
                joins: Vec::new(),
                grading: None,
                source: name,
            });
        }
        if is_mesh_path(path) {
            let stem = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "mesh".into());
            let file = path
                .file_name()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            return Ok(Design {
                units: Units::Mm,
                pieces: vec![PieceDef::of_surface(stem, SurfaceDef::Mesh { file }, name)],
                parts: Vec::new(),
                joins: Vec::new(),
                grading: None,
                source: path.display().to_string(),
            });
        }
        let text = std::fs::read_to_string(path).map_err(|source| DesignError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_file_text(&text, path)
    }

    /// A design file's text as [`Design::load`] reads it from `path` (JSON for a `.json` path,
    /// else TOML; STEP pieces expanded from the files they name, relative to the path's
    /// directory), without reading the file: an editor's unsaved text.
    pub fn from_file_text(text: &str, path: &Path) -> Result<Design, DesignError> {
        let name = path.display().to_string();
        let is_json = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"));
        let mut d = if is_json {
            Self::from_json_str(text, &name)
        } else {
            Self::from_toml_str(text, &name)
        }?;
        d.pieces = crate::step::expand(d.pieces, path.parent().unwrap_or(Path::new(".")))?;
        Ok(d)
    }

    /// Parses TOML text; `name` names the source in errors.
    pub fn from_toml_str(text: &str, name: &str) -> Result<Design, DesignError> {
        let f: DesignFile = toml::from_str(text).map_err(|e| {
            let (line, col) = e.span().map_or((0, 0), |s| line_col(text, s.start));
            DesignError::Syntax {
                file: name.to_string(),
                line,
                col,
                msg: e.message().to_string(),
            }
        })?;
        Self::finish(f, name)
    }

    /// Parses JSON text (same structure as TOML: `{"units": "mm", "piece": [...]}`).
    pub fn from_json_str(text: &str, name: &str) -> Result<Design, DesignError> {
        let f: DesignFile = serde_json::from_str(text).map_err(|e| DesignError::Syntax {
            file: name.to_string(),
            line: e.line(),
            col: e.column(),
            msg: e.to_string(),
        })?;
        Self::finish(f, name)
    }

    fn finish(f: DesignFile, name: &str) -> Result<Design, DesignError> {
        if f.pieces.is_empty() && f.parts.is_empty() {
            return Err(DesignError::NoPieces {
                file: name.to_string(),
            });
        }
        let s = f.units.mm();
        let to_mm = Axes::uniform(s);
        let mut pieces = f.pieces;
        for (i, p) in pieces.iter_mut().enumerate() {
            p.index = i;
            p.file = name.to_string();
            check_piece(p, s)?;
            p.resolve_pairs();
            if s != 1.0 {
                map_piece(p, &to_mm, true).map_err(|m| crate::error::Ctx::of(p).err(m))?;
            }
        }
        let mut parts = f.parts;
        for (i, p) in parts.iter_mut().enumerate() {
            p.index = i;
            p.file = name.to_string();
            check_part(p, s)?;
            if s != 1.0 {
                map_part(p, &to_mm, true).map_err(|m| p.err(m))?;
            }
        }
        let mut joins = f.joins;
        for (i, j) in joins.iter_mut().enumerate() {
            j.index = i;
            check_join(name, j, s)?;
            if s != 1.0 {
                map_join(j, &to_mm);
            }
        }
        let mut grading = f.grading;
        if let Some(g) = &mut grading {
            crate::grading::check(name, g, s)?;
            crate::grading::scale(g, s);
        }
        Ok(Design {
            units: f.units,
            pieces,
            parts,
            joins,
            grading,
            source: name.to_string(),
        })
    }
}
