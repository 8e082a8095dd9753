//! The fewest parts a set of neighbouring parts can be sewn back into, each group's union lying
//! within the limits, and among those the shortest seams: the search behind the merging of
//! [`crate::split`].
//!
//! Merging the pairs that share the longest seams first, round by round, can pair the parts so
//! that no two of the resulting parts merge, where another grouping would: the four parts of the
//! 13,520-face plush body came back as three where two lie within ±10 %. A group of parts is
//! *within* when its union, flattened alone with the limits held, lies within them (a judgement
//! that costs a flattening); *beyond* when it does not. Beyond is inherited upwards: a union that
//! holds a group beyond the limits is beyond them too (a flat map of the larger union, restricted
//! to the group, would be a map of the group within them), so no group holding one is judged. A
//! union refused for another reason (not one disk, a neck too narrow to sew) says nothing about
//! the groups holding it, and is `Unfit`.
//!
//! The search, for up to [`FEWEST_EXACT`] parts (a bit each): the best grouping of the groups
//! known within (fewest parts, then the longest seams sewn inside the groups, by dynamic
//! programming over the sets of parts) is compared with the best grouping of every group that
//! may still be within (connected, not holding a group beyond, not judged). While the second is
//! better, its groups not yet judged are judged, side by side: each as the merge of two groups
//! known within (the pair sharing the longest seam), or where it has no such pair, the groups one
//! part smaller inside it first. A group that cannot be built so is `Unfit`. Every judgement
//! either confirms a group of the optimistic grouping or rules it (and every group holding it)
//! out, so the search ends, with the best grouping there is, after judging only the groups that
//! could have beaten the one at hand. The judgements made before (by the greedy rounds) are
//! reused, and the search stops where the caller's time is out, with the best grouping known.

use rayon::prelude::*;
use std::collections::BTreeMap;

/// The most parts the search takes on (a part is a bit of a `u32`, and the groupings of `n`
/// parts are compared over all `2^n` sets, `3^n` steps).
pub const FEWEST_EXACT: usize = 12;

/// How much longer (mm) the seams sewn inside the groups of a grouping must be for it to count as
/// better than one with as many parts: less is rounding.
pub const SEAM_GAIN_MM: f64 = 1e-6;

/// The judgement of a union of parts.
#[derive(Clone, Debug)]
pub enum Verdict<T> {
    /// Within the limits, as this part (flattened).
    Within(T),
    /// Beyond the limits, or overlapping itself flat: so is every union holding it.
    Beyond,
    /// Refused for what a larger union may not share (not one disk, a narrow neck).
    Unfit,
}

/// The parts and what is known of their unions.
pub struct Parts<'a, T> {
    /// The parts, each within the limits.
    pub parts: &'a [T],
    /// The seam length (mm) shared by each pair of parts `(i, j)`, `i < j`; pairs not listed
    /// are not neighbours.
    pub shared: &'a BTreeMap<(usize, usize), f64>,
    /// The unions judged so far, by their parts (ascending).
    pub judged: &'a BTreeMap<Vec<usize>, Verdict<T>>,
}

/// The outcome of the search: the groups (each its parts, ascending; the groups in the order of
/// their first part), the judgements made (to keep), and whether it was cut short by the time.
pub struct Fewest<T> {
    /// The groups of the best grouping.
    pub groups: Vec<Vec<usize>>,
    /// The unions the search judged, by their parts.
    pub judged: Vec<(Vec<usize>, Verdict<T>)>,
    /// Whether the time ran out before the search ended.
    pub cut_short: bool,
}

/// The state of a set of parts in the search.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum State {
    Unknown,
    Within,
    Beyond,
    Unfit,
}

