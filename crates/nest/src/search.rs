//! The nesting search: items and stock in, placements and utilization out.

use flatcut_geom::DVec2;
use flatcut_pattern::Placement;
use jagua_rs::collision_detection::CDEConfig;
use jagua_rs::collision_detection::hazards::filter::NoFilter;
use jagua_rs::entities::{Item, Layout, LayoutSnapshot};
use jagua_rs::geometry::DTransformation;
use jagua_rs::geometry::fail_fast::SPSurrogateConfig;
use jagua_rs::geometry::geo_traits::Transformable;
use jagua_rs::io::ext_repr::{
    ExtContainer, ExtItem, ExtOrientation, ExtRotation, ExtSPolygon, ExtShape,
};
use jagua_rs::io::import::Importer;
use std::sync::Arc;
use std::time::{Duration, Instant};
use thiserror::Error;

/// Errors of the nester; messages name the item.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum NestError {
    #[error("item `{item}`: {reason}")]
    InvalidItem { item: String, reason: String },
    #[error(
        "item `{item}` ({w:.1} × {h:.1} mm) does not fit the {stock} in any allowed orientation"
    )]
    PieceTooLarge {
        item: String,
        w: f64,
        h: f64,
        stock: String,
    },
    #[error("invalid nesting input: {0}")]
    InvalidInput(String),
    #[error("collision engine: {0}")]
    Engine(String),
}

/// Allowed rotations of an item.
#[derive(Clone, Debug, PartialEq)]
pub enum Rotations {
    /// As drawn only.
    None,
    /// 0° and 180° (keeps a grain line parallel).
    Half,
    /// Multiples of 90°.
    Quarter,
    /// Any angle, sampled every `360° / NestOptions::free_rotation_steps`.
    Free,
    /// An explicit list (radians).
    List(Vec<f64>),
}

/// One piece type to nest.
#[derive(Clone, Debug, PartialEq)]
pub struct NestItem {
    /// Name used in reports and errors.
    pub name: String,
    /// Outline (cut line), closed, without repeated end point (mm). Either orientation.
    pub outline: Vec<DVec2>,
    /// Copies to place (for a mirrored pair: copies of each side).
    pub quantity: usize,
    pub rotations: Rotations,
    /// Angle of the grain line in the piece frame (radians). When set, the piece may only be
    /// turned so its grain runs along the x axis (the roll's length / sheet width): the
    /// allowed rotations become {−g, π − g}, or {−g} with [`Rotations::None`].
    pub grain_angle: Option<f64>,
    /// Also place `quantity` mirror images (left/right shoe parts).
    pub mirrored_pair: bool,
}

impl NestItem {
    /// An item with `quantity` copies, rotations 0/180°, no grain, no mirror.
    pub fn new(name: impl Into<String>, outline: Vec<DVec2>, quantity: usize) -> Self {
        Self {
            name: name.into(),
            outline,
            quantity,
            rotations: Rotations::Half,
            grain_angle: None,
            mirrored_pair: false,
        }
    }
}

/// The material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stock {
    /// A roll of fixed `width` (y) whose used length (x) is minimised.
    Roll { width: f64, max_length: Option<f64> },
    /// Identical sheets `width` (x) × `height` (y); the number used is minimised.
    Sheets {
        width: f64,
        height: f64,
        max_sheets: Option<usize>,
    },
}

impl Stock {
    fn describe(&self) -> String {
        match self {
            Stock::Roll { width, .. } => format!("roll of width {width:.1} mm"),
            Stock::Sheets { width, height, .. } => format!("sheet {width:.1} × {height:.1} mm"),
        }
    }
}

/// Search options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NestOptions {
    /// Minimum gap between pieces and from the stock edge (kerf, knife clearance), mm.
    pub spacing: f64,
    pub seed: u64,
    /// Local-search iterations after the construction (0 = bottom-left fill only).
    pub max_iters: usize,
    /// Wall-clock budget of the local search (`None` = iterations only, fully deterministic).
    pub time_limit: Option<Duration>,
    /// Random position samples per orientation when placing one piece.
    pub samples: usize,
    /// Angles tried for [`Rotations::Free`].
    pub free_rotation_steps: usize,
}

