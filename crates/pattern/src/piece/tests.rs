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

/// The flat outline of a part of a split ball (±5 %), to 0.1 µm: simple, but at the tip of its
/// lens three seams meet in a zigzag of 0.7 mm edges, and the curves fitted within the 0.1 mm
/// tolerance there crossed each other ("outline is self-intersecting", edges 54 and 56).
const SPLIT_BALL_PART: [[f64; 2]; 54] = [
    [50.7780, 32.0290],
    [40.2338, 33.4453],
    [32.0604, 34.3815],
    [23.5694, 35.2819],
    [1.4537, 36.1234],
    [-3.0024, 37.3953],
    [-21.3339, 35.4402],
    [-29.2753, 34.9303],
    [-41.9532, 33.8093],
    [-56.7515, 31.6660],
    [-62.4725, 31.1200],
    [-83.1528, 26.0341],
    [-87.9785, 24.8343],
    [-101.6260, 21.2523],
    [-107.4177, 19.5403],
    [-120.8070, 14.2912],
    [-132.3205, 10.5038],
    [-139.3950, 8.4898],
    [-151.2199, 3.7552],
    [-157.3790, 1.4441],
    [-155.0518, 0.4679],
    [-145.0193, -3.8876],
    [-127.3855, -10.8625],
    [-117.7627, -13.9095],
    [-98.4751, -21.0210],
    [-78.7140, -26.3056],
    [-67.8714, -27.9570],
    [-38.1388, -34.1792],
    [-37.6357, -35.3496],
    [-31.4682, -36.0093],
    [-7.6424, -37.9285],
    [-1.5221, -38.2789],
    [5.3441, -38.2079],
    [19.5719, -37.6945],
    [37.4462, -36.3325],
    [48.0700, -34.7502],
    [76.5466, -29.4061],
    [90.1398, -24.8251],
    [103.6229, -20.0169],
    [115.1803, -15.7883],
    [129.8912, -9.4774],
    [150.6026, 0.1158],
    [153.8149, 1.7588],
    [151.5136, 2.7933],
    [151.7351, 3.4410],
    [137.6123, 9.1713],
    [126.5282, 12.7869],
    [119.0101, 15.2414],
    [110.2712, 17.8409],
    [99.7811, 20.5115],
    [84.7439, 24.7684],
    [80.3478, 26.0330],
    [72.1207, 28.0175],
    [60.7056, 30.2655],
];

#[test]
fn a_simple_outline_gets_a_simple_sew_line_where_fitted_curves_would_cross() {
    let outline: Vec<DVec2> = SPLIT_BALL_PART
        .iter()
        .map(|p| DVec2::from_array(*p))
        .collect();
    assert!(poly::first_self_intersection(&outline).is_none());
    let opts = PieceOptions {
        default_seam: 0.0,
        ..PieceOptions::default()
    };
    let p = Piece::build(&PieceInput::new("ball-5", outline.clone()), &opts).unwrap();
    assert!(poly::first_self_intersection(&p.sew_polyline).is_none());
    // The sew line passes through every point of the outline.
    for q in &outline {
        assert!(
            poly::dist_to_closed(&p.sew_polyline, *q) < 1e-6,
            "{q} is off the sew line"
        );
    }
}
