//! Nesting: place pattern pieces on a roll, sheets or leather hides, with jagua-rs as the
//! collision-detection engine.
//!
//! The search is ours and follows the method of Gardeyn & Vanden Berghe, "An open-source
//! heuristic to reboot 2D nesting research" (2025, arXiv:2509.13329), the method of sparrow:
//! pieces may overlap during the search; a guided local search moves overlapping pieces to
//! places of least *weighted* overlap (the weights of pairs that keep colliding grow), overlap
//! being quantified on the pieces' inscribed circles (poles) so it is smooth and cheap; the
//! strip is shrunk whenever a layout is separated (exploration, with restarts from disrupted
//! layouts when separation fails) and then by ever smaller random cuts (compression).
//! Sheets and hides are filled in order and improved by the same separation.
//!
//! - Rotations per piece, grain rules (`fixed`, `0,180`, `any`, with a tolerance), mirrored
//!   pairs placed as mirror images, spacing (kerf), rolls, sheets and hides with defects,
//!   graded quality zones and a grain direction field.
//! - Deterministic: the same input, seed and worker count give the same layout with an
//!   iteration budget, whatever the number of threads. A time budget stops after however many
//!   iterations the machine managed.
//! - Bounded: inputs are checked (finite, coordinates within [`MAX_COORD_MM`], stock within
//!   [`MAX_STOCK_MM`], at most [`MAX_INSTANCES`] pieces and [`MAX_VERTICES`] per outline); the time limit and the cancel hook are honoured in
//!   every phase; progress is reported per phase.
#![warn(missing_docs)]

mod bin;
mod bins;
mod budget;
mod construct;
mod distance;
mod error;
mod evaluate;
mod field;
mod hide_io;
pub mod instance;
mod item;
mod options;
mod orient;
mod problem;
mod progress;
mod quantify;
mod result;
mod search;
mod separate;
mod state;
mod stock;
mod strip;
mod tracker;

pub use error::NestError;
pub use hide_io::{HideFormat, read_hide};
pub use instance::{BenchInstance, load_bench_instance, load_scarpa};
pub use item::{GrainDirections, NestItem, Rotations};
pub use options::NestOptions;
pub use problem::{MAX_COORD_MM, MAX_INSTANCES, MAX_STOCK_MM, MAX_VERTICES};
pub use progress::{NestPhase, NestProgress};
pub use result::{NestResult, PlacedInstance, SheetUse, Unplaced};
pub use stock::{Hide, QualityZone, Stock};

use bin::Bin;
use bins::{Supply, nest_bins};
use budget::Budget;
use flatcut_geom::DVec2;
use jagua_rs::geometry::Transformation;
use jagua_rs::geometry::geo_traits::TransformableFrom;
use problem::Problem;
use state::Snap;
use stock::Material;
use strip::nest_strip;

/// Most sheets one run may open.
const MAX_SHEETS: usize = 10_000;

/// Signed area of a polygon (positive CCW).
pub fn polygon_area(p: &[DVec2]) -> f64 {
    problem::polygon_area(p)
}

/// Places items on a roll or on sheets. Calls `progress` after the construction and whenever a
/// better layout is found (on the calling thread).
///
/// Four 100 × 50 mm rectangles on a roll 110 mm wide, 2 mm apart: every one placed, on no less
/// roll than their area needs and no more than a single file of them.
///
/// ```
/// use flatcut_geom::DVec2;
/// use flatcut_nest::{NestItem, NestOptions, Stock, nest};
///
/// let rect = [(0., 0.), (100., 0.), (100., 50.), (0., 50.)].map(|(x, y)| DVec2::new(x, y)).to_vec();
/// let items = [NestItem::new("panel", rect, 4)];
/// let stock = Stock::Roll { width: 110.0, max_length: None };
/// let opts = NestOptions::DEFAULT.with_max_iters(50);
/// let r = nest(&items, stock, &opts, &mut |_| {})?;
/// assert_eq!((r.placed.len(), r.unplaced.len()), (4, 0));
/// assert!(r.length >= 4.0 * 100.0 * 50.0 / 110.0 && r.length <= 4.0 * 102.0 + 2.0, "{}", r.length);
/// # Ok::<(), flatcut_nest::NestError>(())
/// ```
pub fn nest(
    items: &[NestItem],
    stock: Stock,
    opts: &NestOptions,
    progress: &mut dyn FnMut(&NestProgress),
) -> Result<NestResult, NestError> {
    check_stock(&stock, opts.spacing)?;
    run(items, Material::Stock(stock), opts, progress)
}

