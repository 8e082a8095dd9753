//! The search for the fewest parts ([`flatcut_darts::fewest`]) on parts whose unions are judged by
//! a rule: each part is the set of the parts it is made of, a union within the limits where the
//! rule says so. The first case is the one the greedy rounds get wrong (the plush body's four
//! parts: the pair sharing the longest seam merged first, and nothing merged after).

use std::collections::BTreeMap;
use std::sync::Mutex;

use flatcut_darts::fewest::{Fewest, Parts, Verdict, fewest};

/// A part: the parts it is made of, ascending.
type Set = Vec<usize>;

/// Runs the search on `n` parts with the seams `shared` and the judgements `judged`, a union
/// within the limits where it is one of `within` (beyond them otherwise, or `unfit` where
/// listed there); returns the outcome and the unions judged, in the order judged.
fn search(
    n: usize,
    shared: &[((usize, usize), f64)],
    judged: &[(Set, Verdict<Set>)],
    within: &[Set],
    unfit: &[Set],
    out_of_time: &(dyn Fn() -> bool + Sync),
) -> (Fewest<Set>, Vec<Set>) {
    let parts: Vec<Set> = (0..n).map(|k| vec![k]).collect();
    let shared: BTreeMap<(usize, usize), f64> = shared.iter().copied().collect();
    let judged: BTreeMap<Set, Verdict<Set>> = judged.iter().cloned().collect();
    let calls = Mutex::new(Vec::new());
    let judge = |a: &Set, b: &Set| {
        let mut u = [a.as_slice(), b.as_slice()].concat();
        u.sort_unstable();
        calls.lock().unwrap().push(u.clone());
        if within.contains(&u) {
            Verdict::Within(u)
        } else if unfit.contains(&u) {
            Verdict::Unfit
        } else {
            Verdict::Beyond
        }
    };
    let p = Parts {
        parts: &parts,
        shared: &shared,
        judged: &judged,
    };
    let f = fewest(&p, &judge, out_of_time).expect("few enough parts");
    let mut calls = calls.into_inner().unwrap();
    calls.sort();
    (f, calls)
}

/// The seams of four parts in a row, 2 – 0 – 1 – 3, the seam 0–1 the longest; what the greedy
/// rounds judged of them (0 and 1 merged, neither 2 nor 3 joining them); and the unions within
/// the limits.
fn row_of_four() -> (
    [((usize, usize), f64); 3],
    [(Set, Verdict<Set>); 3],
    [Set; 3],
) {
    (
        [((0, 1), 30.0), ((0, 2), 20.0), ((1, 3), 20.0)],
        [
            (vec![0, 1], Verdict::Within(vec![0, 1])),
            (vec![0, 1, 2], Verdict::Beyond),
            (vec![0, 1, 3], Verdict::Beyond),
        ],
        [vec![0, 1], vec![0, 2], vec![1, 3]],
    )
}

/// Four parts in a row, 2 – 0 – 1 – 3, the seam 0–1 the longest: the greedy rounds merge 0 and
/// 1, and neither 2 nor 3 joins them (nor are 2 and 3 neighbours), three parts; 0 with 2 and 1
/// with 3 lie within the limits, two parts. The unions holding one found beyond (0, 1, 2 and 0,
/// 1, 3) are never judged again, nor is the whole.
#[test]
fn a_grouping_the_longest_seams_first_miss_is_found() {
    let (shared, judged, within) = row_of_four();
    let (f, calls) = search(4, &shared, &judged, &within, &[], &|| false);
    assert_eq!(f.groups, vec![vec![0, 2], vec![1, 3]]);
    assert!(!f.cut_short);
    assert_eq!(calls, vec![vec![0, 2], vec![1, 3]]);
    assert_eq!(f.judged.len(), 2);
}

/// A ring of four parts, every pair of neighbours within the limits and no three: two parts
/// either way round, and the grouping chosen sews the two long seams inside its parts (the
/// seams left 2 × 10 mm, not 2 × 30 mm).
#[test]
fn among_as_few_parts_the_shortest_seams_are_chosen() {
    let shared = [
        ((0, 1), 10.0),
        ((1, 2), 30.0),
        ((2, 3), 10.0),
        ((0, 3), 30.0),
    ];
    let within = [vec![0, 1], vec![1, 2], vec![2, 3], vec![0, 3]];
    let (f, _) = search(4, &shared, &[], &within, &[], &|| false);
    assert_eq!(f.groups, vec![vec![0, 3], vec![1, 2]]);
}

/// A union refused for its shape (a neck, not one disk) does not rule out the unions holding
/// it: 0 and 1 make a part of two lobes on a waist, and with 2 a piece within the limits.
#[test]
fn a_union_refused_for_its_shape_does_not_rule_out_a_larger_one() {
    let shared = [((0, 1), 5.0), ((1, 2), 20.0), ((0, 2), 20.0)];
    let within = [vec![1, 2], vec![0, 2], vec![0, 1, 2]];
    let (f, calls) = search(3, &shared, &[], &within, &[vec![0, 1]], &|| false);
    assert_eq!(f.groups, vec![vec![0, 1, 2]]);
    assert!(calls.contains(&vec![0, 1, 2]));
}

/// Where every union is beyond the limits, the parts stay as they are, each pair judged once
/// and no larger union judged.
#[test]
fn parts_no_pair_of_which_merges_stay_apart() {
    let shared = [((0, 1), 10.0), ((1, 2), 10.0), ((0, 2), 10.0)];
    let (f, calls) = search(3, &shared, &[], &[], &[], &|| false);
    assert_eq!(f.groups, vec![vec![0], vec![1], vec![2]]);
    assert_eq!(calls, vec![vec![0, 1], vec![0, 2], vec![1, 2]]);
}

/// Out of time, the search judges nothing more and returns the best grouping known (the
/// greedy rounds' three parts), saying it was cut short.
#[test]
fn out_of_time_the_best_grouping_known_is_the_result_and_says_so() {
    let (shared, judged, within) = row_of_four();
    let (f, calls) = search(4, &shared, &judged, &within, &[], &|| true);
    assert!(f.cut_short);
    assert!(calls.is_empty());
    assert_eq!(f.groups, vec![vec![0, 1], vec![2], vec![3]]);
}

/// More parts than the search takes on: no result (the greedy rounds' grouping stands).
#[test]
fn too_many_parts_are_left_to_the_rounds() {
    let n = flatcut_darts::fewest::FEWEST_EXACT + 1;
    let shared: Vec<((usize, usize), f64)> = (1..n).map(|k| ((k - 1, k), 10.0)).collect();
    let parts: Vec<Set> = (0..n).map(|k| vec![k]).collect();
    let shared: BTreeMap<(usize, usize), f64> = shared.into_iter().collect();
    let judged = BTreeMap::new();
    let p = Parts {
        parts: &parts,
        shared: &shared,
        judged: &judged,
    };
    let judge = |_: &Set, _: &Set| -> Verdict<Set> { panic!("nothing is judged") };
    assert!(fewest(&p, &judge, &|| false).is_none());
}
