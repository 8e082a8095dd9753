//! Loader for the ESICUP strip-packing benchmark instances in the jagua-rs JSON format
//! (`/work/shared/bench/nesting/instances`): `{name, strip_height, items: [{id, demand,
//! allowed_orientations?, shape: {type: "simple_polygon", data: [[x, y], …]}}]}`, and the
//! shoe-part items of the Baldacci `Scarpa.json` leather instance (older PascalCase schema).

use crate::search::{NestError, NestItem, Rotations};
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
    pub name: String,
    /// Fixed strip height (the roll width).
    pub strip_height: f64,
    pub items: Vec<NestItem>,
}

impl BenchInstance {
    /// Total area of all demanded pieces.
    pub fn total_area(&self) -> f64 {
        self.items
            .iter()
            .map(|i| crate::search::polygon_area(&i.outline).abs() * i.quantity as f64)
            .sum()
    }
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
        let mut outline: Vec<DVec2> = pts
            .iter()
            .filter(|p| p.len() == 2)
            .map(|p| DVec2::new(p[0], p[1]))
            .collect();
        if outline.len() > 1 && outline[0] == outline[outline.len() - 1] {
            outline.pop();
        }
        let rotations = match it.allowed_orientations {
            None => Rotations::Free,
            Some(a) if a.is_empty() => Rotations::None,
            Some(a) => Rotations::List(a.iter().map(|d| d.to_radians()).collect()),
        };
        items.push(NestItem {
            name,
            outline,
            quantity: it.demand,
            rotations,
            grain_angle: None,
            mirrored_pair: false,
        });
    }
    Ok(BenchInstance {
        name: raw.name,
        strip_height: raw.strip_height,
        items,
    })
}

#[derive(Deserialize)]
struct ScarpaShape {
    #[serde(rename = "Outer")]
    outer: Vec<Vec<f64>>,
}

#[derive(Deserialize)]
struct ScarpaItem {
    #[serde(rename = "Demand")]
    demand: usize,
    #[serde(rename = "Shape")]
    shape: ScarpaShape,
}

#[derive(Deserialize)]
struct ScarpaInstance {
    #[serde(rename = "Name", default)]
    name: String,
    #[serde(rename = "Items")]
    items: Vec<ScarpaItem>,
}

/// Shoe parts of the Baldacci `Scarpa.json` instance as mirrored left/right pairs (mm): each
/// part gets `pairs` copies per side, free rotation (leather has no woven grain). The hides,
/// defects and quality zones of the instance are not used.
pub fn load_scarpa_items(json: &str, pairs: usize) -> Result<Vec<NestItem>, NestError> {
    let raw: ScarpaInstance = serde_json::from_str(json)
        .map_err(|e| NestError::InvalidInput(format!("Scarpa JSON: {e}")))?;
    let base = if raw.name.is_empty() {
        "scarpa".to_string()
    } else {
        raw.name.to_lowercase()
    };
    Ok(raw
        .items
        .into_iter()
        .enumerate()
        .filter(|(_, it)| it.demand > 0)
        .map(|(k, it)| {
            let mut outline: Vec<DVec2> = it
                .shape
                .outer
                .iter()
                .filter(|p| p.len() == 2)
                .map(|p| DVec2::new(p[0], p[1]))
                .collect();
            if outline.len() > 1 && outline[0] == outline[outline.len() - 1] {
                outline.pop();
            }
            NestItem {
                name: format!("{base}-{k}"),
                outline,
                quantity: pairs,
                rotations: Rotations::Free,
                grain_angle: None,
                mirrored_pair: true,
            }
        })
        .collect())
}
