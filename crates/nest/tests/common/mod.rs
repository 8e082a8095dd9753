//! Layout checks shared by the tests: an independent polygon check with geo's boolean
//! operations and segment distances, and a check by jagua-rs on a layout rebuilt from the
//! result with the original (unsimplified) outlines.

#![allow(dead_code)]

use flatcut_geom::DVec2;
use flatcut_nest::{Hide, NestItem, NestResult};
use geo::{Area, BooleanOps, Coord, LineString, Polygon};
use jagua_rs::collision_detection::CDEConfig;
use jagua_rs::entities::Layout;
use jagua_rs::geometry::DTransformation;
use jagua_rs::geometry::fail_fast::SPSurrogateConfig;
use jagua_rs::io::ext_repr::{
    ExtContainer, ExtItem, ExtOrientation, ExtPolygon, ExtQualityZone, ExtRotation, ExtSPolygon,
    ExtShape,
};
use jagua_rs::io::import::Importer;

fn seg_seg_dist(a0: DVec2, a1: DVec2, b0: DVec2, b1: DVec2) -> f64 {
    let r = a1 - a0;
    let s = b1 - b0;
    let den = r.perp_dot(s);
    if den.abs() > 1e-300 {
        let t = (b0 - a0).perp_dot(s) / den;
        let u = (b0 - a0).perp_dot(r) / den;
        if (0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u) {
            return 0.0;
        }
    }
    let pd = |p: DVec2, a: DVec2, b: DVec2| {
        let d = b - a;
        let t = if d.length_squared() > 0.0 {
            ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (a + d * t).distance(p)
    };
    pd(a0, b0, b1)
        .min(pd(a1, b0, b1))
        .min(pd(b0, a0, a1))
        .min(pd(b1, a0, a1))
}

pub use flatcut_pattern::poly::contains;

/// Placed outlines in stock coordinates, with their sheet.
pub fn placed_polygons(items: &[NestItem], r: &NestResult) -> Vec<(usize, Vec<DVec2>)> {
    r.placed
        .iter()
        .map(|p| {
            (
                p.sheet,
                items[p.item]
                    .outline
                    .iter()
                    .map(|q| p.placement.apply(*q))
                    .collect(),
            )
        })
        .collect()
}

/// Minimum distance between any two placed pieces on the same sheet (0 when they overlap).
pub fn min_gap(polys: &[(usize, Vec<DVec2>)]) -> f64 {
    let mut best = f64::INFINITY;
    let bbs: Vec<(DVec2, DVec2)> = polys
        .iter()
        .map(|(_, p)| {
            (
                p.iter().copied().fold(DVec2::INFINITY, DVec2::min),
                p.iter().copied().fold(DVec2::NEG_INFINITY, DVec2::max),
            )
        })
        .collect();
    for i in 0..polys.len() {
        for j in i + 1..polys.len() {
            if polys[i].0 != polys[j].0 {
                continue;
            }
            let (a, b) = (&polys[i].1, &polys[j].1);
            let gap = (bbs[j].0 - bbs[i].1).max(bbs[i].0 - bbs[j].1).max_element();
            if gap > best {
                continue;
            }
            if contains(b, a[0]) || contains(a, b[0]) {
                return 0.0;
            }
            for k in 0..a.len() {
                for l in 0..b.len() {
                    let d = seg_seg_dist(a[k], a[(k + 1) % a.len()], b[l], b[(l + 1) % b.len()]);
                    best = best.min(d);
                }
            }
        }
    }
    best
}

pub fn geo_poly(p: &[DVec2]) -> Polygon<f64> {
    let mut c: Vec<Coord<f64>> = p.iter().map(|q| Coord { x: q.x, y: q.y }).collect();
    c.push(c[0]);
    Polygon::new(LineString::new(c), vec![])
}

/// Largest overlap area between two placed pieces on the same sheet (geo's boolean ops).
pub fn max_pair_overlap(polys: &[(usize, Vec<DVec2>)]) -> f64 {
    let g: Vec<Polygon<f64>> = polys.iter().map(|(_, p)| geo_poly(p)).collect();
    let mut worst: f64 = 0.0;
    for i in 0..g.len() {
        for j in i + 1..g.len() {
            if polys[i].0 != polys[j].0 {
                continue;
            }
            worst = worst.max(g[i].intersection(&g[j]).unsigned_area());
        }
    }
    worst
}

/// Largest area of a placed piece outside `region` (geo's boolean ops).
pub fn max_area_outside(polys: &[(usize, Vec<DVec2>)], region: &[DVec2], sheet: usize) -> f64 {
    let r = geo_poly(region);
    polys
        .iter()
        .filter(|(s, _)| *s == sheet)
        .map(|(_, p)| geo_poly(p).difference(&r).unsigned_area())
        .fold(0.0, f64::max)
}

/// Largest area of a placed piece inside `region`.
pub fn max_area_inside(polys: &[(usize, Vec<DVec2>)], region: &[DVec2], sheet: usize) -> f64 {
    let r = geo_poly(region);
    polys
        .iter()
        .filter(|(s, _)| *s == sheet)
        .map(|(_, p)| geo_poly(p).intersection(&r).unsigned_area())
        .fold(0.0, f64::max)
}

pub fn rect(w: f64, h: f64) -> Vec<DVec2> {
    vec![
        DVec2::ZERO,
        DVec2::new(w, 0.),
        DVec2::new(w, h),
        DVec2::new(0., h),
    ]
}

fn importer(spacing: f64) -> Importer {
    Importer::new(
        CDEConfig {
            quadtree_depth: 5,
            cd_threshold: 16,
            item_surrogate_config: SPSurrogateConfig::none(),
        },
        None,
        None,
    )
    .with_min_item_separation(spacing as f32)
    .unwrap()
}

fn ext(p: &[DVec2]) -> ExtSPolygon {
    ExtSPolygon(p.iter().map(|q| (q.x as f32, q.y as f32)).collect())
}

/// jagua-rs's own verdict on the layout of one sheet: the placed original outlines (placed as
/// drawn, no reuse of the search's shapes), the container and its hazards; `spacing` is the
/// gap to require (pass a little less than the nesting spacing: f32 rounding).
pub fn jagua_collision_free(
    items: &[NestItem],
    r: &NestResult,
    sheet: usize,
    container: ExtContainer,
    spacing: f64,
    min_quality: impl Fn(usize) -> Option<usize>,
) -> bool {
    let imp = importer(spacing);
    let c = imp.import_container(&container).unwrap();
    let mut layout = Layout::new(c);
    for (k, p) in r
        .placed
        .iter()
        .enumerate()
        .filter(|(_, p)| p.sheet == sheet)
    {
        let world: Vec<DVec2> = items[p.item]
            .outline
            .iter()
            .map(|q| p.placement.apply(*q))
            .collect();
        let mut pts = world.clone();
        pts.dedup();
        let item = imp
            .import_item(
                &ExtItem {
                    id: k as u64,
                    orientation: ExtOrientation {
                        rotation: ExtRotation::Continuous {},
                        reflection_axes: vec![],
                    },
                    shape: ExtShape::SimplePolygon(ext(&pts)),
                    min_quality: min_quality(p.item),
                },
                k,
            )
            .unwrap();
        // the importer centred the shape; put it back where it is
        let pre = item.shape_orig().pre_transform.translation();
        layout.place_item(&item, DTransformation::new(0.0, (-pre.0, -pre.1)));
    }
    layout.is_collision_free()
}

pub fn rect_container(w: f64, h: f64) -> ExtContainer {
    ExtContainer {
        id: 0,
        shape: ExtShape::Rectangle {
            x_min: 0.0,
            y_min: 0.0,
            width: w as f32,
            height: h as f32,
        },
        zones: vec![],
    }
}

/// A hide as a jagua-rs container, grades mapped the way the nester maps them (10 − grade).
pub fn hide_container(h: &Hide) -> ExtContainer {
    ExtContainer {
        id: 0,
        shape: ExtShape::Polygon(ExtPolygon {
            outer: ext(&h.outline),
            inner: h.defects.iter().map(|d| ext(d)).collect(),
        }),
        zones: h
            .zones
            .iter()
            .map(|z| ExtQualityZone {
                quality: 10 - z.grade as usize,
                shape: ExtShape::SimplePolygon(ext(&z.outline)),
            })
            .collect(),
    }
}