impl NestOptions {
    /// 2 mm between pieces: a typical knife/laser clearance.
    pub const DEFAULT_SPACING: f64 = 2.0;
    pub const DEFAULT_SEED: u64 = 0;
    pub const DEFAULT_MAX_ITERS: usize = 200;
    /// 300 samples per orientation: enough to find the bottom-left region on benchmark-sized
    /// strips before the slide refines it.
    pub const DEFAULT_SAMPLES: usize = 300;
    /// 24 angles = 15° steps for free rotation.
    pub const DEFAULT_FREE_ROTATION_STEPS: usize = 24;
    pub const DEFAULT: Self = Self {
        spacing: Self::DEFAULT_SPACING,
        seed: Self::DEFAULT_SEED,
        max_iters: Self::DEFAULT_MAX_ITERS,
        time_limit: None,
        samples: Self::DEFAULT_SAMPLES,
        free_rotation_steps: Self::DEFAULT_FREE_ROTATION_STEPS,
    };
    pub fn with_spacing(mut self, v: f64) -> Self {
        self.spacing = v;
        self
    }
    pub fn with_seed(mut self, v: u64) -> Self {
        self.seed = v;
        self
    }
    pub fn with_max_iters(mut self, v: usize) -> Self {
        self.max_iters = v;
        self
    }
    pub fn with_time_limit(mut self, v: Option<Duration>) -> Self {
        self.time_limit = v;
        self
    }
    pub fn with_samples(mut self, v: usize) -> Self {
        self.samples = v;
        self
    }
}

impl Default for NestOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Reported while searching.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NestProgress {
    pub iteration: usize,
    pub elapsed: Duration,
    /// Used roll length, or the extent on the last sheet (mm).
    pub length: f64,
    pub sheets: usize,
    pub utilization: f64,
}

/// One placed piece instance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlacedInstance {
    /// Index into the input items.
    pub item: usize,
    /// Copy number (0-based) among the item's copies of this side.
    pub copy: usize,
    /// Sheet index (always 0 on a roll).
    pub sheet: usize,
    /// Piece frame → stock frame (the mirror flag marks the mirrored side of a pair).
    pub placement: Placement,
}

/// An instance that could not be placed.
#[derive(Clone, Debug, PartialEq)]
pub struct Unplaced {
    pub item: usize,
    pub name: String,
    pub copy: usize,
    pub mirrored: bool,
    pub reason: String,
}

/// The layout found.
#[derive(Clone, Debug, PartialEq)]
pub struct NestResult {
    pub placed: Vec<PlacedInstance>,
    pub unplaced: Vec<Unplaced>,
    /// Placed piece area / used stock area, in percent.
    pub utilization: f64,
    /// Used roll length (max x of the pieces), or the extent on the last sheet.
    pub length: f64,
    pub sheets: usize,
    /// Utilization of the bottom-left-fill construction the search started from (percent).
    pub baseline_utilization: f64,
    pub baseline_length: f64,
    pub iterations: usize,
}

/// Signed area of a polygon (positive CCW).
pub fn polygon_area(p: &[DVec2]) -> f64 {
    let n = p.len();
    (0..n).map(|i| p[i].perp_dot(p[(i + 1) % n])).sum::<f64>() * 0.5
}

/// SplitMix64: a tiny, well-mixed seeded generator; enough for sampling, and fully portable
/// (its output is fixed by the seed on every platform).
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
}

/// A side of an item as the engine sees it.
struct Variant {
    item: usize,
    mirrored: bool,
    outline: Vec<DVec2>,
    area: f64,
    angles: Vec<f64>,
    jitem: Arc<Item>,
}

#[derive(Clone, Copy)]
struct Instance {
    variant: usize,
    copy: usize,
}

/// Lexicographic objective: unplaced, bins, extent (smaller is better).
type Objective = (usize, usize, f64);

