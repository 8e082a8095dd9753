//! Mesh files: OBJ, STL (ASCII and binary) and PLY (ASCII and binary) readers, OBJ and STL
//! writers.
//!
//! The OBJ reader is our own: `tobj` reports no line numbers, and a pattern maker fixing a broken
//! export needs "line 1234, column 7: vertex index 9001 is out of range (the file has 8000
//! vertices)". STL goes through `stl_io`, PLY through `ply-rs-bw`; their coincident vertices are
//! welded within a tolerance (STL stores every triangle's corners separately).
//!
//! OBJ texture coordinates (`vt`) are read as a flattening in mm (`TriMesh::flat`): when each
//! position uses one `vt` throughout the file the mesh keeps its vertices; when a position uses
//! several (a UV seam), the vertex is split, one copy per distinct `vt`. When some faces have no
//! `vt`, texture coordinates are ignored (a partial flattening is no flattening).
//!
//! Writers are deterministic (shortest round-trip float text) and atomic (a temporary file in the same
//! directory is renamed over the target, so a crash never leaves a half-written pattern).

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use flatcut_geom::{DVec2, DVec3, Tolerances};

use crate::TriMesh;

/// Why a mesh file could not be read or written. Every message names the file, and the line and
/// column where the format has them.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MeshIoError {
    /// The file could not be opened, read or written (atomic writes: also the rename of the
    /// temporary file over the target).
    #[error("{}: {source}", path.display())]
    Io {
        /// The file being read or written.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// An OBJ statement is malformed: a token is not a number or an index, or a statement has
    /// too few values.
    #[error("{}:{line}:{col}: {msg}", path.display())]
    Parse {
        /// The OBJ file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// 1-based column, in characters, of the offending token (or just past the line's last
        /// token when a value is missing).
        col: usize,
        /// What is wrong, naming the statement and the token.
        msg: String,
    },
    /// An OBJ face corner refers to a vertex, texture coordinate or normal that does not exist
    /// (yet) at that line; OBJ indices are 1-based, negative ones count back from the last.
    #[error("{}:{line}:{col}: {what} index {index} is out of range (the file has {} at this point)", path.display(), count_of(*count, what))]
    BadIndex {
        /// The OBJ file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// 1-based column, in characters, of the corner holding the index.
        col: usize,
        /// The kind of element indexed: `"vertex"`, `"texture coordinate"` or `"normal"`.
        what: &'static str,
        /// The index as written in the file (1-based or negative; 0 is always invalid).
        index: i64,
        /// How many elements of that kind the file had defined before this line.
        count: usize,
    },
    /// An OBJ coordinate is NaN or infinite.
    #[error("{}:{line}:{col}: {what} has a non-finite coordinate ({text})", path.display())]
    NonFinite {
        /// The OBJ file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// 1-based column, in characters, of the coordinate.
        col: usize,
        /// The statement the coordinate belongs to, e.g. `"vertex"`.
        what: &'static str,
        /// The coordinate exactly as written (`nan`, `inf`, …).
        text: String,
    },
    /// An OBJ coordinate is finite but farther than
    /// [`MAX_COORD_MM`](flatcut_geom::limits::MAX_COORD_MM) from zero.
    #[error("{}:{line}:{col}: {what} coordinate {}", path.display(), flatcut_geom::limits::out_of_range_reason(*value))]
    OutOfRange {
        /// The OBJ file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// 1-based column, in characters, of the coordinate.
        col: usize,
        /// The statement the coordinate belongs to, e.g. `"vertex"`.
        what: &'static str,
        /// The coordinate's value (mm).
        value: f64,
    },
    /// An STL or PLY file is malformed (the decoding library's message or a missing element),
    /// or a vertex coordinate in it is non-finite or out of range.
    #[error("{}: {msg}", path.display())]
    Format {
        /// The STL or PLY file.
        path: PathBuf,
        /// What is wrong.
        msg: String,
    },
    /// The file is empty or holds no triangle (for STL: none left after welding, since
    /// triangles collapsed by the weld are dropped).
    #[error("{}: the file contains no triangles", path.display())]
    Empty {
        /// The mesh file.
        path: PathBuf,
    },
    /// The extension is none of `.obj`, `.stl`, `.ply` (in any case).
    #[error("{}: unknown mesh format (expected .obj, .stl or .ply)", path.display())]
    UnknownFormat {
        /// The file whose extension was not recognised.
        path: PathBuf,
    },
}

/// "1 vertex", "121 vertices", "3 texture coordinates": a count with its noun.
fn count_of(count: usize, what: &str) -> String {
    match (count, what) {
        (1, w) => format!("1 {w}"),
        (n, "vertex") => format!("{n} vertices"),
        (n, w) => format!("{n} {w}s"),
    }
}

/// Reads a mesh, choosing the format from the extension (`.obj`, `.stl`, `.ply`, any case).
/// STL and PLY vertices closer than [`Tolerances::DEFAULT_WELD_MM`] are welded.
pub fn read_mesh(path: &Path) -> Result<TriMesh, MeshIoError> {
    read_mesh_with(path, &Tolerances::DEFAULT)
}

/// [`read_mesh`] with an explicit weld tolerance (`tol.weld_mm`).
pub fn read_mesh_with(path: &Path, tol: &Tolerances) -> Result<TriMesh, MeshIoError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    let bytes = std::fs::read(path).map_err(|source| MeshIoError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    match ext.as_str() {
        "obj" => {
            // Valid UTF-8 is read as it is (the lossy reading's result, found faster).
            let text = match std::str::from_utf8(&bytes) {
                Ok(t) => std::borrow::Cow::Borrowed(t),
                Err(_) => String::from_utf8_lossy(&bytes),
            };
            parse_obj(&text, path)
        }
        "stl" => parse_stl(&bytes, path, tol.weld_mm),
        "ply" => parse_ply(&bytes, path, tol.weld_mm),
        _ => Err(MeshIoError::UnknownFormat {
            path: path.to_path_buf(),
        }),
    }
}

