//! Reading a hide from JSON, DXF or SVG. Elements are told apart by name: in a DXF by layer, in
//! an SVG by element id (case-insensitive):
//!
//! | name starts with | is |
//! |---|---|
//! | `defect`, `hole`, `scar` | a defect (closed) |
//! | `quality-N`, `grade-N`, `zone-N` | a zone of grade N ≥ 2 (closed) |
//! | `direction`, `backbone`, `grain` | a direction line (open or closed) |
//! | anything else | the outline: the largest closed contour |
//!
//! JSON: `{"name": …, "outline": [[x, y], …], "defects": [[[x, y], …], …],
//! "zones": [{"grade": 2, "outline": [[x, y], …]}], "directions": [[[x, y], …], …]}` (mm).

use crate::error::NestError;
use crate::problem::polygon_area;
use crate::stock::{Hide, QualityZone};
use flatcut_geom::DVec2;
use serde::Deserialize;

/// Chordal tolerance for curves in hide SVGs (mm): far below a knife's kerf.
const SVG_CHORD_MM: f64 = 0.1;
/// Segments per quarter turn when a DXF bulge (arc) is flattened.
const ARC_SEGMENTS_PER_QUARTER: f64 = 8.0;

/// The file formats a hide can come in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HideFormat {
    Json,
    Dxf,
    Svg,
}

