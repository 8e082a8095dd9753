//! Tests of piece building: allowance, notches, labels, widths, errors, placement.

use super::*;
use crate::drawing::Layer;

fn rect(w: f64, h: f64, per_side: usize) -> Vec<DVec2> {
    let c = [
        DVec2::ZERO,
        DVec2::new(w, 0.),
        DVec2::new(w, h),
        DVec2::new(0., h),
    ];
    (0..4)
        .flat_map(|k| {
            (0..per_side).map(move |j| c[k].lerp(c[(k + 1) % 4], j as f64 / per_side as f64))
        })
        .collect()
}

#[test]
fn stitch_lines_are_drawn_as_polylines_and_checked() {
    let mut input = PieceInput::new("quarter", rect(200., 100., 20));
    let stitch = vec![
        DVec2::new(10., 10.),
        DVec2::new(100., 12.),
        DVec2::new(100., 12.), // repeated point: dropped
        DVec2::new(190., 10.),
    ];
    input.lines.push(stitch);
    let p = Piece::build(&input, &PieceOptions::default()).unwrap();
    assert_eq!(
        p.lines,
        vec![vec![
            DVec2::new(10., 10.),
            DVec2::new(100., 12.),
            DVec2::new(190., 10.)
        ]]
    );
    let d = p.to_drawing(1);
    let line: Vec<_> = d
        .strokes
        .iter()
        .filter(|s| s.id == "quarter-1-line-1")
        .collect();
    assert_eq!(line.len(), 1);
    assert_eq!(line[0].layer, Layer::Draw);
    assert!(!line[0].closed && line[0].points.len() == 3);
    // a straight line sampled densely keeps only its ends
    let mut straight = input.clone();
    straight.lines[0] = (0..=50)
        .map(|k| DVec2::new(10. + 3.0 * k as f64, 50.))
        .collect();
    let q = Piece::build(&straight, &PieceOptions::default()).unwrap();
    assert_eq!(
        q.lines[0],
        vec![DVec2::new(10., 50.), DVec2::new(160., 50.)]
    );
    // within the allowance is fine (a topstitch on the seam); beyond the cut line is not
    input.lines[0].push(DVec2::new(205., 10.));
    assert!(Piece::build(&input, &PieceOptions::default()).is_ok());
    input.lines[0].push(DVec2::new(260., 10.));
    let e = Piece::build(&input, &PieceOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("quarter") && e.contains("internal line 1 leaves the piece"),
        "{e}"
    );
    input.lines[0] = vec![DVec2::new(10., 10.), DVec2::new(f64::NAN, 1.)];
    let e = Piece::build(&input, &PieceOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("internal line 1"), "{e}");
    input.lines[0] = vec![DVec2::new(10., 10.)];
    let e = Piece::build(&input, &PieceOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("fewer than two"), "{e}");
}

#[test]
fn rectangle_piece_has_allowance_notches_label() {
    let mut input = PieceInput::new("vamp", rect(200., 100., 20));
    input.marks.push(Mark {
        kind: MarkKind::Notch,
        pos: DVec2::new(100., 0.),
        boundary_index: None,
    });
    input.marks.push(Mark {
        kind: MarkKind::Drill,
        pos: DVec2::new(50., 50.),
        boundary_index: None,
    });
    input.grain = Some((DVec2::new(20., 20.), DVec2::new(180., 20.)));
    input.label.size = "42".into();
    let p = Piece::build(&input, &PieceOptions::default()).unwrap();
    // four straight seams, the bottom one split at the notch (marks are kept as corners)
    assert_eq!(p.sew.len(), 5, "{:?}", p.sew);
    assert!(p.sew.iter().all(|s| matches!(s, PathSeg::Line { .. })));
    assert!(p.sew.iter().any(|s| s.end() == DVec2::new(100., 0.)));
    assert!((p.cut_area() - 220.0 * 120.0).abs() < 1e-6);
    assert_eq!(p.notches.len(), 1);
    let nt = &p.notches[0];
    assert!(nt[0].distance(DVec2::new(100., -10.)) < 1e-6, "{:?}", nt);
    assert!(nt[1].distance(DVec2::new(100., -6.)) < 1e-6);
    assert!(!p.label_strokes.is_empty());
    let d = p.to_drawing(1);
    assert!(
        d.strokes
            .iter()
            .any(|s| s.id == "vamp-1-cut" && s.is_outer())
    );
    assert!(d.strokes.iter().any(|s| s.id == "vamp-1-notch-1"));
    // label inside the sew line
    for st in &p.label_strokes {
        for q in st {
            assert!(poly::contains(&p.sew_polyline, *q));
        }
    }
}

