//! Grading: a design cut in a run of sizes. `[grading]` names the base size (the design as
//! written) and every size, each either the design scaled about `origin` per axis (a shoe
//! last's length and girth grade differently) or its own design file (a graded last or a body
//! scan, in its own units and coordinates) with the same pieces, style lines, notches, edges and
//! joins by name.
//!
//! ```toml
//! [grading]
//! base = "42"
//! origin = [0, 0, 0]           # the point every scaled size keeps (the heel's back, say)
//! [[grading.size]]
//! name = "40"
//! scale = [0.9506, 0.9583, 0.9583]
//! [[grading.size]]
//! name = "42"                  # the base: the design itself
//! [[grading.size]]
//! name = "44"
//! design = "last-44.toml"      # relative to this design
//! ```

use std::path::{Path, PathBuf};

use flatcut_geom::limits;
use serde::Deserialize;

use crate::units::{Axes, map_piece, map_point};
use crate::{Design, DesignError, P3};

/// A design's size run, as the file gives it (the origin in mm once loaded).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GradingDef {
    /// The size the design is drawn in.
    pub base: String,
    /// The point every scaled size keeps.
    pub origin: P3,
    #[serde(rename = "size")]
    /// The sizes of the run besides the base, in the order the file lists them
    /// (`[[grading.size]]`).
    pub sizes: Vec<SizeDef>,
}

/// One size of a run: the design scaled per axis about the origin, or its own design file.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SizeDef {
    /// The size's name, as outputs and labels carry it.
    pub name: String,
    #[serde(default)]
    /// The factor per axis (x, y, z) about the grading's origin; dimensionless, each finite and
    /// positive.
    pub scale: Option<[f64; 3]>,
    /// A design file (relative to the graded design) for this size.
    #[serde(default)]
    pub design: Option<String>,
}

/// One size of a design: its name (`None` for a design without grading), the design in mm
/// and the folder its files are relative to.
#[derive(Clone, Debug)]
pub struct SizedDesign {
    /// The size's name; `None` for a design without grading.
    pub size: Option<String>,
    /// The design of this size, every length in mm.
    pub design: Design,
    /// The folder the design's files (meshes, STEP models, materials) are relative to.
    pub dir: PathBuf,
}

fn err(file: &str, size: Option<&str>, msg: String) -> DesignError {
    DesignError::Grading {
        file: file.to_string(),
        size: size.map(str::to_string),
        msg,
    }
}