impl HideFormat {
    /// The format of a file name's extension.
    pub fn from_extension(ext: &str) -> Option<Self> {
        match ext.to_ascii_lowercase().as_str() {
            "json" => Some(Self::Json),
            "dxf" => Some(Self::Dxf),
            "svg" => Some(Self::Svg),
            _ => None,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JsonZone {
    grade: u32,
    outline: Vec<[f64; 2]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JsonHide {
    #[serde(default)]
    name: Option<String>,
    outline: Vec<[f64; 2]>,
    #[serde(default)]
    defects: Vec<Vec<[f64; 2]>>,
    #[serde(default)]
    zones: Vec<JsonZone>,
    #[serde(default)]
    directions: Vec<Vec<[f64; 2]>>,
}

fn pts(v: &[[f64; 2]]) -> Vec<DVec2> {
    v.iter().map(|p| DVec2::new(p[0], p[1])).collect()
}

/// What an element name says it is.
enum Role {
    Defect,
    Zone(u32),
    Direction,
    Other,
}

fn role(name: &str) -> Result<Role, String> {
    let n = name.trim().to_ascii_lowercase();
    for p in ["defect", "hole", "scar"] {
        if n.starts_with(p) {
            return Ok(Role::Defect);
        }
    }
    for p in ["quality", "grade", "zone"] {
        if let Some(rest) = n.strip_prefix(p) {
            let digits: String = rest
                .trim_start_matches(['-', '_', ' '])
                .chars()
                .take_while(|c| c.is_ascii_digit())
                .collect();
            return digits
                .parse()
                .map(Role::Zone)
                .map_err(|_| format!("`{name}`: a zone's name must give its grade, e.g. `{p}-2`"));
        }
    }
    for p in ["direction", "backbone", "grain"] {
        if n.starts_with(p) {
            return Ok(Role::Direction);
        }
    }
    Ok(Role::Other)
}

/// A hide from named contours: `(name, points, closed)`.
fn classify(source: &str, elems: Vec<(String, Vec<DVec2>, bool)>) -> Result<Hide, NestError> {
    let bad = |reason: String| NestError::InvalidStock {
        stock: format!("hide {source}"),
        reason,
    };
    let mut hide = Hide::new(source, Vec::new());
    let mut outline: Option<Vec<DVec2>> = None;
    for (name, p, closed) in elems {
        match role(&name).map_err(bad)? {
            Role::Defect | Role::Zone(_) if !closed => {
                return Err(bad(format!("`{name}` must be a closed contour")));
            }
            Role::Defect => hide.defects.push(p),
            Role::Zone(grade) => hide.zones.push(QualityZone { grade, outline: p }),
            Role::Direction => hide.directions.push(p),
            Role::Other if closed => {
                if outline
                    .as_ref()
                    .is_none_or(|o| polygon_area(&p).abs() > polygon_area(o).abs())
                {
                    outline = Some(p);
                }
            }
            Role::Other => {}
        }
    }
    hide.outline = outline.ok_or_else(|| bad("no closed outline found".into()))?;
    Ok(hide)
}

/// Points of a DXF polyline with its bulges (arcs) flattened.
fn flatten_bulges(points: &[DVec2], bulges: &[f64], closed: bool) -> Vec<DVec2> {
    let n = points.len();
    let mut out = Vec::with_capacity(n);
    let segs = if closed { n } else { n.saturating_sub(1) };
    for i in 0..n {
        out.push(points[i]);
        let b = bulges.get(i).copied().unwrap_or(0.0);
        if i >= segs || b == 0.0 || !b.is_finite() {
            continue;
        }
        let (a, c) = (points[i], points[(i + 1) % n]);
        let sweep = 4.0 * b.atan();
        let chord = c - a;
        let len = chord.length();
        if len == 0.0 {
            continue;
        }
        // the arc's centre lies on the chord's bisector
        let r = len / (2.0 * (sweep / 2.0).sin());
        let mid = a + chord * 0.5;
        let normal = DVec2::new(-chord.y, chord.x) / len;
        let h = r * (sweep / 2.0).cos();
        let centre = mid + normal * h;
        let start = (a - centre).y.atan2((a - centre).x);
        let k = ((sweep.abs() / std::f64::consts::FRAC_PI_2) * ARC_SEGMENTS_PER_QUARTER)
            .ceil()
            .clamp(1.0, 256.0) as usize;
        for j in 1..k {
            let t = start + sweep * j as f64 / k as f64;
            out.push(centre + r.abs() * DVec2::from_angle(t));
        }
    }
    out
}

/// Reads a hide; `source` names it in the result and in errors (the file name).
pub fn read_hide(text: &str, source: &str, format: HideFormat) -> Result<Hide, NestError> {
    let bad = |reason: String| NestError::InvalidStock {
        stock: format!("hide {source}"),
        reason,
    };
    match format {
        HideFormat::Json => {
            let j: JsonHide = serde_json::from_str(text).map_err(|e| bad(e.to_string()))?;
            Ok(Hide {
                name: j.name.unwrap_or_else(|| source.to_string()),
                outline: pts(&j.outline),
                defects: j.defects.iter().map(|d| pts(d)).collect(),
                zones: j
                    .zones
                    .iter()
                    .map(|z| QualityZone {
                        grade: z.grade,
                        outline: pts(&z.outline),
                    })
                    .collect(),
                directions: j.directions.iter().map(|d| pts(d)).collect(),
            })
        }
        HideFormat::Dxf => {
            let pls = flatcut_pattern::dxf::read_polylines(text).map_err(|e| bad(e.to_string()))?;
            classify(
                source,
                pls.into_iter()
                    .map(|p| {
                        let pts = flatten_bulges(&p.points, &p.bulges, p.closed);
                        (p.layer, pts, p.closed)
                    })
                    .collect(),
            )
        }
        HideFormat::Svg => {
            let d = flatcut_pattern::svg::read_svg(text, source, SVG_CHORD_MM)
                .map_err(|e| bad(e.to_string()))?;
            classify(
                source,
                d.strokes
                    .into_iter()
                    .map(|s| (s.id, s.points, s.closed))
                    .collect(),
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_hide_with_everything() {
        let h = read_hide(
            r#"{"outline": [[0,0],[100,0],[100,80],[0,80]],
                "defects": [[[10,10],[20,10],[20,20]]],
                "zones": [{"grade": 3, "outline": [[50,0],[100,0],[100,40],[50,40]]}],
                "directions": [[[0,40],[100,40]]]}"#,
            "h.json",
            HideFormat::Json,
        )
        .unwrap();
        assert_eq!(h.name, "h.json");
        assert_eq!(h.outline.len(), 4);
        assert_eq!(h.defects.len(), 1);
        assert_eq!(h.zones[0].grade, 3);
        assert_eq!(h.directions.len(), 1);
        let e = read_hide(r#"{"outline": [], "colour": 1}"#, "x.json", HideFormat::Json)
            .unwrap_err();
        assert!(e.to_string().contains("x.json"), "{e}");
    }

    #[test]
    fn roles_from_names() {
        assert!(matches!(role("DEFECT-3").unwrap(), Role::Defect));
        assert!(matches!(role("quality-4").unwrap(), Role::Zone(4)));
        assert!(matches!(role("Grade_2 belly").unwrap(), Role::Zone(2)));
        assert!(matches!(role("backbone").unwrap(), Role::Direction));
        assert!(matches!(role("0").unwrap(), Role::Other));
        assert!(role("zone-x").is_err());
    }

    fn lwpolyline(layer: &str, pts: &[(f64, f64)], closed: bool) -> String {
        let mut s = format!(
            "0\nLWPOLYLINE\n8\n{layer}\n90\n{}\n70\n{}\n",
            pts.len(),
            closed as i32
        );
        for (x, y) in pts {
            s += &format!("10\n{x}\n20\n{y}\n");
        }
        s
    }

    #[test]
    fn dxf_hide_by_layer_names() {
        let mut t = String::from("0\nSECTION\n2\nENTITIES\n");
        t += &lwpolyline(
            "HIDE",
            &[(0., 0.), (500., 0.), (520., 300.), (0., 320.)],
            true,
        );
        t += &lwpolyline("DEFECT", &[(100., 100.), (120., 100.), (110., 130.)], true);
        t += &lwpolyline(
            "QUALITY-3",
            &[(300., 0.), (500., 0.), (500., 100.), (300., 100.)],
            true,
        );
        t += &lwpolyline("BACKBONE", &[(0., 160.), (520., 160.)], false);
        t += "0\nENDSEC\n0\nEOF\n";
        let h = read_hide(&t, "h.dxf", HideFormat::Dxf).unwrap();
        assert_eq!(h.outline.len(), 4);
        assert_eq!(h.defects.len(), 1);
        assert_eq!(h.zones.len(), 1);
        assert_eq!(h.zones[0].grade, 3);
        assert_eq!(h.directions, vec![vec![DVec2::new(0., 160.), DVec2::new(520., 160.)]]);
        let open_defect = t.replace("DEFECT\n90\n3\n70\n1", "DEFECT\n90\n3\n70\n0");
        let e = read_hide(&open_defect, "h.dxf", HideFormat::Dxf).unwrap_err();
        assert!(e.to_string().contains("closed"), "{e}");
    }

    #[test]
    fn a_bulge_is_flattened_on_its_arc() {
        // a half circle of radius 10 from (0,0) to (20,0): bulge 1
        let p = flatten_bulges(&[DVec2::ZERO, DVec2::new(20., 0.)], &[1.0, 0.0], false);
        assert!(p.len() > 10);
        for q in &p {
            assert!((q.distance(DVec2::new(10., 0.)) - 10.0).abs() < 1e-9, "{q}");
        }
    }
}