/// True when the path has a mesh extension this module reads.
pub fn is_mesh_path(path: &Path) -> bool {
    matches!(
        path.extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .as_deref(),
        Some("obj" | "stl" | "ply")
    )
}

/// The whitespace-separated tokens of a line with their byte offsets in it (the 1-based column an
/// error names is counted from the offset only then, [`ObjCtx::col`]).
fn tokens(line: &str) -> impl Iterator<Item = (usize, &str)> {
    // `char::is_whitespace` of an ASCII byte (which also counts the vertical tab).
    let space = |b: u8| b.is_ascii_whitespace() || b == 0x0b;
    let ascii = line.is_ascii();
    let bytes = line.as_bytes();
    let mut at = 0;
    std::iter::from_fn(move || {
        if ascii {
            while at < bytes.len() && space(bytes[at]) {
                at += 1;
            }
            let start = at;
            while at < bytes.len() && !space(bytes[at]) {
                at += 1;
            }
            return (start < at).then(|| (start, &line[start..at]));
        }
        let rest = &line[at..];
        let skip = rest.find(|c: char| !c.is_whitespace())?;
        let start = at + skip;
        let len = line[start..]
            .find(char::is_whitespace)
            .unwrap_or(line.len() - start);
        at = start + len;
        Some((start, &line[start..at]))
    })
}

struct ObjCtx<'a> {
    path: &'a Path,
    line: usize,
    /// The current line, its comment cut off.
    text: &'a str,
}

impl ObjCtx<'_> {
    /// The 1-based column of the byte at `offset` in the current line.
    fn col(&self, offset: usize) -> usize {
        self.text[..offset].chars().count() + 1
    }

    /// The column just past the line's last token.
    fn eol_col(&self) -> usize {
        self.text.trim_end().chars().count() + 1
    }

    fn parse_err(&self, col: usize, msg: String) -> MeshIoError {
        MeshIoError::Parse {
            path: self.path.to_path_buf(),
            line: self.line,
            col,
            msg,
        }
    }

    fn float(&self, tok: Option<(usize, &str)>, what: &'static str) -> Result<f64, MeshIoError> {
        let Some((at, t)) = tok else {
            return Err(self.parse_err(self.eol_col(), format!("{what} needs more coordinates")));
        };
        let v: f64 = t
            .parse()
            .map_err(|_| self.parse_err(self.col(at), format!("{what}: '{t}' is not a number")))?;
        if !v.is_finite() {
            return Err(MeshIoError::NonFinite {
                path: self.path.to_path_buf(),
                line: self.line,
                col: self.col(at),
                what,
                text: t.to_string(),
            });
        }
        if !flatcut_geom::limits::in_range(v) {
            return Err(MeshIoError::OutOfRange {
                path: self.path.to_path_buf(),
                line: self.line,
                col: self.col(at),
                what,
                value: v,
            });
        }
        Ok(v)
    }

    /// Resolves an OBJ index (1-based, or negative relative to the current count) to 0-based;
    /// `at` is the byte offset of its corner in the line.
    fn index(
        &self,
        text: &str,
        at: usize,
        what: &'static str,
        count: usize,
    ) -> Result<u32, MeshIoError> {
        let i: i64 = text
            .parse()
            .map_err(|_| self.parse_err(self.col(at), format!("'{text}' is not a {what} index")))?;
        let resolved = if i > 0 { i - 1 } else { count as i64 + i };
        if i == 0 || resolved < 0 || resolved >= count as i64 {
            return Err(MeshIoError::BadIndex {
                path: self.path.to_path_buf(),
                line: self.line,
                col: self.col(at),
                what,
                index: i,
                count,
            });
        }
        Ok(resolved as u32)
    }
}

/// What the lines of an OBJ text (or a part of one) define, in file order.
#[derive(Debug, Default, PartialEq)]
struct ObjParts {
    /// Lines read.
    lines: usize,
    positions: Vec<DVec3>,
    texcoords: Vec<DVec2>,
    normal_count: usize,
    /// Triangles of (position, texcoord) corners, indices counted from the file's start.
    corners: Vec<[(u32, Option<u32>); 3]>,
}

/// What the lines before a part of an OBJ text define: the part's line numbers and its indices
/// (relative ones too) count from them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct ObjBefore {
    lines: usize,
    positions: usize,
    texcoords: usize,
    normals: usize,
}

/// Texts (bytes) from which an OBJ is parsed in two halves on two threads; below, a thread
/// costs more than it saves.
const OBJ_PARSE_TWO_THREADS_FROM: usize = 1 << 20;

