//! Searching a placement for one piece (Gardeyn & Vanden Berghe 2025, Alg. 6): uniform samples
//! over the container and around the piece's current place, the best few kept apart from each
//! other, each refined by an adaptive coordinate descent, the best of those refined finer.

use crate::bin::Bin;
use crate::evaluate::{Eval, Evaluator};
use crate::orient::Turns;
use crate::problem::{Kind, Problem};
use jagua_rs::geometry::DTransformation;
use jagua_rs::geometry::Transformation;
use jagua_rs::geometry::geo_traits::TransformableFrom;
use jagua_rs::geometry::primitives::Rect;
use rand::RngExt;
use rand::rngs::Xoshiro256PlusPlus;

/// Samples closer than this fraction of the piece's smallest dimension (and 1°) are the same.
const UNIQUE_SAMPLE_RATIO: f32 = 0.05;
/// Coordinate descent: step growth on success, shrink on failure.
const CD_GROW: f32 = 1.1;
const CD_SHRINK: f32 = 0.5;
/// First refinement: translation steps from 25 % down to 2 % of the smallest dimension,
/// rotation steps from 5° down to 1°.
const CD_COARSE: (f32, f32, f32, f32) = (0.25, 0.02, 5.0, 1.0);
/// Final refinement: 1 % down to 0.1 %, 0.5° down to 0.05°.
const CD_FINE: (f32, f32, f32, f32) = (0.01, 0.001, 0.5, 0.05);
/// Hard cap on the steps of one coordinate descent (it normally ends far sooner).
const CD_MAX_STEPS: usize = 1000;

/// How many samples one search takes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SampleConfig {
    pub container: usize,
    pub focused: usize,
    pub descents: usize,
}

/// Where and how a kind may be sampled: per angle, the translation ranges that keep its
/// bounding box inside the container's.
struct Sampler {
    entries: Vec<(f32, (f32, f32), (f32, f32))>,
}

impl Sampler {
    fn new(region: Rect, kind: &Kind, bin: &Bin, angles: &[f32]) -> Option<Self> {
        let cb = bin.container.outer_cd().bbox();
        let base = kind.jitem.shape_cd();
        let mut buf = base.as_ref().clone();
        let mut entries = Vec::new();
        for &a in angles {
            let b = buf
                .transform_from(base, &Transformation::from_rotation(a))
                .bbox();
            let x = (
                (cb.x_min - b.x_min).max(region.x_min),
                (cb.x_max - b.x_max).min(region.x_max),
            );
            let y = (
                (cb.y_min - b.y_min).max(region.y_min),
                (cb.y_max - b.y_max).min(region.y_max),
            );
            if x.0 <= x.1 && y.0 <= y.1 {
                entries.push((a, x, y));
            }
        }
        (!entries.is_empty()).then_some(Self { entries })
    }

    fn sample(&self, rng: &mut Xoshiro256PlusPlus) -> DTransformation {
        let (a, x, y) = self.entries[rng.random_range(0..self.entries.len())];
        let u = |r: (f32, f32), rng: &mut Xoshiro256PlusPlus| {
            if r.1 > r.0 {
                rng.random_range(r.0..r.1)
            } else {
                r.0
            }
        };
        let tx = u(x, rng);
        let ty = u(y, rng);
        DTransformation::new(a, (tx, ty))
    }
}

/// The angle allowed for `kind` at translation `t` closest to `a`.
pub(crate) fn project_turn(kind: &Kind, bin: &Bin, a: f32, t: (f32, f32)) -> f32 {
    if kind.follows_field {
        let g = bin.grain_at(t);
        g + kind.turns.project(a - g)
    } else {
        kind.turns.project(a)
    }
}

/// The angles to sample for `kind` (relative to the local grain when it follows the field).
fn sample_angles(kind: &Kind, steps: usize) -> Vec<f32> {
    if kind.follows_field {
        // any angle is sampled; the position decides the allowed one
        Turns::Continuous.sample_angles(steps)
    } else {
        kind.turns.sample_angles(steps)
    }
}

/// The best `n` samples, kept apart from each other.
struct Best {
    n: usize,
    unique: f32,
    samples: Vec<(DTransformation, Eval)>,
}

fn similar(a: &DTransformation, b: &DTransformation, d: f32) -> bool {
    let (ta, tb) = (a.translation(), b.translation());
    (ta.0 - tb.0).abs() < d
        && (ta.1 - tb.1).abs() < d
        && crate::orient::wrap(a.rotation() - b.rotation()).abs() < 1f32.to_radians()
}

impl Best {
    fn bound(&self) -> Eval {
        if self.samples.len() < self.n {
            Eval::Invalid
        } else {
            self.samples[self.n - 1].1
        }
    }

    fn report(&mut self, dt: DTransformation, e: Eval) {
        if !e.better(&self.bound()) {
            return;
        }
        let close: Vec<usize> = (0..self.samples.len())
            .filter(|&i| similar(&self.samples[i].0, &dt, self.unique))
            .collect();
        if close.iter().any(|&i| !e.better(&self.samples[i].1)) {
            return;
        }
        for i in close.into_iter().rev() {
            self.samples.remove(i);
        }
        if self.samples.len() == self.n {
            self.samples.pop();
        }
        let at = self
            .samples
            .iter()
            .position(|(_, s)| e.better(s))
            .unwrap_or(self.samples.len());
        self.samples.insert(at, (dt, e));
    }
}

