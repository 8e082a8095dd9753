//! A piece's name and notches in its flat OBJ, so that a later `report`, `pattern` or `run` on
//! that file names the piece as the design did and finds its notches (and the mating seams'
//! notches between pieces read from files) where the design put them.
//!
//! The name is the OBJ's object statement, `o <name>`, the file's first line. Each notch is a
//! group `g notch <name>` holding one OBJ point element (`p <vertex>`), after the faces. OBJ
//! readers that know no `p` elements skip them; the mesh itself is unchanged.

use std::fmt::Write as _;

use flatcut_mesh::TriMesh;

use crate::obj_vertex::obj_vertex;

use crate::flat_piece::FlatNotch;

/// The group a notch's point is in: `g notch <name>`.
const GROUP: &str = "notch";

/// The object statement naming a piece (newlines and other control characters become spaces).
pub fn write_name(name: &str) -> String {
    format!("o {}\n", one_line(name))
}

/// The name of the first object statement of an OBJ text, if it has one: the rest of its line
/// (a name may hold `#`, which [`write_name`] writes as it is).
pub fn read_name(text: &str) -> Option<String> {
    text.lines()
        .map(str::trim)
        .find_map(|l| l.strip_prefix("o ").or_else(|| l.strip_prefix("o\t")))
        .map(|n| n.trim().to_string())
        .filter(|n| !n.is_empty())
}

/// The OBJ lines of `notches` (to follow the mesh's own lines).
pub fn write(notches: &[FlatNotch]) -> String {
    let mut s = String::new();
    for n in notches {
        let _ = write!(s, "g {GROUP} {}\np {}\n", one_line(&n.name), n.vertex + 1);
    }
    s
}

/// `s` on one line: control characters (a newline) become spaces, the ends trimmed.
fn one_line(s: &str) -> String {
    let line: String = s
        .chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect();
    line.trim().to_string()
}

/// The notches written by [`write()`] in the OBJ text `text` of `mesh`. A point in a notch group
/// that is not one vertex index of a boundary vertex is an error naming its line.
pub fn read(text: &str, mesh: &TriMesh) -> Result<Vec<FlatNotch>, String> {
    let boundary: std::collections::BTreeSet<u32> = flatcut_mesh::Topology::build(mesh)
        .map(|t| t.boundary_loops.into_iter().flatten().collect())
        .unwrap_or_default();
    let mut notches = Vec::new();
    let mut name: Option<String> = None;
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if let Some(group) = line.strip_prefix("g ") {
            let mut words = group.split_whitespace();
            name = (words.next() == Some(GROUP)).then(|| words.collect::<Vec<_>>().join(" "));
            continue;
        }
        let (Some(rest), Some(name)) = (line.strip_prefix("p "), &name) else {
            continue;
        };
        let at = |what: String| format!("line {}: notch '{name}': {what}", i + 1);
        let ids: Vec<&str> = rest.split_whitespace().collect();
        let [t] = ids.as_slice() else {
            return Err(at(format!(
                "a notch is one vertex, the line names {}",
                ids.len()
            )));
        };
        let vertex = obj_vertex(t, mesh.positions.len()).map_err(at)?;
        if !boundary.contains(&vertex) {
            return Err(at(format!(
                "vertex {} is not on the piece's boundary; a notch sits on its outline",
                vertex + 1
            )));
        }
        notches.push(FlatNotch {
            name: name.clone(),
            vertex,
        });
    }
    Ok(notches)
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_geom::DVec3;

    /// Two triangles making a unit square: every vertex on the boundary, plus an inner vertex 4
    /// in a fan of four.
    fn square() -> TriMesh {
        let positions = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (0.5, 0.5)]
            .into_iter()
            .map(|(x, y)| DVec3::new(x, y, 0.0))
            .collect();
        TriMesh::new(positions, vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
    }

    #[test]
    fn notches_written_are_read_back_by_name_and_vertex() {
        let notches = vec![
            FlatNotch {
                name: "back 1".into(),
                vertex: 1,
            },
            FlatNotch {
                name: "toe".into(),
                vertex: 3,
            },
        ];
        let text = write(&notches);
        assert_eq!(text, "g notch back 1\np 2\ng notch toe\np 4\n");
        let back = read(&format!("v 0 0 0\n{text}g dart-1\np 3\n"), &square()).unwrap();
        assert_eq!(back, notches);
    }

    #[test]
    fn a_notch_off_the_outline_or_out_of_range_names_its_line() {
        let e = read("g notch a\np 5\n", &square()).unwrap_err();
        assert!(
            e.starts_with("line 2: notch 'a'") && e.contains("boundary"),
            "{e}"
        );
        let e = read("g notch a\np 9\n", &square()).unwrap_err();
        assert!(e.contains("vertex index 9 is out of range"), "{e}");
        let e = read("g notch a\np 1 2\n", &square()).unwrap_err();
        assert!(e.contains("one vertex"), "{e}");
    }

    #[test]
    fn the_object_name_is_the_first_o_statement() {
        assert_eq!(write_name("toe cap 40"), "o toe cap 40\n");
        assert_eq!(write_name("vamp #1\nL"), "o vamp #1 L\n");
        assert_eq!(
            read_name("# c\no vamp #1 L\no other\nv 0 0 0\n").as_deref(),
            Some("vamp #1 L")
        );
        assert_eq!(read_name("v 0 0 0\n"), None);
        assert_eq!(read_name("o \n"), None);
    }
}
