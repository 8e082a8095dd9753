//! The state of one container during the search: the jagua-rs layout, which piece instance
//! each placed item is, and the collision tracker; saved and restored as a unit.

use crate::bin::Bin;
use crate::problem::Problem;
use crate::quantify::{Poles, pair_loss};
use crate::tracker::{Losses, Tracker};
use jagua_rs::collision_detection::hazards::collector::BasicHazardCollector;
use jagua_rs::collision_detection::hazards::filter::HazardFilter;
use jagua_rs::collision_detection::hazards::{BasicHazardEntity, HazKey};
use jagua_rs::entities::{Layout, LayoutSnapshot, PItemKey};
use jagua_rs::geometry::DTransformation;
use jagua_rs::geometry::primitives::SPolygon;
use slotmap::SecondaryMap;
use std::sync::Arc;

/// Hazards a piece ignores: itself, and quality zones good enough for it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PieceFilter {
    pub own: Option<PItemKey>,
    pub min_quality: usize,
}

impl HazardFilter<BasicHazardEntity> for PieceFilter {
    fn is_irrelevant(&self, _: HazKey, e: &BasicHazardEntity) -> bool {
        match e {
            BasicHazardEntity::PlacedItem { pk, .. } => Some(*pk) == self.own,
            BasicHazardEntity::InferiorQualityZone { quality, .. } => *quality >= self.min_quality,
            _ => false,
        }
    }
}

/// One container's layout during the search.
#[derive(Clone)]
pub(crate) struct State {
    pub bin: Arc<Bin>,
    pub layout: Layout,
    /// Per piece instance: its key in this layout, if placed here.
    pub pk: Vec<Option<PItemKey>>,
    pub inst: SecondaryMap<PItemKey, u32>,
    pub tracker: Tracker,
}

/// A saved [`State`].
#[derive(Clone)]
pub(crate) struct Snap {
    bin: Arc<Bin>,
    layout: LayoutSnapshot,
    pk: Vec<Option<PItemKey>>,
    inst: SecondaryMap<PItemKey, u32>,
    pub losses: Losses,
    pub total_loss: f32,
}

impl Snap {
    pub(crate) fn bin(&self) -> &Arc<Bin> {
        &self.bin
    }

    /// Instances placed in the snapshot with their transformations.
    pub(crate) fn placements(&self) -> Vec<(usize, DTransformation)> {
        self.pk
            .iter()
            .enumerate()
            .filter_map(|(i, k)| k.map(|k| (i, self.layout.placed_items()[k].d_transf())))
            .collect()
    }
}

/// The hazards `shape` collides with, with their losses: (other instance, loss) pairs and the
/// static loss (exterior, defects, zones).
pub(crate) fn quantify_all(
    st: &State,
    shape: &SPolygon,
    filter: &PieceFilter,
) -> (Vec<(u32, f32)>, f32) {
    let cde = st.layout.cde();
    let mut coll = BasicHazardCollector::new();
    cde.collect_poly_collisions(shape, filter, &mut coll);
    let poles = Poles::of(shape);
    let mut hits = Vec::new();
    let mut stat = 0.0;
    for (hkey, e) in coll.iter() {
        match e {
            BasicHazardEntity::PlacedItem { pk, .. } => {
                let other = st.layout.placed_items()[*pk].shape();
                hits.push((st.inst[*pk], pair_loss(shape, &poles, other)));
            }
            BasicHazardEntity::Exterior => stat += st.bin.exterior_loss(shape),
            BasicHazardEntity::Hole { .. } | BasicHazardEntity::InferiorQualityZone { .. } => {
                if let Some(h) = cde.hazard(hkey) {
                    stat += pair_loss(shape, &poles, &h.shape);
                }
            }
        }
    }
    (hits, stat)
}

impl State {
    pub(crate) fn new(bin: Arc<Bin>, n: usize) -> Self {
        Self {
            layout: Layout::new(bin.container.clone()),
            bin,
            pk: vec![None; n],
            inst: SecondaryMap::new(),
            tracker: Tracker::new(n),
        }
    }

