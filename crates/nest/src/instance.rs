//! Loaders for benchmark instances: the ESICUP strip-packing instances in the jagua-rs JSON
//! format (copies in `crates/nest/tests/data/instances`), and the leather instances of Baldacci
//! et al. (2014) in their PascalCase schema (`Scarpa.json`: shoe parts and two hides with defects
//! and quality zones).

use crate::error::NestError;
use crate::item::{NestItem, Rotations};
use crate::stock::{Hide, QualityZone};
use flatcut_geom::DVec2;
use serde::Deserialize;

#[derive(Deserialize)]
struct RawShape {
    #[serde(rename = "type")]
    kind: String,
    data: serde_json::Value,
}

#[derive(Deserialize)]
struct RawItem {
    id: u64,
    demand: usize,
    allowed_orientations: Option<Vec<f64>>,
    shape: RawShape,
}

#[derive(Deserialize)]
struct RawInstance {
    name: String,
    strip_height: f64,
    items: Vec<RawItem>,
}

/// A strip-packing benchmark instance converted to nesting items.
#[derive(Clone, Debug)]
pub struct BenchInstance {
    /// The instance's name (its file stem).
    pub name: String,
    /// Fixed strip height (the roll width).
    pub strip_height: f64,
    /// The items to pack.
    pub items: Vec<NestItem>,
}

impl BenchInstance {
    /// Total area of all demanded pieces.
    pub fn total_area(&self) -> f64 {
        self.items
            .iter()
            .map(|i| crate::polygon_area(&i.outline).abs() * i.quantity as f64)
            .sum()
    }
}

fn points(v: &[Vec<f64>]) -> Vec<DVec2> {
    let mut out: Vec<DVec2> = v
        .iter()
        .filter(|p| p.len() == 2)
        .map(|p| DVec2::new(p[0], p[1]))
        .collect();
    if out.len() > 1 && out[0] == out[out.len() - 1] {
        out.pop();
    }
    out
}

/// Parses an instance from JSON text.
pub fn load_bench_instance(json: &str) -> Result<BenchInstance, NestError> {
    let raw: RawInstance = serde_json::from_str(json)
        .map_err(|e| NestError::InvalidInput(format!("instance JSON: {e}")))?;
    let mut items = Vec::with_capacity(raw.items.len());
    for it in raw.items {
        let name = format!("{}-{}", raw.name, it.id);
        let pts: Vec<Vec<f64>> = match it.shape.kind.as_str() {
            "simple_polygon" => {
                serde_json::from_value(it.shape.data).map_err(|e| NestError::InvalidItem {
                    item: name.clone(),
                    reason: e.to_string(),
                })?
            }
            other => {
                return Err(NestError::InvalidItem {
                    item: name,
                    reason: format!("unsupported shape type `{other}`"),
                });
            }
        };
        let rotations = match it.allowed_orientations {
            None => Rotations::Free,
            Some(a) if a.is_empty() => Rotations::None,
            Some(a) => Rotations::List(a.iter().map(|d| d.to_radians()).collect()),
        };
        items.push(NestItem {
            rotations,
            ..NestItem::new(name, points(&pts), it.demand)
        });
    }
    Ok(BenchInstance {
        name: raw.name,
        strip_height: raw.strip_height,
        items,
    })
}

#[derive(Deserialize)]
struct BShape {
    #[serde(rename = "Outer")]
    outer: Vec<Vec<f64>>,
    #[serde(rename = "Inner", default)]
    inner: Vec<Vec<Vec<f64>>>,
}

#[derive(Deserialize)]
struct BZone {
    #[serde(rename = "Quality")]
    quality: u32,
    #[serde(rename = "Shape")]
    shape: BShape,
}

#[derive(Deserialize)]
struct BItem {
    #[serde(rename = "Demand")]
    demand: usize,
    #[serde(rename = "BaseQuality", default)]
    base_quality: Option<u32>,
    #[serde(rename = "Shape")]
    shape: BShape,
}

#[derive(Deserialize)]
struct BObject {
    #[serde(rename = "Shape")]
    shape: BShape,
    #[serde(rename = "Zones", default)]
    zones: Vec<BZone>,
}

#[derive(Deserialize)]
struct BInstance {
    #[serde(rename = "Name", default)]
    name: String,
    #[serde(rename = "Items")]
    items: Vec<BItem>,
    #[serde(rename = "Objects")]
    objects: Vec<BObject>,
}

/// A leather instance of Baldacci et al.: its pieces (free rotation, the demanded quantity,
/// each with the worst grade it accepts) and its hides (outline, defects, graded zones).
///
/// The file grades quality the jagua-rs way: larger numbers are better, the hide outside every
/// zone is best, and a piece accepts zones at least as good as its base quality. flatcut grades
/// 1 = first quality and larger = worse, so level `q` becomes grade `m + 2 − q` with `m` the
/// best level in the file (the unzoned hide is grade 1). The per-piece quality zones of the
/// file (a region of a piece that needs a better grade) are not modelled: the whole piece meets
/// its base quality.
pub fn load_scarpa(json: &str) -> Result<(Vec<NestItem>, Vec<Hide>), NestError> {
    let raw: BInstance = serde_json::from_str(json)
        .map_err(|e| NestError::InvalidInput(format!("leather instance JSON: {e}")))?;
    let base = if raw.name.is_empty() {
        "hide-instance".to_string()
    } else {
        raw.name.to_lowercase()
    };
    let best = raw
        .objects
        .iter()
        .flat_map(|o| o.zones.iter().map(|z| z.quality))
        .chain(raw.items.iter().filter_map(|i| i.base_quality))
        .max()
        .unwrap_or(1);
    let grade = |q: u32| best + 2 - q.min(best + 1);
    let items = raw
        .items
        .iter()
        .enumerate()
        .filter(|(_, it)| it.demand > 0)
        .map(|(k, it)| NestItem {
            rotations: Rotations::Free,
            quality: it.base_quality.map(grade),
            ..NestItem::new(format!("{base}-{k}"), points(&it.shape.outer), it.demand)
        })
        .collect();
    let hides = raw
        .objects
        .iter()
        .enumerate()
        .map(|(k, o)| {
            let mut h = Hide::new(format!("{base}-hide-{}", k + 1), points(&o.shape.outer));
            h.defects = o.shape.inner.iter().map(|d| points(d)).collect();
            for z in &o.zones {
                if z.quality == 0 {
                    h.defects.push(points(&z.shape.outer));
                } else {
                    h.zones.push(QualityZone {
                        grade: grade(z.quality),
                        outline: points(&z.shape.outer),
                    });
                }
            }
            h
        })
        .collect();
    Ok((items, hides))
}