#[derive(Clone)]
struct Solution {
    order: Vec<usize>,
    /// State before each step: bin snapshots.
    snaps: Vec<Vec<LayoutSnapshot>>,
    /// Per step: (bin, transformation) or None when unplaced.
    steps: Vec<Option<(usize, DTransformation)>>,
    final_bins: Vec<LayoutSnapshot>,
    obj: Objective,
}

struct Engine<'a> {
    variants: Vec<Variant>,
    instances: Vec<Instance>,
    importer: Importer,
    stock: Stock,
    opts: &'a NestOptions,
    /// Container length used for a roll (an upper bound on the used length).
    roll_len: f64,
    names: Vec<String>,
}

/// Inset from the stock edges, relative to the piece size: the engine treats touching
/// edges as a collision, and f32 coordinates need some room.
const EDGE_INSET: f32 = 1e-4;

fn cde_config() -> CDEConfig {
    CDEConfig {
        quadtree_depth: 5,
        cd_threshold: 16,
        item_surrogate_config: SPSurrogateConfig {
            n_pole_limits: [(64, 0.0), (16, 0.8), (8, 0.9)],
            ff_pole_area_ratio: 0.05,
            n_ff_piers: 0,
        },
    }
}

/// Places items on the stock. Calls `progress` after the construction and after every
/// local-search iteration.
pub fn nest(
    items: &[NestItem],
    stock: Stock,
    opts: &NestOptions,
    progress: &mut dyn FnMut(&NestProgress),
) -> Result<NestResult, NestError> {
    check_input_size(items, stock, opts.spacing)?;
    let eng = Engine::new(items, stock, opts)?;
    let start = Instant::now();
    let mut rng = Rng(opts.seed ^ 0x5EED_F1A7_C0DE_0001);
    // construction: decreasing area, then input order
    let mut order: Vec<usize> = (0..eng.instances.len()).collect();
    order.sort_by(|&a, &b| {
        let (va, vb) = (
            &eng.variants[eng.instances[a].variant],
            &eng.variants[eng.instances[b].variant],
        );
        vb.area.total_cmp(&va.area).then(a.cmp(&b))
    });
    let mut best = eng.decode(order, None, 0, &mut rng);
    let baseline = eng.measure(&best);
    progress(&NestProgress {
        iteration: 0,
        elapsed: start.elapsed(),
        length: baseline.1,
        sheets: baseline.2,
        utilization: baseline.0,
    });
    let n = best.order.len();
    let mut iters = 0;
    while iters < opts.max_iters && n >= 2 {
        if opts.time_limit.is_some_and(|t| start.elapsed() >= t) {
            break;
        }
        iters += 1;
        let mut order = best.order.clone();
        let i = rng.below(n);
        let mut j = rng.below(n);
        if i == j {
            j = (j + 1) % n;
        }
        let first = i.min(j);
        if rng.below(2) == 0 {
            order.swap(i, j);
        } else {
            let v = order.remove(j);
            order.insert(i, v);
        }
        if eng.instances[order[first]].variant == eng.instances[best.order[first]].variant
            && order[first..] == best.order[first..]
        {
            continue;
        }
        let cand = eng.decode(order, Some(&best), first, &mut rng);
        if cand.obj.0 < best.obj.0
            || (cand.obj.0 == best.obj.0 && cand.obj.1 < best.obj.1)
            || (cand.obj.0 == best.obj.0 && cand.obj.1 == best.obj.1 && cand.obj.2 <= best.obj.2)
        {
            best = cand;
        }
        let m = eng.measure(&best);
        progress(&NestProgress {
            iteration: iters,
            elapsed: start.elapsed(),
            length: m.1,
            sheets: m.2,
            utilization: m.0,
        });
    }
    Ok(eng.result(&best, baseline, iters))
}

