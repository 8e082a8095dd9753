//! The engine's immutable model of a nesting input: piece kinds (an item, or its mirror image)
//! as jagua-rs items with their allowed turns and quality, the piece instances, and the
//! collision-engine configuration. Input is validated here: finite, in range, bounded in size.

use crate::error::NestError;
use crate::item::{GrainDirections, NestItem, Rotations};
use crate::options::NestOptions;
use crate::orient::{Turns, wrap};
use crate::stock::Material;
use flatcut_geom::DVec2;
use flatcut_pattern::Placement;
use jagua_rs::collision_detection::CDEConfig;
use jagua_rs::entities::{Item, N_QUALITIES};
use jagua_rs::geometry::DTransformation;
use jagua_rs::geometry::fail_fast::SPSurrogateConfig;
use jagua_rs::io::ext_repr::{ExtItem, ExtOrientation, ExtRotation, ExtSPolygon, ExtShape};
use jagua_rs::io::import::Importer;
use std::f64::consts::PI;
use std::sync::Arc;

pub use flatcut_geom::limits::MAX_COORD_MM;
/// Largest sheet side, roll width or roll length the nester accepts (mm): 100 m. The collision
/// engine computes in f32, whose resolution at 1e5 mm is 8 µm; at 1e6 mm it is 62 µm, coarser
/// than the engine's edge handling, and the search slows by an order of magnitude.
pub const MAX_STOCK_MM: f64 = 1e5;
/// Most piece instances (copies, mirrored copies included) in one run: the collision tracker
/// and the layouts grow with them, and the search's time with their square.
pub const MAX_INSTANCES: usize = 2000;
/// Most vertices in one outline (the engine checks outlines for self-intersection pairwise).
pub const MAX_VERTICES: usize = 5000;
/// Smallest piece relative to the stock's extent that f32 coordinates still resolve well.
const MIN_PIECE_TO_STOCK: f64 = 1e-5;
/// Shape simplification: the collision outline may grow by at most this fraction of the area
/// (never shrink), which removes near-collinear vertices (as sparrow does).
const SIMPLIFY_TOLERANCE: f32 = 0.001;
/// Narrow concavities (mouth under 1 % of the diameter, area under 1 % of the piece) are closed
/// in the collision outline: nothing fits in them anyway.
const NARROW_CONCAVITY: (f32, f32) = (0.01, 0.01);
/// Quality grades are mapped onto jagua-rs's levels `N_QUALITIES - grade`.
pub(crate) const MAX_GRADE: u32 = N_QUALITIES as u32 - 1;

/// One side of a piece type as the engine sees it.
#[derive(Debug)]
pub(crate) struct Kind {
    pub item: usize,
    pub mirrored: bool,
    pub jitem: Arc<Item>,
    pub turns: Turns,
    /// Turns are relative to a hide's local grain direction (grain-constrained pieces on hides
    /// with direction lines).
    pub follows_field: bool,
    /// Area of the original outline (mm²).
    pub area: f64,
    /// Outline in the item's frame (mirrored for the mirrored side).
    pub outline: Vec<DVec2>,
    /// What was subtracted from `outline` before handing it to the engine (f32 precision).
    pub offset: DVec2,
    /// jagua-rs minimum quality: zones of lower quality are hazards for this kind.
    pub min_quality: usize,
    /// Smallest side of the collision shape's bounding box (f32, mm).
    pub min_dim: f32,
}

/// The model shared by every worker.
#[derive(Debug)]
pub(crate) struct Problem {
    pub kinds: Vec<Kind>,
    /// Per instance: (kind, copy).
    pub instances: Vec<(u32, u32)>,
    pub importer: Importer,
    pub samples: usize,
    pub rotation_steps: usize,
    pub spacing: f64,
    pub names: Vec<String>,
}

pub(crate) use flatcut_pattern::poly::signed_area as polygon_area;

/// Checks an outline: enough finite points within range, not too many, some area. Returns it
/// counter-clockwise without repeated points.
pub(crate) fn clean_outline(pts: &[DVec2], what: &str) -> Result<Vec<DVec2>, String> {
    if let Some(p) = pts.iter().find(|p| !flatcut_geom::limits::in_range2(**p)) {
        return Err(format!(
            "{what} has a point ({}, {}) that is not finite or beyond ±{MAX_COORD_MM:e} mm",
            p.x, p.y
        ));
    }
    let mut out: Vec<DVec2> = pts.to_vec();
    out.dedup();
    while out.len() > 1 && out[0] == out[out.len() - 1] {
        out.pop();
    }
    if out.len() < 3 {
        return Err(format!("{what} needs at least 3 distinct points"));
    }
    if out.len() > MAX_VERTICES {
        return Err(format!(
            "{what} has {} points; at most {MAX_VERTICES} are accepted (simplify it first)",
            out.len()
        ));
    }
    let a = polygon_area(&out);
    if a.abs() <= 0.0 || !a.is_finite() {
        return Err(format!("{what} has zero area"));
    }
    if a < 0.0 {
        out.reverse();
    }
    Ok(out)
}

