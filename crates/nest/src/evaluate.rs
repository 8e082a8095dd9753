//! Evaluating a candidate placement of one piece: either its weighted collision loss against
//! the layout (stopping as soon as it exceeds the best loss it must beat: Gardeyn & Vanden Berghe
//! 2025, Alg. 7), or, for the construction, feasibility and a left-bottom score.

use crate::problem::{Kind, Problem};
use crate::quantify::{Poles, pair_loss};
use crate::state::{PieceFilter, State};
use jagua_rs::collision_detection::CDEngine;
use jagua_rs::collision_detection::hazards::collector::HazardCollector;
use jagua_rs::collision_detection::hazards::{BasicHazardEntity, HazKey};
use jagua_rs::entities::Layout;
use jagua_rs::geometry::DTransformation;
use jagua_rs::geometry::geo_traits::TransformableFrom;
use jagua_rs::geometry::primitives::SPolygon;
use std::cell::Cell;
use std::cmp::Ordering;

/// Weight of x against y in the left-bottom score: fill along the strip first.
const LBF_X_WEIGHT: f32 = 10.0;

/// The evaluation of a sample, ordered best first.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Eval {
    /// No collision; the score ranks clear samples (0 during separation).
    Clear(f32),
    /// Collisions with this weighted loss.
    Collision(f32),
    /// Rejected (worse than the bound it had to beat, or infeasible).
    Invalid,
}

impl Eval {
    fn rank(&self) -> (u8, f32) {
        match self {
            Eval::Clear(s) => (0, *s),
            Eval::Collision(l) => (1, *l),
            Eval::Invalid => (2, 0.0),
        }
    }
    pub(crate) fn cmp(&self, o: &Self) -> Ordering {
        let (a, b) = (self.rank(), o.rank());
        a.0.cmp(&b.0).then(a.1.total_cmp(&b.1))
    }
    pub(crate) fn better(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Less
    }
}

/// Something that scores candidate transformations of one piece.
pub(crate) trait Evaluator {
    /// Scores `dt`; may return [`Eval::Invalid`] as soon as the result cannot beat `bound`.
    fn eval(&mut self, dt: DTransformation, bound: Eval) -> Eval;
}

/// Collects the hazards a candidate collides with, adding up their weighted loss as they come.
struct LossCollector<'a> {
    hits: &'a mut Vec<(HazKey, BasicHazardEntity)>,
    loss: &'a Cell<f32>,
    st: &'a State,
    cde: &'a CDEngine,
    inst: usize,
    shape: &'a SPolygon,
    poles: &'a Poles,
}

impl LossCollector<'_> {
    fn weighted(&self, k: HazKey, e: &BasicHazardEntity) -> f32 {
        match e {
            BasicHazardEntity::PlacedItem { pk, .. } => {
                let other = self.st.layout.placed_items()[*pk].shape();
                let j = self.st.inst[*pk] as usize;
                pair_loss(self.shape, self.poles, other) * self.st.tracker.pair_weight(self.inst, j)
            }
            BasicHazardEntity::Exterior => {
                self.st.bin.exterior_loss(self.shape) * self.st.tracker.static_weight(self.inst)
            }
            BasicHazardEntity::Hole { .. } | BasicHazardEntity::InferiorQualityZone { .. } => {
                self.cde.hazard(k).map_or(0.0, |h| {
                    pair_loss(self.shape, self.poles, &h.shape)
                        * self.st.tracker.static_weight(self.inst)
                })
            }
        }
    }
}