/// Largest sheet side, roll width or roll length the nester accepts (mm): 100 m. The collision
/// engine computes in f32, whose resolution at 1e5 mm is 8 µm; at 1e6 mm it is 62 µm, coarser
/// than the engine's edge inset, and the search slows by an order of magnitude (measured: a
/// 1e6 mm sheet took 8× as long as a 2 m one for the same pieces; 1e9 mm never finished).
pub const MAX_STOCK_MM: f64 = 1e5;
/// Most piece instances (copies, mirrored copies included) one nesting run places.
pub const MAX_INSTANCES: usize = 10_000;

/// Input checks at the public entry: a stock the engine can resolve, and a bounded number of
/// instances, before anything is allocated for them.
fn check_input_size(items: &[NestItem], stock: Stock, spacing: f64) -> Result<(), NestError> {
    let sides: Vec<f64> = match stock {
        Stock::Roll { width, max_length } => std::iter::once(width).chain(max_length).collect(),
        Stock::Sheets { width, height, .. } => vec![width, height],
    };
    if sides.iter().any(|s| !(s.is_finite() && *s <= MAX_STOCK_MM)) {
        return Err(NestError::InvalidInput(format!(
            "the {} is larger than the {MAX_STOCK_MM:e} mm the nester accepts",
            stock.describe()
        )));
    }
    // The engine shrinks the stock by the spacing; a spacing of half its width leaves nothing
    // (the engine's own words were "Offset resulted in an empty polygon").
    let narrowest = sides.iter().copied().fold(f64::INFINITY, f64::min);
    if 2.0 * spacing >= narrowest {
        return Err(NestError::InvalidInput(format!(
            "a spacing of {spacing} mm from the edges leaves no room on the {}",
            stock.describe()
        )));
    }
    let mut instances = 0usize;
    for it in items {
        let copies = it
            .quantity
            .saturating_mul(if it.mirrored_pair { 2 } else { 1 });
        instances = instances.saturating_add(copies);
    }
    if instances > MAX_INSTANCES {
        return Err(NestError::InvalidInput(format!(
            "{instances} piece copies to place; the nester places at most {MAX_INSTANCES} in one run"
        )));
    }
    Ok(())
}