/// Checks a parsed grading (design units, `s` mm per unit).
pub(crate) fn check(file: &str, g: &GradingDef, s: f64) -> Result<(), DesignError> {
    if g.origin.iter().any(|x| !limits::in_range(x * s)) {
        return Err(err(
            file,
            None,
            format!(
                "origin has a coordinate that is not finite or beyond ±{:e} mm",
                limits::MAX_COORD_MM
            ),
        ));
    }
    if g.sizes.is_empty() {
        return Err(err(file, None, "it has no [[grading.size]]".into()));
    }
    for (k, z) in g.sizes.iter().enumerate() {
        let e = |msg: String| err(file, Some(&z.name), msg);
        if z.name.trim().is_empty() {
            return Err(err(file, None, format!("size {k} has an empty name")));
        }
        if g.sizes[..k].iter().any(|o| o.name == z.name) {
            return Err(e("two sizes have this name".into()));
        }
        if let Some(sc) = z.scale
            && let Some(v) = sc.iter().find(|v| !(v.is_finite() && **v > 0.0))
        {
            return Err(e(format!(
                "scale {sc:?}: every factor must be finite and > 0, got {v}"
            )));
        }
        match (z.name == g.base, &z.scale, &z.design) {
            (true, Some(sc), _) if *sc != [1.0; 3] => {
                return Err(e(format!(
                    "it is the base size (the design itself), but scale = {sc:?}"
                )));
            }
            (true, _, Some(_)) => {
                return Err(e(
                    "it is the base size (the design itself); it takes no design file".into(),
                ));
            }
            (false, None, None) => {
                return Err(e(
                    "give `scale = [sx, sy, sz]` or `design = \"file\"`".into()
                ));
            }
            (false, Some(_), Some(_)) => {
                return Err(e("give `scale` or `design`, not both".into()));
            }
            _ => {}
        }
    }
    if !g.sizes.iter().any(|z| z.name == g.base) {
        return Err(err(
            file,
            None,
            format!(
                "base = \"{}\" is none of the sizes ({})",
                g.base,
                g.sizes
                    .iter()
                    .map(|z| z.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ));
    }
    Ok(())
}

/// Scales a grading's origin by `s` (design units → mm).
pub(crate) fn scale(g: &mut GradingDef, s: f64) {
    map_point(&mut g.origin, &Axes::uniform(s));
}

impl Design {
    /// Every size of the design in the grading's order, each a design of its own in mm (the
    /// base size is this design); a design without grading is its one size, unnamed. `dir` is
    /// the folder of this design's file. Errors name the file and the size.
    pub fn sizes(&self, dir: &Path) -> Result<Vec<SizedDesign>, DesignError> {
        let Some(g) = &self.grading else {
            return Ok(vec![SizedDesign {
                size: None,
                design: self.clone(),
                dir: dir.to_path_buf(),
            }]);
        };
        let mut out = Vec::with_capacity(g.sizes.len());
        for z in &g.sizes {
            let (design, at) = match (&z.design, z.scale) {
                (Some(file), _) => {
                    let path = dir.join(file);
                    let d = Design::load(&path)?;
                    if d.grading.is_some() {
                        return Err(err(
                            &self.source,
                            Some(&z.name),
                            format!("{}: a size's design has no [grading] of its own", d.source),
                        ));
                    }
                    same_names(self, &d).map_err(|m| {
                        err(&self.source, Some(&z.name), format!("{}: {m}", d.source))
                    })?;
                    (
                        d,
                        path.parent().map_or(dir.to_path_buf(), Path::to_path_buf),
                    )
                }
                (None, Some(sc)) if z.name != g.base => (
                    scaled(self, &Axes::about(g.origin, sc))
                        .map_err(|m| err(&self.source, Some(&z.name), m))?,
                    dir.to_path_buf(),
                ),
                _ => (self.clone(), dir.to_path_buf()),
            };
            let mut design = design;
            design.grading = None;
            out.push(SizedDesign {
                size: Some(z.name.clone()),
                design,
                dir: at,
            });
        }
        Ok(out)
    }
}

/// The design with every length mapped by `m`.
fn scaled(base: &Design, m: &Axes) -> Result<Design, String> {
    let mut d = base.clone();
    for p in &mut d.pieces {
        map_piece(p, m, false).map_err(|e| format!("piece '{}': {e}", p.name))?;
    }
    for part in &mut d.parts {
        crate::part::map_part(part, m, false).map_err(|e| format!("part '{}': {e}", part.name))?;
    }
    for j in &mut d.joins {
        crate::part::map_join(j, m);
    }
    Ok(d)
}

/// Refuses a size's design that lacks (or adds) a piece, part, style line, notch, edge or join
/// of the base design; the message names it.
fn same_names(base: &Design, size: &Design) -> Result<(), String> {
    fn both<T>(what: &str, a: &[T], b: &[T], name: impl Fn(&T) -> &str) -> Result<(), String> {
        for x in a {
            if !b.iter().any(|y| name(y) == name(x)) {
                return Err(format!(
                    "it has no {what} '{}', which the base design has",
                    name(x)
                ));
            }
        }
        for y in b {
            if !a.iter().any(|x| name(x) == name(y)) {
                return Err(format!(
                    "it has a {what} '{}', which the base design has not",
                    name(y)
                ));
            }
        }
        Ok(())
    }
    both("[[piece]]", &base.pieces, &size.pieces, |p| p.name.as_str())?;
    for p in &base.pieces {
        if let Some(q) = size.pieces.iter().find(|q| q.name == p.name) {
            both("edge", &p.edges, &q.edges, |e| e.name.as_str())
                .map_err(|m| format!("piece '{}': {m}", p.name))?;
        }
    }
    both("[[part]]", &base.parts, &size.parts, |p| p.name.as_str())?;
    for p in &base.parts {
        let Some(q) = size.parts.iter().find(|q| q.name == p.name) else {
            continue;
        };
        let at = |m: String| format!("part '{}': {m}", p.name);
        both("line", &p.lines, &q.lines, |l| l.name.as_str()).map_err(at)?;
        both("edge", &p.edges, &q.edges, |e| e.name.as_str()).map_err(at)?;
        both("piece", &p.pieces, &q.pieces, |x| x.name.as_str()).map_err(at)?;
        for l in &p.lines {
            if let Some(m) = q.lines.iter().find(|m| m.name == l.name)
                && m.notches.len() != l.notches.len()
            {
                return Err(at(format!(
                    "line '{}' has {} notches, the base design's {}",
                    l.name,
                    m.notches.len(),
                    l.notches.len()
                )));
            }
        }
    }
    both("[[join]]", &base.joins, &size.joins, |j| j.name.as_str())
}
