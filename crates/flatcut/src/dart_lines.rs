//! A darted piece's darts in its flat OBJ, so that a later `pattern`, `report` or `run` on that
//! file draws them as darts (a sew line, notches, a drill mark, the mouth bridged by the cut
//! line) rather than as a notch cut deep into the outline.
//!
//! Each dart is a group `g dart-<k>` holding one OBJ polyline (`l`): its sew line, the first
//! leg from the mouth to the point, then the second back to the mouth, by vertex index. OBJ
//! readers that know no `l` elements skip them; the mesh itself is unchanged.

use std::fmt::Write as _;

use flatcut_darts::{Dart, Legs};
use flatcut_geom::DVec2;
use flatcut_mesh::TriMesh;

use crate::obj_vertex::obj_vertex;

/// Prefix of a dart's group name.
const GROUP: &str = "dart-";

/// The OBJ lines of `darts` (to follow the mesh's own lines).
pub fn write(darts: &[Dart]) -> String {
    let mut s = String::new();
    for (k, d) in darts.iter().enumerate() {
        let [a, b] = &d.legs.sides;
        let _ = write!(s, "g {GROUP}{}\nl", k + 1);
        for v in a.iter().chain(b.iter().rev().skip(1)) {
            let _ = write!(s, " {}", v + 1);
        }
        s.push('\n');
    }
    s
}

/// The darts written by [`write()`] in the OBJ text `text` of `mesh` (its flat map `x`), measured
/// again with their drill marks `drill_mm` short of their points. A line in a dart group that
/// cannot be a sew line (an even vertex count, fewer than three, an index out of range) is an
/// error naming its line.
pub fn read(text: &str, mesh: &TriMesh, x: &[DVec2], drill_mm: f64) -> Result<Vec<Dart>, String> {
    let mut darts = Vec::new();
    let mut in_dart = false;
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if let Some(name) = line.strip_prefix("g ") {
            in_dart = name.trim().starts_with(GROUP);
            continue;
        }
        let Some(rest) = line.strip_prefix("l ").filter(|_| in_dart) else {
            continue;
        };
        let at = |what: String| format!("line {}: {what}", i + 1);
        let ids = rest
            .split_whitespace()
            .map(|t| obj_vertex(t, mesh.positions.len()).map_err(at))
            .collect::<Result<Vec<u32>, String>>()?;
        if ids.len() < 3 || ids.len() % 2 == 0 {
            return Err(at(format!(
                "a dart's sew line runs mouth, point, mouth, an odd number of vertices (3 or more); it has {}",
                ids.len()
            )));
        }
        let mid = ids.len() / 2;
        let first: Vec<u32> = ids[..=mid].to_vec();
        let second: Vec<u32> = ids[mid..].iter().rev().copied().collect();
        let legs = Legs {
            sides: [first, second],
        };
        darts.push(Dart::measure(mesh, &legs.sides[0], &legs, x, drill_mm));
    }
    Ok(darts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_geom::DVec3;

    /// A wedge cut into a square: vertices 0–3 the corners, 4 the point, 5 and 6 the mouth's
    /// corners on the bottom edge.
    fn notched() -> (TriMesh, Vec<DVec2>) {
        let x: Vec<DVec2> = [
            (0.0, 0.0),
            (10.0, 0.0),
            (10.0, 10.0),
            (0.0, 10.0),
            (5.0, 5.0),
            (4.0, 0.0),
            (6.0, 0.0),
        ]
        .into_iter()
        .map(|(a, b)| DVec2::new(a, b))
        .collect();
        let mesh = TriMesh {
            positions: x.iter().map(|p| DVec3::new(p.x, p.y, 0.0)).collect(),
            triangles: vec![[0, 5, 4], [0, 4, 3], [3, 4, 2], [4, 6, 1], [4, 1, 2]],
            flat: Some(x.clone()),
            ..Default::default()
        };
        (mesh, x)
    }

    #[test]
    fn a_dart_written_is_read_back_with_its_measures() {
        let (mesh, x) = notched();
        let legs = Legs {
            sides: [vec![5, 4], vec![6, 4]],
        };
        let dart = Dart::measure(&mesh, &legs.sides[0], &legs, &x, 1.0);
        let text = write(std::slice::from_ref(&dart));
        assert_eq!(text, "g dart-1\nl 6 5 7\n");
        let back = read(&format!("v 0 0 0\n{text}g other\nl 1 2\n"), &mesh, &x, 1.0).unwrap();
        assert_eq!(back.len(), 1);
        let b = &back[0];
        assert_eq!(b.legs, dart.legs);
        assert_eq!(b.opening_mm, 2.0);
        assert_eq!(b.leg_2d_mm, dart.leg_2d_mm);
        assert_eq!(b.drill_2d, dart.drill_2d);
    }

    #[test]
    fn a_broken_dart_line_names_its_line() {
        let (mesh, x) = notched();
        let e = read("g dart-1\nl 6 5\n", &mesh, &x, 1.0).unwrap_err();
        assert!(e.starts_with("line 2:") && e.contains("odd number"), "{e}");
        let e = read("g dart-1\nl 6 9 7\n", &mesh, &x, 1.0).unwrap_err();
        assert!(e.contains("vertex index 9 is out of range"), "{e}");
    }
}