impl<'a> Engine<'a> {
    fn new(items: &[NestItem], stock: Stock, opts: &'a NestOptions) -> Result<Self, NestError> {
        if !(opts.spacing.is_finite() && opts.spacing >= 0.0) {
            return Err(NestError::InvalidInput(format!(
                "spacing must be ≥ 0, got {}",
                opts.spacing
            )));
        }
        let (sw, sh) = match stock {
            Stock::Roll { width, max_length } => {
                if let Some(l) = max_length.filter(|l| !(l.is_finite() && *l > 0.0)) {
                    return Err(NestError::InvalidInput(format!(
                        "roll length must be positive, got {l}"
                    )));
                }
                (f64::INFINITY, width)
            }
            Stock::Sheets {
                width,
                height,
                max_sheets,
            } => {
                if max_sheets == Some(0) {
                    return Err(NestError::InvalidInput("max_sheets is 0".into()));
                }
                (width, height)
            }
        };
        if !(sh.is_finite() && sh > 0.0 && sw > 0.0) {
            return Err(NestError::InvalidInput(format!(
                "stock size must be positive, got {}",
                stock.describe()
            )));
        }
        let importer = Importer::new(cde_config(), None, None)
            .with_min_item_separation(opts.spacing as f32)
            .map_err(|e| NestError::InvalidInput(e.to_string()))?;
        let mut variants = Vec::new();
        let mut instances = Vec::new();
        let mut total_extent = 0.0;
        for (k, it) in items.iter().enumerate() {
            let bad = |reason: String| NestError::InvalidItem {
                item: it.name.clone(),
                reason,
            };
            if it.quantity == 0 {
                continue;
            }
            if it.outline.len() < 3 || !it.outline.iter().all(|p| flatcut_geom::finite2(*p)) {
                return Err(bad("outline needs at least 3 finite points".into()));
            }
            let mut base = it.outline.clone();
            if polygon_area(&base) < 0.0 {
                base.reverse();
            }
            if polygon_area(&base) <= 0.0 {
                return Err(bad("outline has zero area".into()));
            }
            let mut angles: Vec<f64> = match (&it.rotations, it.grain_angle) {
                (Rotations::None, Some(g)) => vec![-g],
                (_, Some(g)) => vec![-g, std::f64::consts::PI - g],
                (Rotations::None, None) => vec![0.0],
                (Rotations::Half, None) => vec![0.0, std::f64::consts::PI],
                (Rotations::Quarter, None) => (0..4)
                    .map(|i| i as f64 * std::f64::consts::FRAC_PI_2)
                    .collect(),
                (Rotations::Free, None) => {
                    let s = opts.free_rotation_steps.max(1);
                    (0..s)
                        .map(|i| i as f64 * std::f64::consts::TAU / s as f64)
                        .collect()
                }
                (Rotations::List(v), None) => v.clone(),
            };
            if angles.is_empty() || angles.iter().any(|a| !a.is_finite()) {
                return Err(bad("no valid rotation angle".into()));
            }
            angles.dedup();
            let sides: &[bool] = if it.mirrored_pair {
                &[false, true]
            } else {
                &[false]
            };
            for &mirrored in sides {
                let mut outline: Vec<DVec2> = if mirrored {
                    base.iter().map(|p| DVec2::new(-p.x, p.y)).rev().collect()
                } else {
                    base.clone()
                };
                // for the mirrored side, grain angles mirror too: g → π − g
                let angles = if mirrored && it.grain_angle.is_some() {
                    angles
                        .iter()
                        .map(|a| -(std::f64::consts::PI - (-a)))
                        .collect()
                } else {
                    angles.clone()
                };
                outline.dedup();
                let ext = ExtItem {
                    id: variants.len() as u64,
                    orientation: ExtOrientation {
                        rotation: ExtRotation::Continuous {},
                        reflection_axes: vec![],
                    },
                    shape: ExtShape::SimplePolygon(ExtSPolygon(
                        outline.iter().map(|p| (p.x as f32, p.y as f32)).collect(),
                    )),
                    min_quality: None,
                };
                let jitem = importer
                    .import_item(&ext, variants.len())
                    .map_err(|e| bad(format!("rejected by the engine: {e}")))?;
                let bb = flatcut_geom::Aabb2::from_points(outline.iter().copied());
                // the bounding-box diagonal bounds the piece's extent in every rotation, so a
                // roll this long holds all pieces side by side whatever angles the search picks
                total_extent += ((bb.max - bb.min).length() + opts.spacing) * it.quantity as f64;
                let vi = variants.len();
                variants.push(Variant {
                    item: k,
                    mirrored,
                    area: polygon_area(&outline),
                    outline,
                    angles,
                    jitem,
                });
                for copy in 0..it.quantity {
                    instances.push(Instance { variant: vi, copy });
                }
            }
        }
        if instances.is_empty() {
            return Err(NestError::InvalidInput("nothing to place".into()));
        }
        let roll_len = match stock {
            Stock::Roll {
                max_length: Some(l),
                ..
            } => l,
            _ => total_extent + 2.0 * opts.spacing + 1.0,
        };
        let names = items.iter().map(|i| i.name.clone()).collect();
        let eng = Engine {
            variants,
            instances,
            importer,
            stock,
            opts,
            roll_len,
            names,
        };
        // every variant must fit an empty bin in some orientation
        let empty = eng.new_bin()?;
        let mut rng = Rng(1);
        for v in &eng.variants {
            if eng.best_position(&empty, v, &mut rng).is_none() {
                let bb = flatcut_geom::Aabb2::from_points(v.outline.iter().copied());
                let it = &items[v.item];
                return Err(NestError::PieceTooLarge {
                    item: it.name.clone(),
                    w: bb.max.x - bb.min.x,
                    h: bb.max.y - bb.min.y,
                    stock: stock.describe(),
                });
            }
        }
        Ok(eng)
    }

    fn new_bin(&self) -> Result<Layout, NestError> {
        let (w, h) = match self.stock {
            Stock::Roll { width, .. } => (self.roll_len, width),
            Stock::Sheets { width, height, .. } => (width, height),
        };
        let c = self
            .importer
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
            .map_err(|e| NestError::Engine(e.to_string()))?;
        Ok(Layout::new(c))
    }