/// Points of an outline closer than this to the line through their neighbours are dropped
/// before a second try when the collision engine rejects an outline (mm): far below any
/// cutting precision.
const THIN_MM: f64 = 0.005;

/// Imports an item into the collision engine. The engine inflates the outline by half the
/// spacing (geo's buffer) and rounds it to f32; runs of nearly collinear points a few
/// hundredths of a millimetre apart (a seam allowance's mitred corners, a flattened style
/// line's vertices) can come out of that as a self-intersecting polygon, which it rejects. Then
/// the outline is thinned (Ramer–Douglas–Peucker, geo's, at [`THIN_MM`]) and imported again.
fn import_thinned(importer: &Importer, mut ext: ExtItem, id: usize) -> Result<Arc<Item>, String> {
    match importer.import_item(&ext, id) {
        Ok(item) => Ok(item),
        Err(first) => {
            use geo::Simplify;
            let ExtShape::SimplePolygon(ExtSPolygon(pts)) = &ext.shape else {
                return Err(first.to_string());
            };
            let ring: geo::LineString<f64> = pts
                .iter()
                .chain(pts.first())
                .map(|&(x, y)| geo::Coord {
                    x: f64::from(x),
                    y: f64::from(y),
                })
                .collect();
            let mut thin: Vec<(f32, f32)> = ring
                .simplify(THIN_MM)
                .0
                .iter()
                .map(|c| (c.x as f32, c.y as f32))
                .collect();
            thin.pop();
            if thin.len() < 3 {
                return Err(first.to_string());
            }
            ext.shape = ExtShape::SimplePolygon(ExtSPolygon(thin));
            importer
                .import_item(&ext, id)
                .map_err(|_| first.to_string())
        }
    }
}

/// Quadtree depth: leaves about the size of a typical piece. Deeper trees cost more to walk
/// than they save on the few dozen to few hundred pieces of a nesting (measured on the ESICUP
/// instances: depth 2 ran 10–15 % faster than 4 there).
fn quadtree_depth(container_extent: f64, typical_piece: f64) -> u8 {
    let levels = (container_extent / typical_piece.max(1e-9)).log2().floor();
    levels.clamp(2.0, 5.0) as u8
}

fn cde_config(depth: u8) -> CDEConfig {
    CDEConfig {
        quadtree_depth: depth,
        // a leaf with this many edges is checked directly rather than split further
        cd_threshold: 32,
        item_surrogate_config: SPSurrogateConfig {
            n_pole_limits: [(64, 0.0), (16, 0.8), (8, 0.9)],
            ff_pole_area_ratio: 0.5,
            n_ff_piers: 0,
        },
    }
}

/// The turns an item allows, before mirroring: relative to the material's grain direction.
fn turns_of(it: &NestItem, mirrored: bool) -> Result<(Turns, bool), String> {
    if let Some(g) = it.effective_grain() {
        if !g.is_finite() {
            return Err("grain angle is not finite".into());
        }
        let tol = it.grain_tolerance_deg;
        if !(tol.is_finite() && (0.0..=90.0).contains(&tol)) {
            return Err(format!(
                "grain tolerance must be within 0..=90 degrees, got {tol}"
            ));
        }
        // the mirror image's grain line: x → −x turns angle g into π − g
        let g = if mirrored { PI - g } else { g };
        let centers: Vec<f32> = match it.grain_directions {
            GrainDirections::Fixed => vec![wrap(-g as f32)],
            _ => vec![wrap(-g as f32), wrap((PI - g) as f32)],
        };
        let turns = if tol == 0.0 {
            Turns::Discrete(centers)
        } else {
            Turns::Bands {
                centers,
                half: tol.to_radians() as f32,
            }
        };
        return Ok((turns, true));
    }
    let turns = match &it.rotations {
        Rotations::None => Turns::Discrete(vec![0.0]),
        Rotations::Half => Turns::Discrete(vec![0.0, PI as f32]),
        Rotations::Quarter => Turns::Discrete(
            (0..4)
                .map(|i| wrap(i as f32 * std::f32::consts::FRAC_PI_2))
                .collect(),
        ),
        Rotations::Free => Turns::Continuous,
        Rotations::List(v) => {
            if v.is_empty() || v.len() > 360 || v.iter().any(|a| !a.is_finite()) {
                return Err("rotation list must hold 1..=360 finite angles".into());
            }
            let mut a: Vec<f32> = v.iter().map(|a| wrap(*a as f32)).collect();
            a.sort_by(f32::total_cmp);
            a.dedup();
            Turns::Discrete(a)
        }
    };
    Ok((turns, false))
}

