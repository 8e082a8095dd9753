//! The split's time limit bounds the whole split: cutting, merging and the joint solve of the
//! parts. A surface whose split takes far longer than the limit returns within it (and the
//! stated margin), its result flagged as cut short, its parts disks that tile the surface and
//! sewn along seams whose two sides are equally long, or, where no joint solve finished in the
//! time, flagged as such.
//!
//! Alone in its file: the limit counts the CPU time of the whole process
//! ([`flatcut_darts::clock`]), which tests running beside it would spend too.

use std::time::Duration;

use flatcut_darts::clock::CpuClock;
use flatcut_darts::limits::Band;
use flatcut_darts::split::{SplitOptions, split_surface};
use flatcut_flatten::{FlattenParams, Method};
use flatcut_mesh::check_disk;
use flatcut_mesh::test_shapes::torus;

/// The time limit of the test, and what the split may take beyond it: the Newton step, or the
/// candidate cut being judged, when it runs out, and the checks after.
const LIMIT: Duration = Duration::from_millis(500);
const MARGIN: Duration = Duration::from_millis(1500);

#[test]
fn a_split_ends_within_its_time_limit_and_says_it_was_cut_short() {
    // A fat ring of 9,216 faces: at ±10 % its split takes several times the limit.
    let mesh = torus(50.0, 25.0, 96, 48);
    let opts = SplitOptions {
        band: Band::from_pct(Some(10.0), Some(10.0)),
        max_pieces: 16,
        keep_out: None,
        visibility: Default::default(),
        time_limit: Some(LIMIT),
        seam_allowance_mm: 0.0,
    };
    let clock = CpuClock::start();
    let s = split_surface(&mesh, &FlattenParams::new(Method::Isometric), &opts).unwrap();
    let spent = clock.elapsed();
    eprintln!(
        "torus at a {LIMIT:?} limit: {spent:?} CPU, {} parts, excess {:.4}, timed out {}, seams apart {}",
        s.pieces.len(),
        s.excess,
        s.timed_out,
        s.seams_apart
    );
    assert!(
        spent <= LIMIT + MARGIN,
        "the split took {spent:?} of CPU time for a limit of {LIMIT:?}"
    );
    assert!(s.timed_out);
    let mut area = 0.0;
    for (k, p) in s.pieces.iter().enumerate() {
        check_disk(p).unwrap_or_else(|e| panic!("part {k}: {e}"));
        assert_eq!(p.flat.as_ref().map(Vec::len), Some(p.positions.len()));
        area += p.area();
    }
    assert!(
        (area - mesh.area()).abs() < 1e-5 * mesh.area(),
        "{area} mm² of parts, {} mm² of surface",
        mesh.area()
    );
    // The seams' sides equally long, edge by edge, in the split returned, unless it says no
    // joint solve held them in the time.
    if s.seams_apart {
        return;
    }
    for seam in &s.seams {
        let [a, b] = &seam.sides;
        let (xa, xb) = (
            s.pieces[a.piece].flat.as_deref().unwrap(),
            s.pieces[b.piece].flat.as_deref().unwrap(),
        );
        let pa = &s.pieces[a.piece].positions;
        for k in 1..a.vertices.len() {
            let (a0, a1) = (a.vertices[k - 1] as usize, a.vertices[k] as usize);
            let (b0, b1) = (b.vertices[k - 1] as usize, b.vertices[k] as usize);
            let la = xa[a0].distance(xa[a1]);
            let lb = xb[b0].distance(xb[b1]);
            assert!(
                (la - lb).abs() <= 1e-5 * pa[a0].distance(pa[a1]),
                "seam {}: edge {k} {la} vs {lb}",
                seam.name
            );
        }
    }
}
