//! The edits the page makes by drawing, as changes of the design tree: a style line added, a
//! region named, and the pieces kept in step with the regions the lines make.
//!
//! Regions come from the design loader itself ([`flatcut::design::PartDef::regions`]), so what
//! the page shows is what `flatcut run` will cut. When a line closes a new region, the region
//! gets a `[[part.piece]]` of its own at once (named `<part> <n>`, with `at` inside it and the
//! quantity, allowance and material of the piece across the new line), so its flattening can be
//! shown straight away; clicking in a region renames its piece. When removing a line merges two
//! regions, the first piece naming the merged region keeps it and the other is removed.

use std::path::Path;

use flatcut::design::{Design, PartRegions};
use flatcut::geom::Tolerances;
use serde_json::{Value as Json, json};

/// Coordinates written into the design are rounded to this many decimals (0.1 µm): a click's
/// position carries no more, and the file stays readable.
const DECIMALS: i32 = 4;

/// Why an edit cannot be made; the message says what the page or script got wrong.
#[derive(Debug, thiserror::Error)]
pub enum EditError {
    /// The edit request itself is malformed (a missing name, points not `[[x, y, z], …]` in
    /// mm); the message says what.
    #[error("{0}")]
    Request(String),
    /// The edited design fails the design's own checks.
    #[error(transparent)]
    Design(#[from] flatcut::design::DesignError),
}

fn round(x: f64) -> f64 {
    let s = 10f64.powi(DECIMALS);
    (x * s).round() / s
}

/// A point in mm as JSON in the design's units (a design may be written in cm or inches),
/// rounded.
pub fn point_json(p: [f64; 3], design: &Design) -> Json {
    let s = design.units.mm();
    json!([round(p[0] / s), round(p[1] / s), round(p[2] / s)])
}

/// The index of the part a request names: by name, or by index when a number.
pub fn part_index(design: &Design, part: &Json) -> Result<usize, EditError> {
    let found = match part {
        Json::String(s) => design.parts.iter().position(|p| &p.name == s),
        Json::Number(n) => n
            .as_u64()
            .map(|k| k as usize)
            .filter(|&k| k < design.parts.len()),
        Json::Null if design.parts.len() == 1 => Some(0),
        _ => None,
    };
    found.ok_or_else(|| {
        EditError::Request(format!(
            "no part {part} in the design (its parts: {})",
            design
                .parts
                .iter()
                .map(|p| format!("'{}'", p.name))
                .collect::<Vec<_>>()
                .join(", ")
        ))
    })
}

/// Checks a list of points from a request: each `[x, y, z]` of finite numbers.
pub fn points(v: &Json, what: &str) -> Result<Vec<[f64; 3]>, EditError> {
    let bad = || EditError::Request(format!("{what}: expected [[x, y, z], …] in mm"));
    let arr = v.as_array().ok_or_else(bad)?;
    arr.iter()
        .map(|p| {
            let a = p.as_array().filter(|a| a.len() == 3).ok_or_else(bad)?;
            let mut out = [0.0; 3];
            for (o, x) in out.iter_mut().zip(a) {
                *o = x.as_f64().filter(|x| x.is_finite()).ok_or_else(bad)?;
            }
            Ok(out)
        })
        .collect()
}

/// The tree with a style line added to part `part`: `{name, points, notches}` (mm).
pub fn add_line(
    tree: &Json,
    design: &Design,
    part: usize,
    name: &str,
    pts: &[[f64; 3]],
    notches: &[[f64; 3]],
) -> Result<Json, EditError> {
    if name.trim().is_empty() {
        return Err(EditError::Request("a line needs a name".into()));
    }
    let mut tree = tree.clone();
    let lines = part_table(&mut tree, part)?
        .entry("line")
        .or_insert_with(|| json!([]));
    let lines = lines
        .as_array_mut()
        .ok_or_else(|| EditError::Request("the part's `line` is not a list".into()))?;
    if lines
        .iter()
        .any(|l| l.get("name").and_then(Json::as_str) == Some(name))
    {
        return Err(EditError::Request(format!(
            "the part already has a line named '{name}'"
        )));
    }
    let mut line = json!({
        "name": name,
        "points": pts.iter().map(|p| point_json(*p, design)).collect::<Vec<_>>(),
    });
    if !notches.is_empty() {
        line["notches"] = notches.iter().map(|p| point_json(*p, design)).collect();
    }
    lines.push(line);
    Ok(tree)
}

/// A name for a new line of the part: `line <n>` with the first free n.
pub fn free_line_name(design: &Design, part: usize) -> String {
    let taken: Vec<&str> = design.parts[part]
        .lines
        .iter()
        .map(|l| l.name.as_str())
        .collect();
    (1..)
        .map(|n| format!("line {n}"))
        .find(|n| !taken.contains(&n.as_str()))
        .unwrap_or_default()
}

fn part_table(
    tree: &mut Json,
    part: usize,
) -> Result<&mut serde_json::Map<String, Json>, EditError> {
    tree.get_mut("part")
        .and_then(Json::as_array_mut)
        .and_then(|a| a.get_mut(part))
        .and_then(Json::as_object_mut)
        .ok_or_else(|| EditError::Request(format!("the design has no part {part}")))
}

/// Keys a new region's piece takes from the piece across the line that made it.
const INHERITED: [&str; 6] = [
    "quantity",
    "pairs",
    "pair_labels",
    "seam_allowance_mm",
    "material",
    "material_properties",
];

/// Keeps the part's pieces in step with its regions: every region no piece names gets one, and
/// of several pieces naming one region all but the first are removed. Returns the tree and the
/// names of the pieces added and removed.
pub fn reconcile(
    tree: &Json,
    design: &Design,
    part: usize,
    base: &Path,
    tol: &Tolerances,
) -> Result<(Json, Vec<String>, Vec<String>), EditError> {
    let p = &design.parts[part];
    let regions = p.regions(base, tol)?;
    let mut tree = tree.clone();
    let table = part_table(&mut tree, part)?;
    let old_pieces: Vec<Json> = table
        .get("piece")
        .and_then(Json::as_array)
        .cloned()
        .unwrap_or_default();
    let removed_idx: Vec<usize> = regions
        .pieces_of_region
        .iter()
        .flat_map(|ks| ks.iter().skip(1).copied())
        .collect();
    let removed: Vec<String> = removed_idx
        .iter()
        .map(|&k| p.pieces[k].name.clone())
        .collect();
    let mut pieces: Vec<Json> = old_pieces
        .iter()
        .enumerate()
        .filter(|(k, _)| !removed_idx.contains(k))
        .map(|(_, j)| j.clone())
        .collect();
    let mut names: Vec<String> = p.pieces.iter().map(|q| q.name.clone()).collect();
    let mut added = Vec::new();
    for r in 0..regions.split.regions.len() {
        if !regions.pieces_of_region[r].is_empty() {
            continue;
        }
        let name = (1..)
            .map(|n| format!("{} {n}", p.name))
            .find(|n| !names.contains(n))
            .unwrap_or_default();
        let mut piece = json!({ "name": name });
        if let Some(parent) = parent_piece(&regions, r).and_then(|k| old_pieces.get(k)) {
            for key in INHERITED {
                if let Some(v) = parent.get(key) {
                    piece[key] = v.clone();
                }
            }
        }
        piece["at"] = point_json(regions.inner_point(r).to_array(), design);
        names.push(name.clone());
        added.push(name);
        pieces.push(piece);
    }
    table.insert("piece".into(), Json::Array(pieces));
    Ok((tree, added, removed))
}

/// The piece a new region takes its settings from: the one across the most recent line that
/// bounds it, else any neighbour, else the part's first piece.
fn parent_piece(regions: &PartRegions, r: usize) -> Option<usize> {
    let across = |s: &flatcut::mesh::regions::SeamRun| {
        let [a, b] = [s.sides[0].piece, s.sides[1].piece];
        if a == r {
            Some(b)
        } else if b == r {
            Some(a)
        } else {
            None
        }
    };
    let mut seams: Vec<_> = regions.split.seams.iter().collect();
    seams.sort_by_key(|s| std::cmp::Reverse(s.line));
    seams
        .into_iter()
        .filter_map(across)
        .find_map(|o| regions.pieces_of_region[o].first().copied())
        .or(Some(0))
}

/// The tree with the piece of the region around `at` named `name`: the piece naming that region
/// renamed (and the joins that name it), or a new piece at `at`.
pub fn name_region(
    tree: &Json,
    design: &Design,
    part: usize,
    at: [f64; 3],
    name: &str,
    base: &Path,
    tol: &Tolerances,
) -> Result<Json, EditError> {
    let name = name.trim();
    if name.is_empty() {
        return Err(EditError::Request("a piece needs a name".into()));
    }
    let p = &design.parts[part];
    let regions = p.regions(base, tol)?;
    let (r, d) = regions
        .region_at(flatcut::geom::DVec3::from_array(at))
        .ok_or_else(|| EditError::Request("the part's surface has no triangles".into()))?;
    let far = flatcut::mesh::lines::OFF_SURFACE_REL * regions.mesh.bbox().diagonal();
    if d > far {
        return Err(EditError::Request(format!(
            "({:.2}, {:.2}, {:.2}) is {d:.2} mm from the surface of part '{}'",
            at[0], at[1], at[2], p.name
        )));
    }
    let mine = regions.pieces_of_region[r].first().copied();
    let taken = design
        .pieces
        .iter()
        .map(|q| q.name.as_str())
        .chain(
            design
                .parts
                .iter()
                .flat_map(|q| q.pieces.iter().map(|x| x.name.as_str())),
        )
        .any(|n| n == name && mine.is_none_or(|k| p.pieces[k].name != name));
    if taken {
        return Err(EditError::Request(format!(
            "a piece is already named '{name}'"
        )));
    }
    let mut tree = tree.clone();
    match mine {
        Some(k) => {
            let old = p.pieces[k].name.clone();
            rename_in_joins(&mut tree, &old, name);
            let table = part_table(&mut tree, part)?;
            if let Some(piece) = table
                .get_mut("piece")
                .and_then(Json::as_array_mut)
                .and_then(|a| a.get_mut(k))
            {
                piece["name"] = json!(name);
            }
        }
        None => {
            let table = part_table(&mut tree, part)?;
            let pieces = table.entry("piece").or_insert_with(|| json!([]));
            if let Some(a) = pieces.as_array_mut() {
                a.push(json!({ "name": name, "at": point_json(at, design) }));
            }
        }
    }
    Ok(tree)
}

/// Renames a piece in every `[[join]]` edge that names it.
fn rename_in_joins(tree: &mut Json, old: &str, new: &str) {
    let Some(joins) = tree.get_mut("join").and_then(Json::as_array_mut) else {
        return;
    };
    for j in joins {
        for side in ["a", "b"] {
            if let Some(e) = j.get_mut(side)
                && e.get("piece").and_then(Json::as_str) == Some(old)
            {
                e["piece"] = json!(new);
            }
        }
    }
}