    pub(crate) fn filter(&self, prob: &Problem, inst: usize) -> PieceFilter {
        PieceFilter {
            own: self.pk[inst],
            min_quality: prob.kind_of(inst).min_quality,
        }
    }

    pub(crate) fn dt(&self, inst: usize) -> Option<DTransformation> {
        self.pk[inst].map(|k| self.layout.placed_items()[k].d_transf())
    }

    pub(crate) fn shape(&self, inst: usize) -> Option<&Arc<SPolygon>> {
        self.pk[inst].map(|k| self.layout.placed_items()[k].shape())
    }

    /// Instances placed here, in index order.
    pub(crate) fn placed(&self) -> impl Iterator<Item = usize> + '_ {
        self.pk.iter().enumerate().filter_map(|(i, k)| k.map(|_| i))
    }

    pub(crate) fn n_placed(&self) -> usize {
        self.inst.len()
    }

    /// Places (or moves) an instance and updates its losses.
    pub(crate) fn put(&mut self, prob: &Problem, inst: usize, dt: DTransformation) {
        if let Some(k) = self.pk[inst].take() {
            self.layout.remove_item(k);
            self.inst.remove(k);
        }
        let k = self.layout.place_item(&prob.kind_of(inst).jitem, dt);
        self.pk[inst] = Some(k);
        self.inst.insert(k, inst as u32);
        self.recompute(prob, inst);
    }

    /// Removes an instance (its collisions go with it).
    pub(crate) fn take(&mut self, inst: usize) {
        if let Some(k) = self.pk[inst].take() {
            self.layout.remove_item(k);
            self.inst.remove(k);
            self.tracker.set_losses(inst, &[], 0.0);
        }
    }

    /// Recomputes the losses of one placed instance.
    pub(crate) fn recompute(&mut self, prob: &Problem, inst: usize) {
        let Some(k) = self.pk[inst] else { return };
        let shape = self.layout.placed_items()[k].shape().clone();
        let (hits, stat) = quantify_all(self, &shape, &self.filter(prob, inst));
        self.tracker.set_losses(inst, &hits, stat);
    }

    /// Rebuilds the tracker from scratch (weights back to 1).
    pub(crate) fn rebuild_tracker(&mut self, prob: &Problem) {
        self.tracker = Tracker::new(self.pk.len());
        let placed: Vec<usize> = self.placed().collect();
        for i in placed {
            self.recompute(prob, i);
        }
    }

    /// Moves every piece onto a new container of the same kind (a strip of another length).
    pub(crate) fn swap_bin(&mut self, bin: Arc<Bin>) {
        self.layout.swap_container(bin.container.clone());
        self.bin = bin;
    }

    pub(crate) fn save(&self) -> Snap {
        Snap {
            bin: self.bin.clone(),
            layout: self.layout.save(),
            pk: self.pk.clone(),
            inst: self.inst.clone(),
            losses: self.tracker.losses(),
            total_loss: self.tracker.total_loss(),
        }
    }

    /// Restores a snapshot, keeping the current weights.
    pub(crate) fn restore(&mut self, s: &Snap) {
        if !Arc::ptr_eq(&self.bin, &s.bin) || self.layout.restore(&s.layout).is_err() {
            self.layout = Layout::from_snapshot(&s.layout);
            self.bin = s.bin.clone();
        }
        self.pk.clone_from(&s.pk);
        self.inst.clone_from(&s.inst);
        self.tracker.restore_losses(&s.losses);
    }

    /// Restores another state of the same container, weights included.
    pub(crate) fn copy_from(&mut self, other: &State) {
        self.restore(&other.save());
        self.tracker.clone_from(&other.tracker);
    }

    pub(crate) fn feasible(&self) -> bool {
        self.tracker.total_loss() == 0.0
    }

    /// Rightmost x of the collision shapes placed here.
    pub(crate) fn x_extent(&self) -> f32 {
        self.layout
            .placed_items()
            .values()
            .map(|p| p.shape().bbox().x_max)
            .fold(0.0, f32::max)
    }
}