/// The grouping of `parts` with the fewest groups, then the longest seams inside the groups,
/// each group's union within the limits, by the search of the module documentation: `judge`
/// sews two groups' unions into one and judges it; `out_of_time` stops the search. `None` when
/// there are more than [`FEWEST_EXACT`] parts.
pub fn fewest<T: Clone + Send + Sync>(
    p: &Parts<T>,
    judge: &(dyn Fn(&T, &T) -> Verdict<T> + Sync),
    out_of_time: &(dyn Fn() -> bool + Sync),
) -> Option<Fewest<T>> {
    let n = p.parts.len();
    if n == 0 || n > FEWEST_EXACT {
        return None;
    }
    let full = 1usize << n;
    let mut adj = vec![0u32; n];
    let mut w = vec![vec![0.0; n]; n];
    for (&(i, j), &l) in p.shared {
        if i < n && j < n && i != j {
            adj[i] |= 1 << j;
            adj[j] |= 1 << i;
            w[i][j] = l;
            w[j][i] = l;
        }
    }
    // The seam length inside every set of parts.
    let mut inside = vec![0.0; full];
    for m in 1..full {
        let i = m.trailing_zeros() as usize;
        let rest = m & (m - 1);
        inside[m] = inside[rest] + bits(rest as u32).map(|j| w[i][j]).sum::<f64>();
    }
    let connected: Vec<bool> = (0..full).map(|m| is_connected(m as u32, &adj)).collect();
    let mut state = vec![State::Unknown; full];
    let mut unions: BTreeMap<u32, T> = BTreeMap::new();
    for (i, part) in p.parts.iter().enumerate() {
        state[1 << i] = State::Within;
        unions.insert(1 << i, part.clone());
    }
    for (key, v) in p.judged {
        let Some(m) = mask_of(key, n) else { continue };
        set(&mut state, &mut unions, m, v.clone());
    }
    let mut made = Vec::new();
    let mut cut_short = false;
    loop {
        let best = grouping(n, &inside, |m| state[m as usize] == State::Within)
            .expect("the parts alone are a grouping");
        if out_of_time() {
            cut_short = true;
            return Some(outcome(best, made, cut_short));
        }
        // Every set holding a set beyond the limits.
        let mut doomed = vec![false; full];
        for m in 1..full {
            doomed[m] = state[m] == State::Beyond || bits(m as u32).any(|i| doomed[m & !(1 << i)]);
        }
        let may = |m: u32| {
            let m = m as usize;
            connected[m] && !doomed[m] && state[m] != State::Unfit
        };
        let hope = grouping(n, &inside, may).expect("the parts alone are a grouping");
        if !better(&hope, &best) {
            return Some(outcome(best, made, cut_short));
        }
        // The groups to judge: those of the hoped-for grouping not judged, or the groups inside
        // them that can be built first.
        let mut batch: Vec<(u32, (u32, u32))> = Vec::new();
        let mut seen = vec![None; full];
        let mut unbuilt = Vec::new();
        for &g in &hope.groups {
            if state[g as usize] == State::Unknown
                && !to_judge(g, &state, &adj, &w, &may, &mut seen, &mut batch)
            {
                unbuilt.push(g);
            }
        }
        // No way to build these from groups within the limits.
        for g in unbuilt {
            state[g as usize] = State::Unfit;
        }
        let verdicts: Vec<Option<Verdict<T>>> = batch
            .par_iter()
            .map(|&(_, (a, b))| {
                if out_of_time() {
                    return None;
                }
                Some(judge(&unions[&a], &unions[&b]))
            })
            .collect();
        for ((g, _), v) in batch.into_iter().zip(verdicts) {
            match v {
                Some(v) => {
                    made.push((parts_of(g), v.clone()));
                    set(&mut state, &mut unions, g, v);
                }
                None => cut_short = true,
            }
        }
    }
}

/// Records the verdict `v` on the set `m`.
fn set<T>(state: &mut [State], unions: &mut BTreeMap<u32, T>, m: u32, v: Verdict<T>) {
    state[m as usize] = match v {
        Verdict::Within(t) => {
            unions.insert(m, t);
            State::Within
        }
        Verdict::Beyond => State::Beyond,
        Verdict::Unfit => State::Unfit,
    };
}

/// Pushes onto `batch` the set `g` (not judged) with the two groups within the limits it is
/// built from, or where it has none, the sets one part smaller inside it that may be within
/// (recursively); each set once (`seen`, with whether it led to a set to judge). Whether `g`
/// led to one.
fn to_judge(
    g: u32,
    state: &[State],
    adj: &[u32],
    w: &[Vec<f64>],
    may: &dyn Fn(u32) -> bool,
    seen: &mut [Option<bool>],
    batch: &mut Vec<(u32, (u32, u32))>,
) -> bool {
    if let Some(led) = seen[g as usize] {
        return led;
    }
    if state[g as usize] != State::Unknown {
        return false;
    }
    let led = match build(g, state, adj, w) {
        Some(ab) => {
            batch.push((g, ab));
            true
        }
        None => {
            let mut led = false;
            for i in bits(g) {
                let s = g & !(1 << i);
                if s != 0 && may(s) {
                    led |= to_judge(s, state, adj, w, may, seen, batch);
                }
            }
            led
        }
    };
    seen[g as usize] = Some(led);
    led
}

