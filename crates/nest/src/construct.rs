//! The first feasible layout: pieces largest first, each at the feasible sample of best
//! left-bottom score (sampled over the container, then refined), as sparrow builds its start.

use crate::evaluate::{Eval, FillEval};
use crate::problem::Problem;
use crate::search::{SampleConfig, project_turn, search};
use crate::state::State;
use jagua_rs::geometry::DTransformation;
use jagua_rs::geometry::Transformation;
use jagua_rs::geometry::geo_traits::TransformableFrom;
use rand::rngs::Xoshiro256PlusPlus;

/// Container-wide samples per piece relative to the separation's (sparrow: 1000 against 50).
const FILL_SAMPLE_FACTOR: usize = 20;

pub(crate) fn fill_config(prob: &Problem) -> SampleConfig {
    SampleConfig {
        container: prob.samples * FILL_SAMPLE_FACTOR,
        focused: 0,
        descents: 3,
    }
}

/// Tries to place `inst` feasibly in `st`; returns whether it was placed. With `quick` (the
/// budget is gone) only the cheap right-of-everything position is tried.
pub(crate) fn try_fill(
    prob: &Problem,
    st: &mut State,
    inst: usize,
    quick: bool,
    rng: &mut Xoshiro256PlusPlus,
) -> bool {
    if !quick {
        let found = {
            let mut ev = FillEval::new(&st.layout, prob.kind_of(inst));
            let bin = st.bin.clone();
            search(prob, &bin, inst, None, &mut ev, fill_config(prob), rng)
        };
        if let Some((dt, Eval::Clear(_))) = found {
            st.put(prob, inst, dt);
            return true;
        }
    }
    match right_of_everything(prob, st, inst) {
        Some(dt) => {
            st.put(prob, inst, dt);
            true
        }
        None => false,
    }
}

/// A feasible place right of every placed piece, if the container is long enough: the
/// fallback that keeps the construction bounded.
fn right_of_everything(prob: &Problem, st: &State, inst: usize) -> Option<DTransformation> {
    let kind = prob.kind_of(inst);
    let cb = st.bin.container.outer_cd().bbox();
    let x0 = st.x_extent().max(cb.x_min);
    let base = kind.jitem.shape_cd();
    let mut buf = base.as_ref().clone();
    let mut ev = FillEval::new(&st.layout, kind);
    for a in kind.turns.sample_angles(4) {
        let b = buf
            .transform_from(base, &Transformation::from_rotation(a))
            .bbox();
        let tx = x0 - b.x_min + 1e-3 * b.width().max(b.height());
        for frac in [0.0f32, 1.0, 0.5] {
            let ty0 = cb.y_min - b.y_min;
            let ty1 = cb.y_max - b.y_max;
            if ty1 < ty0 {
                continue;
            }
            let ty = ty0 + (ty1 - ty0) * frac;
            let a = project_turn(kind, &st.bin, a, (tx, ty));
            let dt = DTransformation::new(a, (tx, ty));
            if matches!(
                crate::evaluate::Evaluator::eval(&mut ev, dt, Eval::Invalid),
                Eval::Clear(_)
            ) {
                return Some(dt);
            }
        }
    }
    None
}