#[derive(Clone, Copy)]
enum Axis {
    X,
    Y,
    Diag,
    AntiDiag,
    Turn,
}

fn random_axis(rng: &mut Xoshiro256PlusPlus, turn: bool) -> Axis {
    match rng.random_range(0..if turn { 6 } else { 4 }) {
        0 => Axis::X,
        1 => Axis::Y,
        2 => Axis::Diag,
        3 => Axis::AntiDiag,
        _ => Axis::Turn,
    }
}

/// Refines a sample to a local minimum: two candidates along a random axis, steps growing on
/// success and halving on failure, a new axis whenever a step does not improve.
fn descend(
    start: (DTransformation, Eval),
    kind: &Kind,
    bin: &Bin,
    ev: &mut impl Evaluator,
    steps: (f32, f32, f32, f32),
    rng: &mut Xoshiro256PlusPlus,
) -> (DTransformation, Eval) {
    let turn = kind.turns.can_wiggle();
    let (mut pos, mut eval) = start;
    let (mut sx, mut sy) = (kind.min_dim * steps.0, kind.min_dim * steps.0);
    let t_min = kind.min_dim * steps.1;
    let mut sr = steps.2.to_radians();
    let r_min = steps.3.to_radians();
    let mut axis = random_axis(rng, turn);
    for _ in 0..CD_MAX_STEPS {
        if sx < t_min && sy < t_min && (!turn || sr < r_min) {
            break;
        }
        let (tx, ty) = pos.translation();
        let r = pos.rotation();
        let cands = match axis {
            Axis::X => [(tx + sx, ty, r), (tx - sx, ty, r)],
            Axis::Y => [(tx, ty + sy, r), (tx, ty - sy, r)],
            Axis::Diag => [(tx + sx, ty + sy, r), (tx - sx, ty - sy, r)],
            Axis::AntiDiag => [(tx - sx, ty + sy, r), (tx + sx, ty - sy, r)],
            Axis::Turn => [(tx, ty, r + sr), (tx, ty, r - sr)],
        };
        let mut best: Option<(DTransformation, Eval)> = None;
        for (x, y, a) in cands {
            let a = project_turn(kind, bin, a, (x, y));
            let dt = DTransformation::new(a, (x, y));
            let e = ev.eval(dt, eval);
            if best.as_ref().is_none_or(|b| e.better(&b.1)) {
                best = Some((dt, e));
            }
        }
        let (dt, e) = best.expect("two candidates");
        let better = e.better(&eval);
        if !eval.better(&e) {
            pos = dt;
            eval = e;
        }
        let m = if better { CD_GROW } else { CD_SHRINK };
        match axis {
            Axis::X => sx *= m,
            Axis::Y => sy *= m,
            Axis::Diag | Axis::AntiDiag => {
                sx *= m.sqrt();
                sy *= m.sqrt();
            }
            Axis::Turn => sr *= m,
        }
        if !better {
            axis = random_axis(rng, turn);
        }
    }
    (pos, eval)
}

/// Searches a placement for `inst` in `bin`; `current` is its present placement (evaluated and
/// used to focus part of the samples). Returns the best transformation found and its score.
pub(crate) fn search(
    prob: &Problem,
    bin: &Bin,
    inst: usize,
    current: Option<(DTransformation, Rect)>,
    ev: &mut impl Evaluator,
    cfg: SampleConfig,
    rng: &mut Xoshiro256PlusPlus,
) -> Option<(DTransformation, Eval)> {
    let kind = prob.kind_of(inst);
    let mut best = Best {
        n: cfg.descents.max(1),
        unique: kind.min_dim * UNIQUE_SAMPLE_RATIO,
        samples: Vec::new(),
    };
    let angles = sample_angles(kind, prob.rotation_steps);
    let cb = bin.container.outer_cd().bbox();
    let field_dt = |dt: DTransformation| {
        if kind.follows_field {
            let t = dt.translation();
            DTransformation::new(project_turn(kind, bin, dt.rotation(), t), t)
        } else {
            dt
        }
    };
    if let Some((dt, bbox)) = current {
        let e = ev.eval(dt, best.bound());
        best.report(dt, e);
        if let Some(s) = Sampler::new(bbox, kind, bin, &angles) {
            for _ in 0..cfg.focused {
                let dt = field_dt(s.sample(rng));
                let e = ev.eval(dt, best.bound());
                best.report(dt, e);
            }
        }
    }
    if let Some(s) = Sampler::new(cb, kind, bin, &angles) {
        for _ in 0..cfg.container {
            let dt = field_dt(s.sample(rng));
            let e = ev.eval(dt, best.bound());
            best.report(dt, e);
        }
    }
    let starts = best.samples.clone();
    for s in starts {
        if s.1 == Eval::Invalid {
            continue;
        }
        let d = descend(s, kind, bin, ev, CD_COARSE, rng);
        best.report(d.0, d.1);
    }
    let top = best.samples.first().copied()?;
    if top.1 == Eval::Invalid {
        return None;
    }
    Some(descend(top, kind, bin, ev, CD_FINE, rng))
}