impl Problem {
    /// Builds the model, checking every input; `extent` is the stock's largest dimension.
    pub(crate) fn new(
        items: &[NestItem],
        material: &Material,
        opts: &NestOptions,
        extent: f64,
        has_field: bool,
    ) -> Result<Self, NestError> {
        let spacing = opts.spacing;
        if !(0.0..=MAX_COORD_MM).contains(&spacing) {
            return Err(NestError::InvalidInput(format!(
                "spacing must be a finite number of mm ≥ 0, got {spacing}"
            )));
        }
        let total: usize = items
            .iter()
            .map(|i| i.quantity.saturating_mul(1 + i.mirrored_pair as usize))
            .fold(0usize, usize::saturating_add);
        if total == 0 {
            return Err(NestError::InvalidInput("nothing to place".into()));
        }
        if total > MAX_INSTANCES {
            return Err(NestError::InvalidInput(format!(
                "{total} piece copies to place; the nester places at most {MAX_INSTANCES} in one run"
            )));
        }
        let n_inst = total;
        let mut diameters: Vec<f64> = items
            .iter()
            .filter(|i| i.quantity > 0)
            .map(|i| {
                let b = flatcut_geom::Aabb2::from_points(i.outline.iter().copied());
                (b.max - b.min).length()
            })
            .filter(|d| d.is_finite())
            .collect();
        diameters.sort_by(f64::total_cmp);
        let typical = diameters.get(diameters.len() / 2).copied().unwrap_or(1.0);
        let depth = quadtree_depth(extent, typical);
        let importer = Importer::new(
            cde_config(depth),
            Some(SIMPLIFY_TOLERANCE),
            Some(NARROW_CONCAVITY),
        )
        .with_min_item_separation(spacing as f32)
        .map_err(|e| NestError::InvalidInput(e.to_string()))?;
        let mut kinds = Vec::new();
        let mut instances = Vec::with_capacity(n_inst);
        for (k, it) in items.iter().enumerate() {
            if it.quantity == 0 {
                continue;
            }
            let bad = |reason: String| NestError::InvalidItem {
                item: it.name.clone(),
                reason,
            };
            let base = clean_outline(&it.outline, "outline").map_err(bad)?;
            if let Some(q) = it.quality
                && q == 0
            {
                return Err(bad("quality grades start at 1 (first quality)".into()));
            }
            let min_quality = match it.quality {
                None => 0,
                Some(q) => N_QUALITIES.saturating_sub(q.min(MAX_GRADE + 1) as usize),
            };
            let sides: &[bool] = if it.mirrored_pair {
                &[false, true]
            } else {
                &[false]
            };
            for &mirrored in sides {
                let outline: Vec<DVec2> = if mirrored {
                    base.iter().rev().map(|p| DVec2::new(-p.x, p.y)).collect()
                } else {
                    base.clone()
                };
                let (turns, grain) = turns_of(it, mirrored).map_err(bad)?;
                let bb = flatcut_geom::Aabb2::from_points(outline.iter().copied());
                let size = (bb.max - bb.min).max_element();
                if size < MIN_PIECE_TO_STOCK * extent {
                    return Err(bad(format!(
                        "{size:.3} mm across is too small for a stock {extent:.0} mm long \
                         (the engine resolves pieces down to {:.0e} of the stock's extent)",
                        MIN_PIECE_TO_STOCK
                    )));
                }
                let offset = 0.5 * (bb.min + bb.max);
                let ext = ExtItem {
                    id: kinds.len() as u64,
                    orientation: ExtOrientation {
                        rotation: ExtRotation::Continuous {},
                        reflection_axes: vec![],
                    },
                    shape: ExtShape::SimplePolygon(ExtSPolygon(
                        outline
                            .iter()
                            .map(|p| ((p.x - offset.x) as f32, (p.y - offset.y) as f32))
                            .collect(),
                    )),
                    min_quality: Some(min_quality),
                };
                let jitem = import_thinned(&importer, ext, kinds.len())
                    .map_err(|e| bad(format!("rejected by the collision engine: {e}")))?;
                let cb = jitem.shape_cd().bbox();
                let min_dim = cb.width().min(cb.height());
                let ki = kinds.len() as u32;
                kinds.push(Kind {
                    item: k,
                    mirrored,
                    area: polygon_area(&outline),
                    turns,
                    follows_field: grain && has_field,
                    jitem,
                    outline,
                    offset,
                    min_quality,
                    min_dim,
                });
                for copy in 0..it.quantity {
                    instances.push((ki, copy as u32));
                }
            }
        }
        let _ = material;
        Ok(Self {
            kinds,
            instances,
            importer,
            samples: opts.samples.clamp(1, 10_000),
            rotation_steps: opts.free_rotation_steps.clamp(1, 360),
            spacing,
            names: items.iter().map(|i| i.name.clone()).collect(),
        })
    }