/// Places items on hides, in order: as much piece area as possible, on as few hides as
/// possible, each filled as far as it goes. Pieces that fit nowhere are reported as unplaced.
pub fn nest_hides(
    items: &[NestItem],
    hides: &[Hide],
    opts: &NestOptions,
    progress: &mut dyn FnMut(&NestProgress),
) -> Result<NestResult, NestError> {
    if hides.is_empty() {
        return Err(NestError::InvalidInput("no hide given".into()));
    }
    run(items, Material::Hides(hides), opts, progress)
}

fn check_stock(stock: &Stock, spacing: f64) -> Result<(), NestError> {
    let bad = |reason: String| NestError::InvalidStock {
        stock: stock.describe(),
        reason,
    };
    let sides: Vec<f64> = match *stock {
        Stock::Roll { width, max_length } => std::iter::once(width).chain(max_length).collect(),
        Stock::Sheets {
            width,
            height,
            max_sheets,
        } => {
            if max_sheets.is_some_and(|m| m == 0 || m > MAX_SHEETS) {
                return Err(bad(format!("max_sheets must be within 1..={MAX_SHEETS}")));
            }
            vec![width, height]
        }
    };
    if sides.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
        return Err(bad("sizes must be finite and positive".into()));
    }
    if sides.iter().any(|s| *s > MAX_STOCK_MM) {
        return Err(bad(format!(
            "larger than the {MAX_STOCK_MM:e} mm the nester accepts"
        )));
    }
    // the engine shrinks the stock by half the spacing on every side
    let narrowest = sides.iter().copied().fold(f64::INFINITY, f64::min);
    if spacing.is_finite() && 2.0 * spacing >= narrowest {
        return Err(bad(format!(
            "a spacing of {spacing} mm from the edges leaves no room"
        )));
    }
    Ok(())
}

fn make_pool(opts: &NestOptions) -> Option<rayon::ThreadPool> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads = if opts.threads == 0 {
        cores
    } else {
        opts.threads
    }
    .min(opts.workers.max(1));
    if threads <= 1 {
        return None;
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .ok()
}

/// Every kind must fit an empty sheet or roll in one of its allowed orientations.
fn check_fits(prob: &Problem, stock: &Stock) -> Result<(), NestError> {
    let (w, h) = match *stock {
        Stock::Roll { width, max_length } => (max_length.unwrap_or(f64::INFINITY), width),
        Stock::Sheets { width, height, .. } => (width, height),
    };
    for k in &prob.kinds {
        let base = k.jitem.shape_cd();
        let mut buf = base.as_ref().clone();
        let fits = |buf: &mut jagua_rs::geometry::primitives::SPolygon, a: f32| {
            let b = buf
                .transform_from(base, &Transformation::from_rotation(a))
                .bbox();
            (b.width() as f64) <= w && (b.height() as f64) <= h
        };
        let steps = if k.turns.can_wiggle() { 720 } else { 1 };
        let mut ok = false;
        for c in k.turns.sample_angles(steps) {
            if fits(&mut buf, c) {
                ok = true;
                break;
            }
            if let orient::Turns::Bands { half, .. } = k.turns {
                for s in 1..=16 {
                    let d = half * s as f32 / 16.0;
                    if fits(&mut buf, c + d) || fits(&mut buf, c - d) {
                        ok = true;
                        break;
                    }
                }
                if ok {
                    break;
                }
            }
        }
        if !ok {
            let bb = flatcut_geom::Aabb2::from_points(k.outline.iter().copied());
            return Err(NestError::PieceTooLarge {
                item: prob.names[k.item].clone(),
                w: bb.max.x - bb.min.x,
                h: bb.max.y - bb.min.y,
                stock: stock.describe(),
            });
        }
    }
    Ok(())
}