/// The lines of `text` parsed, a large text in two halves side by side: the second half's
/// thread first counts the lines, vertices, texture coordinates and normals of the first (by
/// the statement keyword alone, a fast pass), then parses its half as if it had read the first.
/// Every line is parsed as in one pass; the first half's error is the file's first, and the
/// second half's errors name their lines and the counts of the whole file at that point.
fn parse_obj_parts(text: &str, path: &Path) -> Result<ObjParts, MeshIoError> {
    let mid = text.len() / 2;
    let split = (text.len() >= OBJ_PARSE_TWO_THREADS_FROM)
        .then(|| text.as_bytes()[mid..].iter().position(|&b| b == b'\n'))
        .flatten()
        .map(|i| mid + i + 1);
    let Some(split) = split else {
        return parse_obj_lines(text, path, ObjBefore::default());
    };
    let (first, second) = text.split_at(split);
    let (a, (before, b)) = std::thread::scope(|s| {
        let b = s.spawn(|| {
            let before = obj_counts(first);
            (before, parse_obj_lines(second, path, before))
        });
        let a = parse_obj_lines(first, path, ObjBefore::default());
        // A panic there is a bug, carried on here as if it were this thread's.
        (a, b.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
    });
    let mut a = a?;
    let read = ObjBefore {
        lines: a.lines,
        positions: a.positions.len(),
        texcoords: a.texcoords.len(),
        normals: a.normal_count,
    };
    if read != before {
        // The keywords counted what the parse read, so this is never met; were it met, the
        // second half was numbered wrong, and one pass is right.
        return parse_obj_lines(text, path, ObjBefore::default());
    }
    let b = b?;
    a.lines += b.lines;
    a.positions.extend(b.positions);
    a.texcoords.extend(b.texcoords);
    a.normal_count += b.normal_count;
    a.corners.extend(b.corners);
    Ok(a)
}

/// A line without its comment.
fn uncommented(raw: &str) -> &str {
    // A byte loop: lines are short, and a search's setup costs more than it saves on them.
    match raw.bytes().position(|b| b == b'#') {
        Some(i) => &raw[..i],
        None => raw,
    }
}

/// The lines of `text` and the vertices, texture coordinates and normals they define, by their
/// keywords, as [`parse_obj_lines`] would read them if they parse.
fn obj_counts(text: &str) -> ObjBefore {
    let mut c = ObjBefore::default();
    for raw in text.lines() {
        c.lines += 1;
        match tokens(uncommented(raw)).next() {
            Some((_, "v")) => c.positions += 1,
            Some((_, "vt")) => c.texcoords += 1,
            Some((_, "vn")) => c.normals += 1,
            _ => {}
        }
    }
    c
}

/// Parses the lines of `text`, a part of an OBJ file after the lines `before` counts.
fn parse_obj_lines(text: &str, path: &Path, before: ObjBefore) -> Result<ObjParts, MeshIoError> {
    let mut out = ObjParts::default();
    let mut ctx = ObjCtx {
        path,
        line: 0,
        text: "",
    };
    // A face's corners, the buffer reused from face to face.
    let mut poly: Vec<(u32, Option<u32>)> = Vec::new();
    for (ln, raw) in text.lines().enumerate() {
        ctx.line = before.lines + ln + 1;
        out.lines = ln + 1;
        let line = uncommented(raw);
        ctx.text = line;
        let mut toks = tokens(line);
        let Some((_, kw)) = toks.next() else {
            continue;
        };
        match kw {
            "v" => {
                let x = ctx.float(toks.next(), "vertex")?;
                let y = ctx.float(toks.next(), "vertex")?;
                let z = ctx.float(toks.next(), "vertex")?;
                out.positions.push(DVec3::new(x, y, z));
            }
            "vt" => {
                let u = ctx.float(toks.next(), "texture coordinate")?;
                let v = match toks.next() {
                    Some(t) => ctx.float(Some(t), "texture coordinate")?,
                    None => 0.0,
                };
                out.texcoords.push(DVec2::new(u, v));
            }
            "vn" => {
                for _ in 0..3 {
                    ctx.float(toks.next(), "normal")?;
                }
                out.normal_count += 1;
            }
            "f" | "fo" => {
                poly.clear();
                for (col, t) in toks {
                    let mut parts = t.split('/');
                    let vi = parts.next().unwrap_or("");
                    let v = ctx.index(vi, col, "vertex", before.positions + out.positions.len())?;
                    let vt = match parts.next() {
                        Some("") | None => None,
                        Some(s) => Some(ctx.index(
                            s,
                            col,
                            "texture coordinate",
                            before.texcoords + out.texcoords.len(),
                        )?),
                    };
                    if let Some(s) = parts.next()
                        && !s.is_empty()
                    {
                        ctx.index(s, col, "normal", before.normals + out.normal_count)?;
                    }
                    if parts.next().is_some() {
                        return Err(ctx.parse_err(
                            ctx.col(col),
                            format!("face corner '{t}' has more than three indices"),
                        ));
                    }
                    poly.push((v, vt));
                }
                if poly.len() < 3 {
                    return Err(ctx.parse_err(
                        1,
                        format!(
                            "a face needs at least 3 corners, this one has {}",
                            poly.len()
                        ),
                    ));
                }
                for k in 1..poly.len() - 1 {
                    out.corners.push([poly[0], poly[k], poly[k + 1]]);
                }
            }
            _ => {}
        }
    }
    Ok(out)
}

/// Parses OBJ text. `path` only names the source in errors.
///
/// Supported: `v x y z [w]` (extra values such as vertex colours are ignored), `vt u [v [w]]`,
/// `vn` (validated, not kept: normals are recomputed from the geometry), `f` with `a`, `a/b`,
/// `a/b/c`, `a//c` corners and negative (relative) indices, polygons fan-triangulated. `o`, `g`,
/// `s`, `usemtl`, `mtllib`, `l`, `p` and unknown statements are ignored; `#` starts a comment.
pub fn parse_obj(text: &str, path: &Path) -> Result<TriMesh, MeshIoError> {
    let ObjParts {
        positions,
        texcoords,
        corners,
        ..
    } = parse_obj_parts(text, path)?;
    if corners.is_empty() {
        return Err(MeshIoError::Empty {
            path: path.to_path_buf(),
        });
    }
    let all_vt = corners.iter().all(|t| t.iter().all(|c| c.1.is_some()));
    if !all_vt {
        return Ok(TriMesh::new(
            positions,
            corners.iter().map(|t| t.map(|c| c.0)).collect(),
        ));
    }
    // One vt per position?
    let mut vt_of: Vec<Option<u32>> = vec![None; positions.len()];
    let mut consistent = true;
    for t in &corners {
        for &(v, vt) in t {
            let vt = vt.unwrap_or(0);
            match vt_of[v as usize] {
                None => vt_of[v as usize] = Some(vt),
                Some(o) if o != vt && texcoords[o as usize] != texcoords[vt as usize] => {
                    consistent = false
                }
                Some(_) => {}
            }
        }
    }
    if consistent {
        let flat = vt_of
            .iter()
            .map(|o| o.map(|i| texcoords[i as usize]).unwrap_or(DVec2::ZERO))
            .collect();
        let mut m = TriMesh::new(positions, corners.iter().map(|t| t.map(|c| c.0)).collect());
        m.flat = Some(flat);
        return Ok(m);
    }
    // Split positions along UV seams: one vertex per distinct (position, texcoord value).
    let mut key_of: BTreeMap<(u32, [u64; 2]), u32> = BTreeMap::new();
    let mut new_pos = Vec::new();
    let mut flat = Vec::new();
    let mut tris = Vec::with_capacity(corners.len());
    for t in &corners {
        let tri = t.map(|(v, vt)| {
            let uv = texcoords[vt.unwrap_or(0) as usize];
            let key = (v, [uv.x.to_bits(), uv.y.to_bits()]);
            *key_of.entry(key).or_insert_with(|| {
                new_pos.push(positions[v as usize]);
                flat.push(uv);
                (new_pos.len() - 1) as u32
            })
        });
        tris.push(tri);
    }
    let mut m = TriMesh::new(new_pos, tris);
    m.flat = Some(flat);
    Ok(m)
}

/// Parses STL bytes (ASCII or binary, detected by `stl_io`), welding corners within `weld_mm`.
pub fn parse_stl(bytes: &[u8], path: &Path, weld_mm: f64) -> Result<TriMesh, MeshIoError> {
    if bytes.iter().all(|b| b.is_ascii_whitespace()) {
        return Err(MeshIoError::Empty {
            path: path.to_path_buf(),
        });
    }
    let mut cur = std::io::Cursor::new(bytes);
    let fmt = |e: std::io::Error| MeshIoError::Format {
        path: path.to_path_buf(),
        msg: format!("not a valid STL file: {e}"),
    };
    let reader = stl_io::create_stl_reader(&mut cur).map_err(fmt)?;
    let mut pts = Vec::new();
    for (t, tri) in reader.enumerate() {
        let tri = tri.map_err(|e| MeshIoError::Format {
            path: path.to_path_buf(),
            msg: format!("facet {t}: {e}"),
        })?;
        for (k, v) in tri.vertices.iter().enumerate() {
            let p = DVec3::new(v.0[0] as f64, v.0[1] as f64, v.0[2] as f64);
            if let Some(x) = p
                .to_array()
                .into_iter()
                .find(|x| !flatcut_geom::limits::in_range(*x))
            {
                return Err(MeshIoError::Format {
                    path: path.to_path_buf(),
                    msg: format!(
                        "facet {t} corner {k}: coordinate {}",
                        flatcut_geom::limits::out_of_range_reason(x)
                    ),
                });
            }
            pts.push(p);
        }
    }
    if pts.is_empty() {
        return Err(MeshIoError::Empty {
            path: path.to_path_buf(),
        });
    }
    let tris = (0..pts.len() as u32 / 3)
        .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
        .collect();
    let m = TriMesh::new(pts, tris).welded(weld_mm);
    if m.triangles.is_empty() {
        return Err(MeshIoError::Empty {
            path: path.to_path_buf(),
        });
    }
    Ok(m)
}

fn ply_scalar(p: &ply_rs_bw::ply::Property) -> Option<f64> {
    use ply_rs_bw::ply::Property as P;
    Some(match *p {
        P::Char(v) => v as f64,
        P::UChar(v) => v as f64,
        P::Short(v) => v as f64,
        P::UShort(v) => v as f64,
        P::Int(v) => v as f64,
        P::UInt(v) => v as f64,
        P::Float(v) => v as f64,
        P::Double(v) => v,
        _ => return None,
    })
}

fn ply_list(p: &ply_rs_bw::ply::Property) -> Option<Vec<i64>> {
    use ply_rs_bw::ply::Property as P;
    Some(match p {
        P::ListChar(v) => v.iter().map(|&x| x as i64).collect(),
        P::ListUChar(v) => v.iter().map(|&x| x as i64).collect(),
        P::ListShort(v) => v.iter().map(|&x| x as i64).collect(),
        P::ListUShort(v) => v.iter().map(|&x| x as i64).collect(),
        P::ListInt(v) => v.iter().map(|&x| x as i64).collect(),
        P::ListUInt(v) => v.iter().map(|&x| x as i64).collect(),
        _ => return None,
    })
}

/// Parses PLY bytes (ASCII or binary). Needs a `vertex` element with `x`, `y`, `z` and a `face`
/// element with a `vertex_indices` (or `vertex_index`) list; `u`/`v` or `s`/`t` per vertex become
/// the flattening. Vertices are welded within `weld_mm`.
pub fn parse_ply(bytes: &[u8], path: &Path, weld_mm: f64) -> Result<TriMesh, MeshIoError> {
    if bytes.is_empty() {
        return Err(MeshIoError::Empty {
            path: path.to_path_buf(),
        });
    }
    let fmt = |msg: String| MeshIoError::Format {
        path: path.to_path_buf(),
        msg,
    };
    let parser = ply_rs_bw::parser::Parser::<ply_rs_bw::ply::DefaultElement>::new();
    let mut cur = std::io::Cursor::new(bytes);
    let ply = parser
        .read_ply(&mut cur)
        .map_err(|e| fmt(format!("not a valid PLY file: {e}")))?;
    let verts = ply
        .payload
        .get("vertex")
        .ok_or_else(|| fmt("no 'vertex' element".into()))?;
    let mut positions = Vec::with_capacity(verts.len());
    let mut uv = Vec::with_capacity(verts.len());
    let mut has_uv = true;
    for (i, v) in verts.iter().enumerate() {
        let get = |k: &str| v.get(k).and_then(ply_scalar);
        let (Some(x), Some(y), Some(z)) = (get("x"), get("y"), get("z")) else {
            return Err(fmt(format!("vertex {i} lacks a numeric x, y or z")));
        };
        if let Some(c) = [x, y, z]
            .into_iter()
            .find(|c| !flatcut_geom::limits::in_range(*c))
        {
            return Err(fmt(format!(
                "vertex {i}: coordinate {}",
                flatcut_geom::limits::out_of_range_reason(c)
            )));
        }
        positions.push(DVec3::new(x, y, z));
        match (get("u").or(get("s")), get("v").or(get("t"))) {
            (Some(a), Some(b))
                if flatcut_geom::limits::in_range(a) && flatcut_geom::limits::in_range(b) =>
            {
                uv.push(DVec2::new(a, b))
            }
            _ => has_uv = false,
        }
    }
    let faces = ply.payload.get("face").map(|f| f.as_slice()).unwrap_or(&[]);
    let mut tris = Vec::new();
    for (fi, f) in faces.iter().enumerate() {
        let list = f
            .get("vertex_indices")
            .or_else(|| f.get("vertex_index"))
            .and_then(ply_list)
            .ok_or_else(|| fmt(format!("face {fi} has no vertex_indices list")))?;
        if list.len() < 3 {
            return Err(fmt(format!(
                "face {fi} has {} corners, needs at least 3",
                list.len()
            )));
        }
        for &i in &list {
            if i < 0 || i as usize >= positions.len() {
                return Err(fmt(format!(
                    "face {fi} refers to vertex {i}, but the file has {} vertices",
                    positions.len()
                )));
            }
        }
        for k in 1..list.len() - 1 {
            tris.push([list[0] as u32, list[k] as u32, list[k + 1] as u32]);
        }
    }
    if tris.is_empty() {
        return Err(MeshIoError::Empty {
            path: path.to_path_buf(),
        });
    }
    let mut m = TriMesh::new(positions, tris);
    if has_uv {
        m.flat = Some(uv);
        // Welding would merge vertices on a UV seam; keep the file's vertices.
        return Ok(m);
    }
    Ok(m.welded(weld_mm))
}

/// Formats a mesh as OBJ text: `v` per vertex, one `vt` per vertex (mm, true scale) when the mesh
/// has a flattening, and `f a/a b/b c/c` (or `f a b c`). Coordinates are the shortest decimals
/// that read back to the same bits ([`crate::decimal`]), so the file is the map that was
/// measured, never `-0` for a zero.
pub fn obj_string(mesh: &TriMesh) -> String {
    use crate::decimal::push_uint;
    // About 30 bytes a vertex line and 25 a face.
    let mut s = String::with_capacity(
        64 + 30 * mesh.positions.len() * (1 + usize::from(mesh.flat.is_some()))
            + 25 * mesh.triangles.len(),
    );
    s.push_str("# flatcut mesh: ");
    push_uint(&mut s, mesh.positions.len() as u64);
    s.push_str(" vertices, ");
    push_uint(&mut s, mesh.triangles.len() as u64);
    s.push_str(" triangles, millimetres\n");
    if mesh.triangles.len() < OBJ_TWO_THREADS_FROM {
        push_vertex_lines(&mut s, mesh);
        push_face_lines(&mut s, mesh);
        return s;
    }
    // Each part's text is its own: the faces are written on another thread while the vertices
    // are written here, then appended.
    std::thread::scope(|scope| {
        let faces = scope.spawn(|| {
            let mut f = String::with_capacity(25 * mesh.triangles.len());
            push_face_lines(&mut f, mesh);
            f
        });
        push_vertex_lines(&mut s, mesh);
        // A panic there is a bug, carried on here as if it were this thread's.
        let faces = faces
            .join()
            .unwrap_or_else(|e| std::panic::resume_unwind(e));
        s.push_str(&faces);
    });
    s
}

/// Faces from which [`obj_string`] writes the vertex and face lines on two threads; below, a
/// thread costs more than it saves.
const OBJ_TWO_THREADS_FROM: usize = 50_000;

/// The `v` lines, then the `vt` lines of a flattened mesh.
fn push_vertex_lines(s: &mut String, mesh: &TriMesh) {
    use crate::decimal::push;
    let z = |x: f64| if x == 0.0 { 0.0 } else { x }; // no "-0.000000"
    let coords = |s: &mut String, tag: &str, xs: &[f64]| {
        s.push_str(tag);
        for &x in xs {
            s.push(' ');
            push(s, z(x));
        }
        s.push('\n');
    };
    for p in &mesh.positions {
        coords(s, "v", &[p.x, p.y, p.z]);
    }
    if let Some(f) = &mesh.flat {
        for q in f {
            coords(s, "vt", &[q.x, q.y]);
        }
    }
}

/// The `f` lines, `f a/a b/b c/c` for a flattened mesh (1-based).
fn push_face_lines(s: &mut String, mesh: &TriMesh) {
    use crate::decimal::push_uint;
    for t in &mesh.triangles {
        s.push('f');
        for i in t.map(|i| u64::from(i) + 1) {
            s.push(' ');
            push_uint(s, i);
            if mesh.flat.is_some() {
                s.push('/');
                push_uint(s, i);
            }
        }
        s.push('\n');
    }
}

/// Writes bytes atomically: to a temporary file in the target's directory, then renamed.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), MeshIoError> {
    let io = |source| MeshIoError::Io {
        path: path.to_path_buf(),
        source,
    };
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
    let res = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if res.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    res.map_err(io)
}