    fn feasible(layout: &Layout, item: &Item, dt: &DTransformation) -> bool {
        let t = dt.compose();
        let cde = layout.cde();
        if cde.detect_surrogate_collision(item.shape_cd().surrogate(), &t, &NoFilter) {
            return false;
        }
        let s = item.shape_cd().transform_clone(&t);
        !cde.detect_poly_collision(&s, &NoFilter)
    }

    /// Bottom-left position of a variant in a layout: (transformation, right edge, bottom).
    fn best_position(
        &self,
        layout: &Layout,
        v: &Variant,
        rng: &mut Rng,
    ) -> Option<(DTransformation, f32, f32)> {
        let cb = layout.container().outer_cd().bbox();
        let extent = layout
            .placed_items()
            .values()
            .map(|p| p.shape().bbox().x_max)
            .fold(cb.x_min, f32::max);
        let mut best: Option<(DTransformation, f32, f32)> = None;
        let item = &*v.jitem;
        for &a in &v.angles {
            let a = a as f32;
            let rot = item
                .shape_cd()
                .transform_clone(&DTransformation::new(a, (0.0, 0.0)).compose());
            let bb = rot.bbox();
            let (bw, bh) = (bb.x_max - bb.x_min, bb.y_max - bb.y_min);
            // keep a hair off the stock edges: the engine counts touching edges as collisions
            let eps = EDGE_INSET * bw.max(bh);
            let tx0 = cb.x_min - bb.x_min + eps;
            let tx_max = cb.x_max - bb.x_max - eps;
            let ty0 = cb.y_min - bb.y_min + eps;
            let ty1 = cb.y_max - bb.y_max - eps;
            if tx_max < tx0 || ty1 < ty0 {
                continue;
            }
            // sample where the piece's left edge is left of the current extent
            let tx1 = (extent - bb.x_min).clamp(tx0, tx_max);
            let score =
                |t: &DTransformation| (t.translation().0 + bb.x_max, t.translation().1 + bb.y_min);
            let better = |s: (f32, f32), b: &Option<(DTransformation, f32, f32)>| {
                b.as_ref()
                    .is_none_or(|(_, bx, by)| s.0 < *bx - 1e-4 || (s.0 <= *bx + 1e-4 && s.1 < *by))
            };
            // samples: a third on the bottom edge, a third on the top edge, a third anywhere
            let mut cands: Vec<(DTransformation, (f32, f32))> = Vec::new();
            let n = self.opts.samples.max(3);
            for k in 0..n {
                let x = tx0 + (tx1 - tx0) * rng.unit() as f32;
                let y = match k % 3 {
                    0 => ty0,
                    1 => ty1,
                    _ => ty0 + (ty1 - ty0) * rng.unit() as f32,
                };
                let dt = DTransformation::new(a, (x, y));
                let s = score(&dt);
                if better(s, &best) && Self::feasible(layout, item, &dt) {
                    cands.push((dt, s));
                }
            }
            if cands.is_empty() {
                // a roll extends beyond the current extent: try right of it
                let x = (extent + eps - bb.x_min).clamp(tx0, tx_max);
                for y in [ty0, ty1, 0.5 * (ty0 + ty1)] {
                    let dt = DTransformation::new(a, (x, y));
                    if Self::feasible(layout, item, &dt) {
                        cands.push((dt, score(&dt)));
                        break;
                    }
                }
            }
            cands.sort_by(|p, q| p.1.0.total_cmp(&q.1.0).then(p.1.1.total_cmp(&q.1.1)));
            for (dt, _) in cands.into_iter().take(3) {
                let dt = self.slide(layout, item, dt, a, bw.max(bh), (tx0, ty0));
                let s = score(&dt);
                if better(s, &best) {
                    best = Some((dt, s.0, s.1));
                }
            }
        }
        best
    }