impl HazardCollector for LossCollector<'_> {
    type Entity = BasicHazardEntity;

    fn contains_key(&self, hkey: HazKey) -> bool {
        self.hits.iter().any(|(k, _)| *k == hkey)
    }

    fn insert(&mut self, hkey: HazKey, entity: BasicHazardEntity) {
        let l = self.weighted(hkey, &entity);
        self.hits.push((hkey, entity));
        self.loss.set(self.loss.get() + l);
    }

    fn remove_by_key(&mut self, hkey: HazKey) {
        if let Some(p) = self.hits.iter().position(|(k, _)| *k == hkey) {
            let (k, e) = self.hits.swap_remove(p);
            self.loss.set(self.loss.get() - self.weighted(k, &e));
        }
    }

    fn len(&self) -> usize {
        self.hits.len()
    }

    fn iter(&self) -> impl Iterator<Item = (HazKey, &BasicHazardEntity)> {
        self.hits.iter().map(|(k, e)| (*k, e))
    }
}

/// Weighted collision loss of one piece instance moving within a layout.
pub(crate) struct SeparationEval<'a> {
    st: &'a State,
    kind: &'a Kind,
    inst: usize,
    filter: PieceFilter,
    shape: SPolygon,
    poles: Poles,
    hits: Vec<(HazKey, BasicHazardEntity)>,
}

impl<'a> SeparationEval<'a> {
    pub(crate) fn new(st: &'a State, prob: &'a Problem, inst: usize) -> Self {
        let kind = prob.kind_of(inst);
        Self {
            st,
            kind,
            inst,
            filter: st.filter(prob, inst),
            shape: kind.jitem.shape_cd().as_ref().clone(),
            poles: Poles::default(),
            hits: Vec::new(),
        }
    }
}

impl Evaluator for SeparationEval<'_> {
    fn eval(&mut self, dt: DTransformation, bound: Eval) -> Eval {
        let bound = match bound {
            Eval::Clear(_) => 0.0,
            Eval::Collision(l) => l,
            Eval::Invalid => f32::INFINITY,
        };
        let cde = self.st.layout.cde();
        self.shape
            .transform_from(self.kind.jitem.shape_cd(), &dt.compose());
        self.poles.load(self.shape.surrogate());
        self.hits.clear();
        let loss = Cell::new(0.0f32);
        let mut coll = LossCollector {
            hits: &mut self.hits,
            loss: &loss,
            st: self.st,
            cde,
            inst: self.inst,
            shape: &self.shape,
            poles: &self.poles,
        };
        let over = |_| loss.get() > bound;
        // the largest poles first: deep overlaps show up (and end the query) early
        if cde.collect_surrogate_collisions_until(&self.shape, &self.filter, &mut coll, over)
            || cde.collect_poly_collisions_until(&self.shape, &self.filter, &mut coll, over)
        {
            return Eval::Invalid;
        }
        if coll.hits.is_empty() {
            Eval::Clear(0.0)
        } else {
            Eval::Collision(loss.get())
        }
    }
}

/// Feasibility plus a left-bottom score, for the construction.
pub(crate) struct FillEval<'a> {
    layout: &'a Layout,
    kind: &'a Kind,
    filter: PieceFilter,
    shape: SPolygon,
}

impl<'a> FillEval<'a> {
    pub(crate) fn new(layout: &'a Layout, kind: &'a Kind) -> Self {
        Self {
            layout,
            kind,
            filter: PieceFilter {
                own: None,
                min_quality: kind.min_quality,
            },
            shape: kind.jitem.shape_cd().as_ref().clone(),
        }
    }
}

impl Evaluator for FillEval<'_> {
    fn eval(&mut self, dt: DTransformation, _bound: Eval) -> Eval {
        let cde = self.layout.cde();
        let t = dt.compose();
        if cde.detect_surrogate_collision(self.kind.jitem.shape_cd().surrogate(), &t, &self.filter)
        {
            return Eval::Invalid;
        }
        self.shape.transform_from(self.kind.jitem.shape_cd(), &t);
        if cde.detect_poly_collision(&self.shape, &self.filter) {
            return Eval::Invalid;
        }
        let poi = self.shape.poi().center;
        let b = self.shape.bbox();
        Eval::Clear(LBF_X_WEIGHT * (poi.0 + b.x_min) + (poi.1 + b.y_min))
    }
}