/// The two groups within the limits, neighbours, that make up `g` and share the longest seam
/// (the first such pair in the order of the sets on a tie).
fn build(g: u32, state: &[State], adj: &[u32], w: &[Vec<f64>]) -> Option<(u32, u32)> {
    let low = g & g.wrapping_neg();
    let rest = g ^ low;
    let mut best: Option<((u32, u32), f64)> = None;
    // Every split of g into a (holding its lowest part) and b.
    let mut sub = rest;
    loop {
        let a = sub | low;
        let b = g ^ a;
        if b != 0
            && state[a as usize] == State::Within
            && state[b as usize] == State::Within
            && bits(a).any(|i| adj[i] & b != 0)
        {
            let l: f64 = bits(a)
                .flat_map(|i| bits(b).map(move |j| (i, j)))
                .map(|(i, j)| w[i][j])
                .sum();
            if best.is_none_or(|(_, bl)| l > bl) {
                best = Some(((a, b), l));
            }
        }
        if sub == 0 {
            break;
        }
        sub = (sub - 1) & rest;
    }
    best.map(|(ab, _)| ab)
}

/// A grouping: its groups (sets of parts) and the seam length inside them.
struct Grouping {
    groups: Vec<u32>,
    inside: f64,
}

/// Whether `a` has fewer groups than `b`, or as many and longer seams inside them (by more than
/// [`SEAM_GAIN_MM`]).
fn better(a: &Grouping, b: &Grouping) -> bool {
    a.groups.len() < b.groups.len()
        || (a.groups.len() == b.groups.len() && a.inside > b.inside + SEAM_GAIN_MM)
}

/// The grouping of all `n` parts into sets that are `ok`, with the fewest groups, then the most
/// seam length `inside` them (on a tie, the first found: the sets holding the lowest part
/// tried in descending order of their bits); `None` when there is none.
fn grouping(n: usize, inside: &[f64], ok: impl Fn(u32) -> bool) -> Option<Grouping> {
    let full = 1usize << n;
    // For every set, its best (groups, seam inside, the group holding its lowest part).
    let mut best: Vec<Option<(usize, f64, u32)>> = vec![None; full];
    best[0] = Some((0, 0.0, 0));
    for m in 1..full {
        let m32 = m as u32;
        let low = m32 & m32.wrapping_neg();
        let rest = m32 ^ low;
        let mut here: Option<(usize, f64, u32)> = None;
        let mut sub = rest;
        loop {
            let g = sub | low;
            if ok(g)
                && let Some((c, s, _)) = best[(m32 ^ g) as usize]
            {
                let cand = (c + 1, s + inside[g as usize], g);
                if here.is_none_or(|(hc, hs, _)| cand.0 < hc || (cand.0 == hc && cand.1 > hs)) {
                    here = Some(cand);
                }
            }
            if sub == 0 {
                break;
            }
            sub = (sub - 1) & rest;
        }
        best[m] = here;
    }
    let (_, total, _) = best[full - 1]?;
    let mut groups = Vec::new();
    let mut m = (full - 1) as u32;
    while m != 0 {
        let (_, _, g) = best[m as usize]?;
        groups.push(g);
        m ^= g;
    }
    Some(Grouping {
        groups,
        inside: total,
    })
}

/// The outcome from the best grouping found.
fn outcome<T>(best: Grouping, judged: Vec<(Vec<usize>, Verdict<T>)>, cut_short: bool) -> Fewest<T> {
    let mut groups: Vec<Vec<usize>> = best.groups.into_iter().map(parts_of).collect();
    groups.sort();
    Fewest {
        groups,
        judged,
        cut_short,
    }
}

/// Whether the set `m` is connected through `adj`.
fn is_connected(m: u32, adj: &[u32]) -> bool {
    if m == 0 {
        return false;
    }
    let mut reached = m & m.wrapping_neg();
    loop {
        let more = bits(reached).fold(reached, |r, i| r | (adj[i] & m));
        if more == reached {
            return reached == m;
        }
        reached = more;
    }
}

/// The set of the parts `key`, `None` when one is not below `n`.
fn mask_of(key: &[usize], n: usize) -> Option<u32> {
    key.iter()
        .try_fold(0u32, |m, &i| (i < n).then(|| m | (1 << i)))
}

/// The parts of the set `m`, ascending.
fn parts_of(m: u32) -> Vec<usize> {
    bits(m).collect()
}

/// The bits set in `m`, ascending.
fn bits(m: u32) -> impl Iterator<Item = usize> {
    (0..32).filter(move |&i| m & (1 << i) != 0)
}