fn run(
    items: &[NestItem],
    material: Material,
    opts: &NestOptions,
    progress: &mut dyn FnMut(&NestProgress),
) -> Result<NestResult, NestError> {
    if opts.workers == 0 || opts.workers > 64 {
        return Err(NestError::InvalidInput(format!(
            "workers must be within 1..=64, got {}",
            opts.workers
        )));
    }
    let (extent, has_field) = match &material {
        Material::Stock(Stock::Roll { width, .. }) => {
            // the strip starts about as long as the pieces' area needs
            let area: f64 = items
                .iter()
                .map(|i| polygon_area(&i.outline).abs() * i.quantity as f64)
                .filter(|a| a.is_finite())
                .sum();
            ((area / width).max(*width), false)
        }
        Material::Stock(Stock::Sheets { width, height, .. }) => (width.max(*height), false),
        Material::Hides(hides) => (
            hides
                .iter()
                .flat_map(|h| h.outline.iter())
                .fold(0.0f64, |m, p| m.max(p.x.abs()).max(p.y.abs())),
            hides.iter().any(|h| !h.directions.is_empty()),
        ),
    };
    let prob = Problem::new(items, &material, opts, extent, has_field)?;
    let pool = make_pool(opts);
    let mut budget = Budget::new(opts.time_limit, opts.max_iters, opts.cancel.clone());
    match material {
        Material::Stock(stock @ Stock::Roll { width, max_length }) => {
            check_fits(&prob, &stock)?;
            let out = nest_strip(
                &prob,
                width,
                opts.workers,
                pool.as_ref(),
                opts.seed,
                &mut budget,
                progress,
            )?;
            let mut res = strip_result(&prob, &out.best, width, &budget);
            let base = strip_result(&prob, &out.baseline, width, &budget);
            res.baseline_utilization = base.utilization;
            res.baseline_length = base.length;
            if let Some(l) = max_length
                && res.length > l
            {
                // the roll is too short for everything: fill one piece of roll that long
                let sheet = Stock::Sheets {
                    width: l,
                    height: width,
                    max_sheets: Some(1),
                };
                let mut r = run(items, Material::Stock(sheet), opts, progress)?;
                r.sheet_use.clear();
                return Ok(r);
            }
            Ok(res)
        }
        Material::Stock(
            stock @ Stock::Sheets {
                width,
                height,
                max_sheets,
            },
        ) => {
            check_fits(&prob, &stock)?;
            let template = Bin::rect(&prob.importer, "sheet".into(), width, height)?;
            let supply = Supply::Sheets {
                template,
                max: max_sheets.unwrap_or(MAX_SHEETS),
            };
            let out = nest_bins(
                &prob,
                supply,
                opts.workers,
                pool.as_ref(),
                opts.seed,
                &mut budget,
                progress,
            );
            Ok(bins_result(&prob, &out, &budget, true))
        }
        Material::Hides(hides) => {
            let bins = hides
                .iter()
                .map(|h| Bin::hide(&prob.importer, h, prob.spacing))
                .collect::<Result<Vec<_>, _>>()?;
            let out = nest_bins(
                &prob,
                Supply::Hides(bins),
                opts.workers,
                pool.as_ref(),
                opts.seed,
                &mut budget,
                progress,
            );
            Ok(bins_result(&prob, &out, &budget, false))
        }
    }
}

/// Max x of an instance's original outline at its placement.
fn outline_extent(prob: &Problem, p: &PlacedInstance) -> f64 {
    let k = prob
        .kinds
        .iter()
        .find(|k| k.item == p.item && k.mirrored == p.placement.mirror)
        .expect("placed kind exists");
    // the kind's outline is the item's, mirrored for the mirrored side: undo that before
    // applying the placement (which mirrors again)
    k.outline
        .iter()
        .map(|q| {
            let q = if k.mirrored {
                DVec2::new(-q.x, q.y)
            } else {
                *q
            };
            p.placement.apply(q).x
        })
        .fold(f64::NEG_INFINITY, f64::max)
}