/// A named stretch from `from` to `to` (outline vertices) of `kind` and `width`.
fn edge(name: &str, kind: EdgeKind, width: Option<f64>, from: usize, to: usize) -> EdgeAllowance {
    EdgeAllowance {
        name: name.into(),
        kind,
        width,
        from,
        to,
    }
}

#[test]
fn named_edges_carry_their_allowance_and_the_rest_the_default() {
    // vertices 0 and 20 are the bottom corners: the bottom cut raw, the rest 15 mm
    let mut input = PieceInput::new("front", rect(200., 100., 20));
    input.edges.push(edge("fold", EdgeKind::Raw, None, 0, 20));
    let opts = PieceOptions::default().with_default_seam(15.0);
    let p = Piece::build(&input, &opts).unwrap();
    let bb = p.bbox();
    assert!((bb.min.y - 0.0).abs() < 1e-9 && (bb.max.y - 115.0).abs() < 1e-9);
    assert!((bb.min.x + 15.0).abs() < 1e-9 && (bb.max.x - 215.0).abs() < 1e-9);
    // two runs: the raw bottom (named) and the default seam round the rest
    assert_eq!(p.edges.len(), 2, "{:?}", p.edges);
    assert_eq!((p.edges[0].name.as_str(), p.edges[0].width), ("fold", 0.0));
    assert_eq!((p.edges[1].name.as_str(), p.edges[1].width), ("", 15.0));
    let len = |e: &PieceEdge| e.sew.windows(2).map(|w| w[0].distance(w[1])).sum::<f64>();
    assert!((len(&p.edges[0]) - 200.0).abs() < 1e-9);
    assert!((len(&p.edges[1]) - 400.0).abs() < 1e-9);
}

#[test]
fn a_lasting_margin_is_written_lasting_inside_it() {
    let mut input = PieceInput::new("quarter", rect(200., 100., 20));
    input
        .edges
        .push(edge("featherline", EdgeKind::Lasting, Some(16.0), 0, 20));
    let p = Piece::build(&input, &PieceOptions::default().with_default_seam(8.0)).unwrap();
    assert!(!p.edge_labels.is_empty());
    // upright, in the margin below the bottom edge, at least the readable height
    let (lo, hi) = p.edge_labels.iter().flatten().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), q| (lo.min(*q), hi.max(*q)),
    );
    assert!(lo.y > -16.0 && hi.y < 0.0, "{lo} {hi}");
    assert!(hi.y - lo.y >= MIN_LABEL_HEIGHT, "{lo} {hi}");
    assert!(
        hi.x - lo.x > 3.0 * (hi.y - lo.y),
        "written along the edge: {lo} {hi}"
    );
    let d = p.to_drawing(1);
    assert!(
        d.strokes
            .iter()
            .any(|s| s.id == "quarter-1-label-lasting-1" && s.kind == crate::StrokeKind::Text)
    );
}