    /// Moves a feasible placement left, then down, with halving steps.
    fn slide(
        &self,
        layout: &Layout,
        item: &Item,
        dt: DTransformation,
        a: f32,
        size: f32,
        lo: (f32, f32),
    ) -> DTransformation {
        let (mut x, mut y) = dt.translation();
        let min_step = (size * 1e-3).max(1e-4);
        let mut step = size * 0.25;
        while step >= min_step {
            let mut moved = false;
            for (dx, dy) in [(-step, 0.0), (0.0, -step)] {
                let (nx, ny) = ((x + dx).max(lo.0), (y + dy).max(lo.1));
                if (nx, ny) == (x, y) {
                    continue;
                }
                if Self::feasible(layout, item, &DTransformation::new(a, (nx, ny))) {
                    x = nx;
                    y = ny;
                    moved = true;
                    break;
                }
            }
            if !moved {
                step *= 0.5;
            }
        }
        DTransformation::new(a, (x, y))
    }

    /// Decodes `order` from step `from`, reusing the states of `prev` before it.
    fn decode(
        &self,
        order: Vec<usize>,
        prev: Option<&Solution>,
        from: usize,
        rng: &mut Rng,
    ) -> Solution {
        let n = order.len();
        let (mut snaps, mut steps, mut bins) = match prev {
            Some(p) if from > 0 => (
                p.snaps[..from].to_vec(),
                p.steps[..from].to_vec(),
                p.snaps[from]
                    .iter()
                    .map(Layout::from_snapshot)
                    .collect::<Vec<_>>(),
            ),
            _ => (Vec::with_capacity(n), Vec::with_capacity(n), Vec::new()),
        };
        if bins.is_empty()
            && let Ok(b) = self.new_bin()
        {
            bins.push(b);
        }
        let max_bins = match self.stock {
            Stock::Roll { .. } => 1,
            Stock::Sheets { max_sheets, .. } => max_sheets.unwrap_or(usize::MAX),
        };
        for k in from..n {
            snaps.push(bins.iter().map(Layout::save).collect());
            let v = &self.variants[self.instances[order[k]].variant];
            let mut placed = None;
            for (b, bin) in bins.iter().enumerate() {
                if let Some((dt, _, _)) = self.best_position(bin, v, rng) {
                    placed = Some((b, dt));
                    break;
                }
            }
            if placed.is_none()
                && bins.len() < max_bins
                && let Ok(nb) = self.new_bin()
                && let Some((dt, _, _)) = self.best_position(&nb, v, rng)
            {
                bins.push(nb);
                placed = Some((bins.len() - 1, dt));
            }
            if let Some((b, dt)) = placed {
                bins[b].place_item(&v.jitem, dt);
            }
            steps.push(placed);
        }
        let unplaced = steps.iter().filter(|s| s.is_none()).count();
        let last_extent = bins
            .last()
            .map(|l| {
                l.placed_items()
                    .values()
                    .map(|p| p.shape().bbox().x_max as f64)
                    .fold(0.0, f64::max)
            })
            .unwrap_or(0.0);
        let final_bins = bins.iter().map(Layout::save).collect();
        Solution {
            order,
            snaps,
            steps,
            final_bins,
            obj: (unplaced, bins.len(), last_extent),
        }
    }

    fn placements(&self, sol: &Solution) -> Vec<(usize, PlacedInstance)> {
        let mut out = Vec::new();
        for (k, st) in sol.steps.iter().enumerate() {
            let Some((bin, dt)) = st else { continue };
            let inst = self.instances[sol.order[k]];
            let v = &self.variants[inst.variant];
            let pre = v.jitem.shape_orig().pre_transform.translation();
            let rot = dt.rotation() as f64;
            let t = dt.translation();
            let r = DVec2::from_angle(rot);
            let translation = DVec2::new(t.0 as f64, t.1 as f64)
                + r.rotate(DVec2::new(pre.0 as f64, pre.1 as f64));
            out.push((
                inst.variant,
                PlacedInstance {
                    item: v.item,
                    copy: inst.copy,
                    sheet: *bin,
                    placement: Placement {
                        rotation: rot,
                        mirror: v.mirrored,
                        translation,
                    },
                },
            ));
        }
        out
    }