fn placed_of(prob: &Problem, snap: &Snap, sheet: usize) -> Vec<PlacedInstance> {
    snap.placements()
        .into_iter()
        .map(|(i, dt)| {
            let k = prob.kind_of(i);
            PlacedInstance {
                item: k.item,
                copy: prob.instances[i].1 as usize,
                sheet,
                placement: prob.placement(i, &dt),
            }
        })
        .collect()
}

fn sort_placed(v: &mut [PlacedInstance]) {
    v.sort_by(|a, b| {
        (a.item, a.placement.mirror, a.copy).cmp(&(b.item, b.placement.mirror, b.copy))
    });
}

fn strip_result(prob: &Problem, snap: &Snap, width: f64, budget: &Budget) -> NestResult {
    let mut placed = placed_of(prob, snap, 0);
    sort_placed(&mut placed);
    let length = placed
        .iter()
        .map(|p| outline_extent(prob, p))
        .fold(0.0, f64::max);
    let area: f64 = snap
        .placements()
        .iter()
        .map(|(i, _)| prob.kind_of(*i).area)
        .sum();
    NestResult {
        placed,
        unplaced: Vec::new(),
        utilization: if length > 0.0 {
            100.0 * area / (length * width)
        } else {
            0.0
        },
        length,
        sheets: 1,
        sheet_use: Vec::new(),
        baseline_utilization: 0.0,
        baseline_length: 0.0,
        iterations: budget.iters as usize,
        cancelled: budget.cancelled(),
    }
}

fn bins_result(
    prob: &Problem,
    out: &bins::BinsOutcome,
    budget: &Budget,
    sheets: bool,
) -> NestResult {
    let measure = |snaps: &[Snap]| {
        let mut placed = Vec::new();
        let mut uses = Vec::new();
        for (b, s) in snaps.iter().enumerate() {
            let p = placed_of(prob, s, b);
            let area: f64 = s
                .placements()
                .iter()
                .map(|(i, _)| prob.kind_of(*i).area)
                .sum();
            let usable = s.bin().usable_area;
            uses.push(SheetUse {
                name: if sheets {
                    format!("sheet {}", b + 1)
                } else {
                    s.bin().name.clone()
                },
                pieces: p.len(),
                piece_area: area,
                usable_area: usable,
                yield_pct: if usable > 0.0 {
                    100.0 * area / usable
                } else {
                    0.0
                },
            });
            placed.extend(p);
        }
        let last = snaps.len().saturating_sub(1);
        let length = placed
            .iter()
            .filter(|p| p.sheet == last)
            .map(|p| outline_extent(prob, p))
            .fold(0.0, f64::max);
        let area: f64 = uses.iter().map(|u| u.piece_area).sum();
        let used: f64 = uses.iter().map(|u| u.usable_area).sum();
        let util = if used > 0.0 { 100.0 * area / used } else { 0.0 };
        (placed, uses, length, util)
    };
    let (mut placed, sheet_use, length, utilization) = measure(&out.bins);
    let (_, _, baseline_length, baseline_utilization) = measure(&out.baseline);
    sort_placed(&mut placed);
    let mut unplaced: Vec<Unplaced> = out
        .unplaced
        .iter()
        .map(|&i| {
            let k = prob.kind_of(i);
            Unplaced {
                item: k.item,
                name: prob.names[k.item].clone(),
                copy: prob.instances[i].1 as usize,
                mirrored: k.mirrored,
                reason: if sheets {
                    "no room on the allowed sheets".into()
                } else {
                    "no room on the hides (outline, defects, quality or grain)".into()
                },
            }
        })
        .collect();
    unplaced.sort_by_key(|a| (a.item, a.mirrored, a.copy));
    NestResult {
        placed,
        unplaced,
        utilization,
        length,
        sheets: out.bins.len(),
        sheet_use,
        baseline_utilization,
        baseline_length,
        iterations: budget.iters as usize,
        cancelled: budget.cancelled(),
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