    pub(crate) fn kind_of(&self, inst: usize) -> &Kind {
        &self.kinds[self.instances[inst].0 as usize]
    }

    /// The placement of an instance at engine transformation `dt`, in the item's frame.
    pub(crate) fn placement(&self, inst: usize, dt: &DTransformation) -> Placement {
        let k = self.kind_of(inst);
        let pre = k.jitem.shape_orig().pre_transform.translation();
        let rot = dt.rotation() as f64;
        let (tx, ty) = dt.translation();
        let r = DVec2::from_angle(rot);
        let local = DVec2::new(pre.0 as f64, pre.1 as f64) - k.offset;
        Placement {
            rotation: rot,
            mirror: k.mirrored,
            translation: DVec2::new(tx as f64, ty as f64) + r.rotate(local),
        }
    }

    /// Instances in placement order for the construction: largest first (convex-hull area times
    /// diameter, as sparrow orders them), then by index.
    pub(crate) fn construction_order(&self) -> Vec<usize> {
        let key = |i: usize| {
            let s = self.kind_of(i).jitem.shape_cd();
            s.surrogate().convex_hull_area * s.diameter()
        };
        let mut order: Vec<usize> = (0..self.instances.len()).collect();
        order.sort_by(|&a, &b| key(b).total_cmp(&key(a)).then(a.cmp(&b)));
        order
    }

    pub(crate) fn total_area(&self) -> f64 {
        self.instances
            .iter()
            .map(|(k, _)| self.kinds[*k as usize].area)
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shoe quarter's outline that the engine rejected once inflated by half of a 3 mm
    /// spacing: imported as it is it fails, thinned it goes in, as large as it is.
    #[test]
    fn an_outline_the_engine_rejects_goes_in_thinned() {
        let text = include_str!("../tests/data/shoe-quarter-outline.txt");
        let pts: Vec<DVec2> = text
            .lines()
            .filter(|l| !l.starts_with('#'))
            .map(|l| {
                let v: Vec<f64> = l.split(' ').map(|x| x.parse().unwrap()).collect();
                DVec2::new(v[0], v[1])
            })
            .collect();
        let bb = flatcut_geom::Aabb2::from_points(pts.iter().copied());
        let c = 0.5 * (bb.min + bb.max);
        let ext = ExtItem {
            id: 0,
            orientation: ExtOrientation {
                rotation: ExtRotation::Continuous {},
                reflection_axes: vec![],
            },
            shape: ExtShape::SimplePolygon(ExtSPolygon(
                pts.iter()
                    .map(|p| ((p.x - c.x) as f32, (p.y - c.y) as f32))
                    .collect(),
            )),
            min_quality: Some(0),
        };
        let importer = Importer::new(
            cde_config(quadtree_depth(600.0, 200.0)),
            Some(SIMPLIFY_TOLERANCE),
            Some(NARROW_CONCAVITY),
        )
        .with_min_item_separation(3.0)
        .unwrap();
        assert!(importer.import_item(&ext, 0).is_err(), "the premise");
        let item = import_thinned(&importer, ext, 0).unwrap();
        // The collision shape is the outline inflated by 1.5 mm: its box 3 mm larger.
        let b = item.shape_cd().bbox();
        let (w, h) = (f64::from(b.width()), f64::from(b.height()));
        let size = bb.max - bb.min;
        assert!((w - size.x - 3.0).abs() < 0.05, "{w} vs {}", size.x);
        assert!((h - size.y - 3.0).abs() < 0.05, "{h} vs {}", size.y);
    }
}