/// Writes the mesh as OBJ (see [`obj_string`]), atomically.
pub fn write_obj(mesh: &TriMesh, path: &Path) -> Result<(), MeshIoError> {
    write_atomic(path, obj_string(mesh).as_bytes())
}

/// Writes the mesh as binary STL (f32 coordinates, facet normals from the geometry), atomically.
pub fn write_stl(mesh: &TriMesh, path: &Path) -> Result<(), MeshIoError> {
    let tris: Vec<stl_io::Triangle> = (0..mesh.triangles.len())
        .map(|t| {
            let c = mesh.corners(t);
            let n = (c[1] - c[0]).cross(c[2] - c[0]).normalize_or_zero();
            stl_io::Triangle {
                normal: stl_io::Normal::new([n.x as f32, n.y as f32, n.z as f32]),
                vertices: c.map(|p| stl_io::Vertex::new([p.x as f32, p.y as f32, p.z as f32])),
            }
        })
        .collect();
    let mut buf = Vec::new();
    stl_io::write_stl(&mut buf, tris.iter()).map_err(|source| MeshIoError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    write_atomic(path, &buf)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p() -> &'static Path {
        Path::new("test.obj")
    }

    #[test]
    fn obj_faces_of_all_forms_and_polygons() {
        let text = "# a quad and a triangle\no thing\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0 1.0\nvn 0 0 1\ng grp\nf 1 2 3 4\nf -4//1 -2//1 -1//1\n";
        let m = parse_obj(text, p()).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 2, 3]]);
        assert!(m.flat.is_none());
    }

    #[test]
    fn obj_consistent_vt_maps_to_flat() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 10 0\nvt 0 10\nvt 10 10\nf 1/1 2/2 3/3\nf 2/2 4/4 3/3\n";
        let m = parse_obj(text, p()).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.flat.as_ref().unwrap()[3], DVec2::new(10.0, 10.0));
    }

    #[test]
    fn obj_inconsistent_vt_splits_vertices() {
        // Vertex 2 and 3 carry different vt in the two triangles: a UV seam along edge 2-3.
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 5 5\nvt 6 6\nvt 7 7\nf 1/1 2/2 3/3\nf 2/4 4/5 3/6\n";
        let m = parse_obj(text, p()).unwrap();
        assert_eq!(m.positions.len(), 6);
        assert_eq!(m.triangles, vec![[0, 1, 2], [3, 4, 5]]);
        let f = m.flat.unwrap();
        assert_eq!(f[3], DVec2::new(5.0, 5.0));
        assert_eq!(m.positions[3], m.positions[1]);
    }

    #[test]
    fn obj_errors_name_line_and_column() {
        let e = parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n", p()).unwrap_err();
        match &e {
            MeshIoError::BadIndex {
                line,
                col,
                index,
                count,
                ..
            } => assert_eq!((*line, *col, *index, *count), (4, 7, 7, 3)),
            other => panic!("{other:?}"),
        }
        assert!(e.to_string().starts_with("test.obj:4:7:"), "{e}");
        let e = parse_obj("v 0 0 0\nv 1 nan 0\n", p()).unwrap_err();
        assert!(
            matches!(
                e,
                MeshIoError::NonFinite {
                    line: 2,
                    col: 5,
                    ..
                }
            ),
            "{e:?}"
        );
        let e = parse_obj("v 0 0 0\n  v 1 inf 0\n", p()).unwrap_err();
        assert!(
            matches!(
                e,
                MeshIoError::NonFinite {
                    line: 2,
                    col: 7,
                    ..
                }
            ),
            "{e:?}"
        );
        let e = parse_obj("v 0 0 x0\n", p()).unwrap_err();
        assert!(
            matches!(
                e,
                MeshIoError::Parse {
                    line: 1,
                    col: 7,
                    ..
                }
            ),
            "{e:?}"
        );
        let e = parse_obj("v 0 0\n", p()).unwrap_err();
        assert!(
            matches!(
                e,
                MeshIoError::Parse {
                    line: 1,
                    col: 6,
                    ..
                }
            ),
            "{e:?}"
        );
        let e = parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", p()).unwrap_err();
        assert!(matches!(e, MeshIoError::BadIndex { index: 0, .. }), "{e:?}");
        let e = parse_obj("v 0 0 0\nv 1 0 0\nf 1 -3 2\n", p()).unwrap_err();
        assert!(
            matches!(
                e,
                MeshIoError::BadIndex {
                    index: -3,
                    col: 5,
                    ..
                }
            ),
            "{e:?}"
        );
        let e = parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/4 2 3\n", p()).unwrap_err();
        assert!(
            matches!(
                e,
                MeshIoError::BadIndex {
                    what: "texture coordinate",
                    ..
                }
            ),
            "{e:?}"
        );
        let e = parse_obj("v 0 0 0\nv 1 0 0\nf 1 2\n", p()).unwrap_err();
        assert!(matches!(e, MeshIoError::Parse { line: 3, .. }), "{e:?}");
        assert!(matches!(parse_obj("", p()), Err(MeshIoError::Empty { .. })));
        assert!(matches!(
            parse_obj("# only comments\nv 1 2 3\n", p()),
            Err(MeshIoError::Empty { .. })
        ));
    }

    #[test]
    fn obj_round_trip_is_bit_exact_and_deterministic() {
        // Values no fixed number of decimals writes exactly: thirds, a sliver's micrometres,
        // the last bit of a large coordinate.
        let third = 1.0 / 3.0;
        let mut m = TriMesh::new(
            vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(12.345678, -0.0, 1.0 + f64::EPSILON),
                DVec3::new(third, 3.0e-7, -7.25),
            ],
            vec![[0, 1, 2]],
        );
        m.flat = Some(vec![
            DVec2::new(-0.0, 0.0),
            DVec2::new(12.0 + 2.0 * third, 1e-9),
            DVec2::new(0.5, 123_456.789_012_345_67),
        ]);
        let s = obj_string(&m);
        let body = &s[s.find('\n').unwrap()..];
        assert!(!body.contains("-0") && !body.contains('e'), "{s}");
        assert_eq!(s, obj_string(&m.clone()));
        let back = parse_obj(&s, p()).unwrap();
        let bits = |v: &[DVec3]| {
            v.iter()
                .map(|p| p.to_array().map(f64::to_bits))
                .collect::<Vec<_>>()
        };
        let bits2 = |v: &[DVec2]| {
            v.iter()
                .map(|p| p.to_array().map(f64::to_bits))
                .collect::<Vec<_>>()
        };
        let zeroed = |v: &[DVec3]| v.iter().map(|p| *p + DVec3::ZERO).collect::<Vec<_>>();
        let zeroed2 = |v: &[DVec2]| v.iter().map(|p| *p + DVec2::ZERO).collect::<Vec<_>>();
        assert_eq!(bits(&back.positions), bits(&zeroed(&m.positions)));
        assert_eq!(back.triangles, m.triangles);
        assert_eq!(
            bits2(back.flat.as_ref().unwrap()),
            bits2(&zeroed2(m.flat.as_ref().unwrap()))
        );
    }

    #[test]
    fn a_large_obj_is_parsed_in_two_halves_as_in_one_pass() {
        let mut m = crate::test_grid::grid_mesh(120, 120, |i, j| {
            DVec3::new(i as f64 * 0.3, j as f64 * 0.7, (i * j) as f64 * 1e-3)
        });
        m.flat = Some(m.positions.iter().map(|p| DVec2::new(p.x, -p.y)).collect());
        let text = obj_string(&m);
        assert!(text.len() >= OBJ_PARSE_TWO_THREADS_FROM);
        let faces_at = text.find("\nf ").unwrap() + 1;
        // The halves split among the faces, which refer to vertices of the first half.
        assert!(faces_at < text.len() / 2);
        let same = |t: &str| {
            let one = parse_obj_lines(t, p(), ObjBefore::default());
            let two = parse_obj_parts(t, p());
            assert_eq!(format!("{two:?}"), format!("{one:?}"));
            two
        };
        let whole = same(&text).unwrap();
        assert_eq!(whole.corners.len(), m.triangles.len());
        // Relative indices and vertices defined after faces, in the second half.
        let more = format!("{text}v 1 2 3\nvt 4 5\nf -1/-1 1/1 2/2\nf -3/1 -2/2 -1/3 # end\n");
        assert_eq!(same(&more).unwrap().corners.len(), m.triangles.len() + 2);
        // Errors in the second half name their line and the whole file's counts there.
        let e = same(&format!("{text}f 1 2 {}\n", m.positions.len() + 1)).unwrap_err();
        let lines = text.lines().count();
        assert!(
            matches!(e, MeshIoError::BadIndex { line, count, .. }
                if line == lines + 1 && count == m.positions.len()),
            "{e:?}"
        );
        let e = same(&format!("{text}v 1 x 3\n")).unwrap_err();
        assert!(matches!(e, MeshIoError::Parse { line, col: 5, .. } if line == lines + 1));
        // Faces before the vertices they name: the first half's error, the file's first.
        let (head, faces) = text.split_at(faces_at);
        let e = same(&format!("{faces}{head}")).unwrap_err();
        assert!(
            matches!(
                e,
                MeshIoError::BadIndex {
                    line: 1,
                    count: 0,
                    ..
                }
            ),
            "{e:?}"
        );
        // An error in each half: the first half's.
        let e = same(&format!("{text}\nf 0 1 2\n").replacen("\nv ", "\nv 1 2 zz\nv ", 1));
        assert!(
            matches!(e, Err(MeshIoError::Parse { line: 2, .. })),
            "{e:?}"
        );
    }

    #[test]
    fn a_large_mesh_is_written_on_two_threads_as_on_one() {
        let mut m = crate::test_grid::grid_mesh(170, 170, |i, j| {
            DVec3::new(i as f64 * 0.3, j as f64 * 0.7, (i * j) as f64 * 1e-3)
        });
        assert!(m.triangles.len() >= OBJ_TWO_THREADS_FROM);
        m.flat = Some(m.positions.iter().map(|p| DVec2::new(p.x, -p.y)).collect());
        let s = obj_string(&m);
        let mut one = String::new();
        push_vertex_lines(&mut one, &m);
        push_face_lines(&mut one, &m);
        let header_end = s.find('\n').unwrap() + 1;
        assert_eq!(&s[header_end..], one);
        assert!(s.starts_with("# flatcut mesh: 29241 vertices, 57800 triangles"));
        let back = parse_obj(&s, p()).unwrap();
        assert_eq!(back.triangles, m.triangles);
    }

    fn tmpdir(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("flatcut-mesh-io-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn files_dispatch_on_extension_and_write_atomically() {
        let d = tmpdir("dispatch");
        let m = TriMesh::new(
            vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(1.0, 1.0, 0.0),
                DVec3::new(0.0, 1.0, 0.5),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        let obj = d.join("a.OBJ");
        write_obj(&m, &obj).unwrap();
        assert_eq!(read_mesh(&obj).unwrap().triangles, m.triangles);
        let stl = d.join("a.stl");
        write_stl(&m, &stl).unwrap();
        let back = read_mesh(&stl).unwrap();
        assert_eq!(back.positions.len(), 4, "STL corners are welded");
        assert_eq!(back.triangles.len(), 2);
        assert!((back.area() - m.area()).abs() < 1e-6);
        // No temporary file is left behind.
        let names: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert!(names.iter().all(|n| !n.contains(".tmp")), "{names:?}");
        assert!(matches!(
            read_mesh(&d.join("a.xyz")),
            Err(MeshIoError::Io { .. })
        ));
        std::fs::write(d.join("b.xyz"), "x").unwrap();
        assert!(matches!(
            read_mesh(&d.join("b.xyz")),
            Err(MeshIoError::UnknownFormat { .. })
        ));
        std::fs::write(d.join("e.stl"), "").unwrap();
        assert!(matches!(
            read_mesh(&d.join("e.stl")),
            Err(MeshIoError::Empty { .. })
        ));
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn ascii_stl_with_nan_is_rejected() {
        let good = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
        let m = parse_stl(good.as_bytes(), Path::new("t.stl"), 1e-3).unwrap();
        assert_eq!(m.triangles.len(), 1);
        let bad = good.replace("vertex 1 0 0", "vertex 1 nan 0");
        let e = parse_stl(bad.as_bytes(), Path::new("t.stl"), 1e-3).unwrap_err();
        assert!(e.to_string().starts_with("t.stl:"), "{e}");
    }

    #[test]
    fn ply_ascii_and_binary() {
        let ascii = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
        let m = parse_ply(ascii.as_bytes(), Path::new("q.ply"), 1e-3).unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        let mut bin = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n".to_vec();
        for v in [[0.0f64, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 1.0]] {
            for c in v {
                bin.extend_from_slice(&c.to_le_bytes());
            }
        }
        bin.push(3);
        for i in [0u32, 1, 2] {
            bin.extend_from_slice(&i.to_le_bytes());
        }
        let m = parse_ply(&bin, Path::new("b.ply"), 1e-3).unwrap();
        assert_eq!(m.positions[2], DVec3::new(0.0, 2.0, 1.0));
        let bad = ascii.replace("4 0 1 2 3", "3 0 1 9");
        let e = parse_ply(bad.as_bytes(), Path::new("q.ply"), 1e-3).unwrap_err();
        assert!(e.to_string().contains("face 0 refers to vertex 9"), "{e}");
        let nan = ascii.replace("1 1 0\n", "1 nan 0\n");
        assert!(parse_ply(nan.as_bytes(), Path::new("q.ply"), 1e-3).is_err());
    }

    proptest::proptest! {
        #[test]
        fn obj_round_trip_property(
            pts in proptest::collection::vec((-1_000_000i64..1_000_000i64, -1_000_000i64..1_000_000i64, -1_000_000i64..1_000_000i64), 3..40),
            seed in 0u64..1000,
        ) {
            // Coordinates on the written 1e-6 grid round-trip exactly.
            let positions: Vec<DVec3> = pts
                .iter()
                .map(|&(x, y, z)| DVec3::new(x as f64 * 1e-3, y as f64 * 1e-3, z as f64 * 1e-3))
                .collect();
            let n = positions.len() as u64;
            let triangles: Vec<[u32; 3]> = (0..n)
                .map(|k| {
                    let a = (k * 7 + seed) % n;
                    [a as u32, ((a + 1) % n) as u32, ((a + 2) % n) as u32]
                })
                .collect();
            let m = TriMesh::new(positions, triangles);
            let back = parse_obj(&obj_string(&m), p()).unwrap();
            proptest::prop_assert_eq!(back.triangles, m.triangles);
            for (a, b) in back.positions.iter().zip(&m.positions) {
                proptest::prop_assert!((*a - *b).abs().max_element() <= 5e-7);
            }
        }
    }
    #[test]
    fn coordinates_beyond_the_sane_range_name_file_line_and_column() {
        let p = Path::new("far.obj");
        let e = parse_obj("v 0 0 0\nv 1 0 0\nv 0 -1e308 0\nf 1 2 3\n", p)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("far.obj:3:5: vertex coordinate") && e.contains("beyond"),
            "{e}"
        );
        let e = parse_obj("v 0 0 0\nvt 1e7 0\n", p).unwrap_err().to_string();
        assert!(e.contains("far.obj:2:4: texture coordinate"), "{e}");
        let ply = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1e30 0\n3 0 1 2\n";
        let e = parse_ply(ply, Path::new("far.ply"), 1e-3)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("far.ply: vertex 2: coordinate") && e.contains("beyond"),
            "{e}"
        );
    }

    #[test]
    fn index_errors_count_in_plain_english() {
        let p = Path::new("i.obj");
        let e = parse_obj("v 0 0 0\nf 1 2 3\n", p).unwrap_err().to_string();
        assert!(e.contains("(the file has 1 vertex at this point)"), "{e}");
        let e = parse_obj("v 0 0 0\nv 1 0 0\nf 1 2 3\n", p)
            .unwrap_err()
            .to_string();
        assert!(e.contains("(the file has 2 vertices at this point)"), "{e}");
        let e = parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/2 3/3\n", p)
            .unwrap_err()
            .to_string();
        assert!(e.contains("the file has 0 texture coordinates"), "{e}");
    }
}
