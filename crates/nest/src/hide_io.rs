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
use flatcut_pattern::colours::{ColourJob, ColourTable, LIGHTBURN_PALETTE};
use serde::Deserialize;

/// Chordal tolerance for curves in hide SVGs and DXFs (mm): far below a knife's kerf.
const CHORD_MM: f64 = 0.1;

/// The file formats a hide can come in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HideFormat {
    /// The nester's own JSON description of a hide.
    Json,
    /// A DXF drawing of the outline, its defects and zones.
    Dxf,
    /// An SVG drawing of the outline, its defects and zones.
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
            let (paths, _) = flatcut_pattern::dxf_read::read_dxf_layers(text, CHORD_MM)
                .map_err(|e| bad(e.to_string()))?;
            classify(
                source,
                paths
                    .into_iter()
                    .map(|p| (p.layer, p.points, p.closed))
                    .collect(),
            )
        }
        HideFormat::Svg => {
            // ids, not colours, say what a contour of a hide is: keep every colour
            let all: std::collections::BTreeMap<String, ColourJob> = LIGHTBURN_PALETTE
                .iter()
                .map(|(n, _)| (n.to_string(), ColourJob::Draw))
                .collect();
            let table = ColourTable::with_overrides(&all).map_err(bad)?;
            let d = flatcut_pattern::svg::read_svg(text, source, CHORD_MM, &table)
                .map_err(|e| bad(e.to_string()))?
                .drawing;
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
        let e = read_hide(
            r#"{"outline": [], "colour": 1}"#,
            "x.json",
            HideFormat::Json,
        )
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
        assert_eq!(
            h.directions,
            vec![vec![DVec2::new(0., 160.), DVec2::new(520., 160.)]]
        );
        let open_defect = t.replace("DEFECT\n90\n3\n70\n1", "DEFECT\n90\n3\n70\n0");
        let e = read_hide(&open_defect, "h.dxf", HideFormat::Dxf).unwrap_err();
        assert!(e.to_string().contains("closed"), "{e}");
    }
}