#[test]
fn overlapping_or_misplaced_edges_are_refused_naming_them() {
    let mut input = PieceInput::new("front", rect(200., 100., 20));
    input
        .edges
        .push(edge("hem", EdgeKind::Hem, Some(30.0), 0, 20));
    input
        .edges
        .push(edge("side", EdgeKind::Seam, Some(10.0), 10, 40));
    let e = Piece::build(&input, &PieceOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("front") && e.contains("'hem' and 'side' overlap"),
        "{e}"
    );
    input.edges[1] = edge("side", EdgeKind::Seam, Some(10.0), 20, 99);
    let e = Piece::build(&input, &PieceOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("edge 'side'") && e.contains("vertex 99"), "{e}");
}

#[test]
fn a_notch_on_a_raw_edge_is_a_nick() {
    let mut input = PieceInput::new("vamp", rect(200., 100., 20));
    input.edges.push(edge("lap", EdgeKind::Raw, None, 0, 20));
    input.marks.push(Mark {
        kind: MarkKind::Notch,
        pos: DVec2::new(100., 0.),
        boundary_index: None,
    });
    let p = Piece::build(&input, &PieceOptions::default()).unwrap();
    let nt = &p.notches[0];
    assert!(nt[0].distance(DVec2::new(100., 0.)) < 1e-6, "{nt:?}");
    assert!((nt[0].distance(nt[1]) - 1.0).abs() < 1e-6, "{nt:?}");
}

#[test]
fn self_intersecting_outline_is_rejected_naming_the_piece() {
    let bow = vec![
        DVec2::ZERO,
        DVec2::new(50., 50.),
        DVec2::new(50., 0.),
        DVec2::new(0., 50.),
    ];
    let e = Piece::build(&PieceInput::new("quarter-L", bow), &PieceOptions::default()).unwrap_err();
    assert!(matches!(e, PatternError::SelfIntersecting { .. }));
    assert!(e.to_string().contains("quarter-L"), "{e}");
}

#[test]
fn allowance_too_large_names_the_piece() {
    let u = vec![
        DVec2::new(0., 0.),
        DVec2::new(60., 0.),
        DVec2::new(60., 80.),
        DVec2::new(32., 80.),
        DVec2::new(32., 10.),
        DVec2::new(28., 10.),
        DVec2::new(28., 80.),
        DVec2::new(0., 80.),
    ];
    let e = Piece::build(
        &PieceInput::new("tongue", u.clone()),
        &PieceOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(e, PatternError::AllowanceTooLarge { .. }), "{e}");
    assert!(e.to_string().contains("tongue"));
    let mut neg = PieceInput::new("heel", u);
    neg.edges
        .push(edge("back", EdgeKind::Seam, Some(-1.0), 0, 4));
    assert!(matches!(
        Piece::build(&neg, &PieceOptions::default()),
        Err(PatternError::AllowanceTooLarge { .. })
    ));
}

#[test]
fn non_finite_and_degenerate_input_errors() {
    let e = Piece::build(
        &PieceInput::new("a", vec![DVec2::ZERO, DVec2::new(f64::NAN, 0.), DVec2::ONE]),
        &PieceOptions::default(),
    );
    assert!(matches!(e, Err(PatternError::NonFinite { .. })));
    let e = Piece::build(
        &PieceInput::new("b", vec![DVec2::ZERO, DVec2::ONE]),
        &PieceOptions::default(),
    );
    assert!(matches!(e, Err(PatternError::DegenerateOutline { .. })));
}

#[test]
fn clockwise_input_is_accepted_and_mirror_keeps_ccw() {
    let mut r = rect(80., 40., 4);
    r.reverse();
    let p = Piece::build(&PieceInput::new("cw", r), &PieceOptions::default()).unwrap();
    assert!(p.cut_area() > 0.0);
    let pp = PlacedPiece {
        piece: &p,
        instance: 1,
        placement: Placement {
            rotation: 0.3,
            mirror: true,
            translation: DVec2::new(5., 5.),
        },
    };
    let d = pp.to_drawing();
    let cut = d.strokes.iter().find(|s| s.is_outer()).unwrap();
    assert!((poly::signed_area(&cut.points) - p.cut_area()).abs() < 1e-6);
}