    /// (utilization %, length, bins) of a solution, measured on the original outlines.
    fn measure(&self, sol: &Solution) -> (f64, f64, usize) {
        let pl = self.placements(sol);
        let bins = sol.final_bins.len().max(1);
        let area: f64 = pl.iter().map(|(v, _)| self.variants[*v].area).sum();
        let last = bins - 1;
        let length = pl
            .iter()
            .filter(|(_, p)| p.sheet == last)
            .flat_map(|(v, p)| {
                let o = p.placement;
                self.variants[*v].outline.iter().map(move |q| {
                    let q = if o.mirror { DVec2::new(-q.x, q.y) } else { *q };
                    o.translation.x + DVec2::from_angle(o.rotation).rotate(q).x
                })
            })
            .fold(0.0, f64::max);
        let used = match self.stock {
            Stock::Roll { width, .. } => length * width,
            Stock::Sheets { width, height, .. } => bins as f64 * width * height,
        };
        let util = if used > 0.0 { 100.0 * area / used } else { 0.0 };
        (util, length, bins)
    }

    fn result(&self, sol: &Solution, baseline: (f64, f64, usize), iterations: usize) -> NestResult {
        let (utilization, length, sheets) = self.measure(sol);
        let mut placed: Vec<PlacedInstance> =
            self.placements(sol).into_iter().map(|(_, p)| p).collect();
        placed.sort_by(|a, b| {
            (a.item, a.placement.mirror, a.copy).cmp(&(b.item, b.placement.mirror, b.copy))
        });
        let mut unplaced = Vec::new();
        for (k, st) in sol.steps.iter().enumerate() {
            if st.is_none() {
                let inst = self.instances[sol.order[k]];
                let v = &self.variants[inst.variant];
                unplaced.push(Unplaced {
                    item: v.item,
                    name: self.names[v.item].clone(),
                    copy: inst.copy,
                    mirrored: v.mirrored,
                    reason: match self.stock {
                        Stock::Roll { .. } => "no room within the roll length".into(),
                        Stock::Sheets { .. } => "no room on the allowed sheets".into(),
                    },
                });
            }
        }
        unplaced.sort_by_key(|a| (a.item, a.mirrored, a.copy));
        NestResult {
            placed,
            unplaced,
            utilization,
            length,
            sheets,
            baseline_utilization: baseline.0,
            baseline_length: baseline.1,
            iterations,
        }
    }
}

impl NestItem {
    /// A nesting item from a built pattern piece: its cut line, its grain line (when it has
    /// one, rotations are limited to keep the grain along the roll), `quantity` copies per side.
    pub fn from_piece(
        piece: &flatcut_pattern::Piece,
        quantity: usize,
        mirrored_pair: bool,
    ) -> Self {
        Self {
            name: piece.name.clone(),
            outline: piece.cut.clone(),
            quantity,
            rotations: Rotations::Half,
            grain_angle: piece.grain.map(|(a, b)| (b - a).y.atan2((b - a).x)),
            mirrored_pair,
        }
    }
}

/// The placed instances of sheet `sheet` as pattern placements (for SVG/DXF export), with
/// instance numbers counted per piece from 1; `pieces[i]` must be the piece of item `i`.
pub fn placed_pieces<'a>(
    pieces: &'a [flatcut_pattern::Piece],
    result: &NestResult,
    sheet: usize,
) -> Vec<flatcut_pattern::PlacedPiece<'a>> {
    let mut counters = vec![0u32; pieces.len()];
    let mut out = Vec::new();
    for p in &result.placed {
        let Some(piece) = pieces.get(p.item) else {
            continue;
        };
        counters[p.item] += 1;
        if p.sheet == sheet {
            out.push(flatcut_pattern::PlacedPiece {
                piece,
                instance: counters[p.item],
                placement: p.placement,
            });
        }
    }
    out
}
