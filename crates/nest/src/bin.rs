//! One container the pieces go into — a strip of some length, a sheet, or a hide — as a
//! jagua-rs container plus what the search needs to measure pieces sticking out of it and, on a
//! hide, its grain direction field.

use crate::distance::DistanceGrid;
use crate::error::NestError;
use crate::field::DirectionField;
use crate::problem::{MAX_GRADE, clean_outline, polygon_area};
use crate::quantify::{field_exterior_loss, rect_exterior_loss};
use crate::stock::Hide;
use flatcut_geom::DVec2;
use jagua_rs::entities::{Container, N_QUALITIES};
use jagua_rs::geometry::primitives::SPolygon;
use jagua_rs::io::ext_repr::{ExtContainer, ExtPolygon, ExtQualityZone, ExtSPolygon, ExtShape};
use jagua_rs::io::import::Importer;
use std::sync::Arc;

/// How a piece sticking out of the container is measured.
#[derive(Debug)]
pub(crate) enum Exterior {
    /// A rectangle: the piece's bounding box outside it.
    Rect,
    /// An irregular outline: signed distance to it (minus half the spacing).
    Field { grid: DistanceGrid, inset: f32 },
}

/// A container and its static context.
#[derive(Debug)]
pub(crate) struct Bin {
    pub name: String,
    pub container: Container,
    pub exterior: Exterior,
    pub field: Option<DirectionField>,
    /// Cuttable area: outline minus defects (mm²).
    pub usable_area: f64,
    /// Rectangle size for strips and sheets (x extent, y extent).
    pub rect: Option<(f64, f64)>,
}

impl Bin {
    /// A rectangle `[0, w] × [0, h]`.
    pub(crate) fn rect(
        importer: &Importer,
        name: String,
        w: f64,
        h: f64,
    ) -> Result<Arc<Self>, NestError> {
        let container = importer
            .import_container(&ExtContainer {
                id: 0,
                shape: ExtShape::Rectangle {
                    x_min: 0.0,
                    y_min: 0.0,
                    width: w as f32,
                    height: h as f32,
                },
                zones: vec![],
            })
            .map_err(|e| NestError::InvalidStock {
                stock: name.clone(),
                reason: e.to_string(),
            })?;
        Ok(Arc::new(Self {
            name,
            container,
            exterior: Exterior::Rect,
            field: None,
            usable_area: w * h,
            rect: Some((w, h)),
        }))
    }

    /// A hide with its defects, graded zones and direction lines.
    pub(crate) fn hide(
        importer: &Importer,
        hide: &Hide,
        spacing: f64,
    ) -> Result<Arc<Self>, NestError> {
        let bad = |reason: String| NestError::InvalidStock {
            stock: format!("hide `{}`", hide.name),
            reason,
        };
        let outline = clean_outline(&hide.outline, "outline").map_err(bad)?;
        let poly = |p: &[DVec2]| ExtSPolygon(p.iter().map(|q| (q.x as f32, q.y as f32)).collect());
        let mut holes = Vec::new();
        for (k, d) in hide.defects.iter().enumerate() {
            holes.push(clean_outline(d, &format!("defect {}", k + 1)).map_err(bad)?);
        }
        let mut zones = Vec::new();
        for (k, z) in hide.zones.iter().enumerate() {
            if !(2..=MAX_GRADE).contains(&z.grade) {
                return Err(bad(format!(
                    "quality zone {} has grade {}; zones are graded 2..={MAX_GRADE} (1 is the \
                     first quality outside every zone)",
                    k + 1,
                    z.grade
                )));
            }
            let o = clean_outline(&z.outline, &format!("quality zone {}", k + 1)).map_err(bad)?;
            zones.push(ExtQualityZone {
                quality: N_QUALITIES - z.grade as usize,
                shape: ExtShape::SimplePolygon(poly(&o)),
            });
        }
        for (k, l) in hide.directions.iter().enumerate() {
            if l.len() < 2 || l.iter().any(|p| !flatcut_geom::finite2(*p)) {
                return Err(bad(format!(
                    "direction line {} needs at least 2 finite points",
                    k + 1
                )));
            }
        }
        let container = importer
            .import_container(&ExtContainer {
                id: 0,
                shape: ExtShape::Polygon(ExtPolygon {
                    outer: poly(&outline),
                    inner: holes.iter().map(|h| poly(h)).collect(),
                }),
                zones,
            })
            .map_err(|e| bad(format!("rejected by the collision engine: {e}")))?;
        let bb = flatcut_geom::Aabb2::from_points(outline.iter().copied());
        let field = DirectionField::new(&hide.directions, bb.min, bb.max);
        let usable_area =
            polygon_area(&outline) - holes.iter().map(|h| polygon_area(h)).sum::<f64>();
        Ok(Arc::new(Self {
            name: hide.name.clone(),
            container,
            exterior: Exterior::Field {
                grid: DistanceGrid::new(&outline),
                inset: (0.5 * spacing) as f32,
            },
            field,
            usable_area,
            rect: None,
        }))
    }

    /// Loss of shape `s` sticking out of this container (called when the engine reports it).
    pub(crate) fn exterior_loss(&self, s: &SPolygon) -> f32 {
        match &self.exterior {
            Exterior::Rect => rect_exterior_loss(s, self.container.outer_cd().bbox()),
            Exterior::Field { grid, inset } => {
                field_exterior_loss(s, &|x, y| grid.at(x, y) - inset)
            }
        }
    }

    /// The local grain direction at a point (0 = along x without a direction field).
    pub(crate) fn grain_at(&self, p: (f32, f32)) -> f32 {
        self.field.as_ref().map_or(0.0, |f| f.at(p))
    }
}
