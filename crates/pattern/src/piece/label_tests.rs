//! Tests of the label: written upright, clear of the grain line and every mark, non-ASCII
//! characters drawn from the font, and readable (not mirror-written) on a mirrored placement.

use super::*;
use crate::drawing::StrokeKind;
use flatcut_font as font;

fn rect(w: f64, h: f64) -> Vec<DVec2> {
    vec![
        DVec2::ZERO,
        DVec2::new(w, 0.),
        DVec2::new(w, h),
        DVec2::new(0., h),
    ]
}

fn bbox(pts: &[DVec2]) -> (DVec2, DVec2) {
    pts.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    )
}

/// Whether the segment `a`–`b` meets the closed box `lo`–`hi` (Liang–Barsky clipping).
fn segment_meets_box(a: DVec2, b: DVec2, lo: DVec2, hi: DVec2) -> bool {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-d.x, a.x - lo.x),
        (d.x, hi.x - a.x),
        (-d.y, a.y - lo.y),
        (d.y, hi.y - a.y),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return false;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    t0 <= t1
}

/// A 300 × 140 piece with a grain line through its middle, drill holes, points and a stitch
/// line where the middle of the piece is, i.e. where a label centred on the piece would go.
fn busy_piece() -> PieceInput {
    let mut input = PieceInput::new("sleeve", rect(300., 140.));
    input.grain = Some((DVec2::new(30., 70.), DVec2::new(270., 70.)));
    for (kind, pos) in [
        (MarkKind::Drill, DVec2::new(150., 80.)),
        (MarkKind::Drill, DVec2::new(120., 60.)),
        (MarkKind::Point, DVec2::new(180., 95.)),
        (MarkKind::Point, DVec2::new(150., 40.)),
    ] {
        input.marks.push(Mark {
            kind,
            pos,
            boundary_index: None,
        });
    }
    input
        .lines
        .push(vec![DVec2::new(100., 20.), DVec2::new(100., 120.)]);
    input.label.size = "M".into();
    input.label.material = "cotton jersey".into();
    input.label.quantity = 2;
    input
}

#[test]
fn label_glyphs_clear_the_grain_line_and_every_mark() {
    let p = Piece::build(&busy_piece(), &PieceOptions::default()).unwrap();
    let d = p.to_drawing(1);
    let obstacles: Vec<Vec<DVec2>> = d
        .strokes
        .iter()
        .filter(|s| {
            matches!(
                s.kind,
                StrokeKind::Grain | StrokeKind::Drill | StrokeKind::Internal | StrokeKind::Notch
            )
        })
        .map(|s| {
            let mut pts = s.points.clone();
            if s.closed {
                pts.push(pts[0]);
            }
            pts
        })
        .collect();
    // grain (line, head, tail), two drill holes, two crosses of two arms, one stitch line
    assert_eq!(obstacles.len(), 3 + 2 + 4 + 1);
    assert!(!p.label_strokes.is_empty());
    let (mut glyph_boxes, mut text_h) = (0, 0.0f64);
    for st in &p.label_strokes {
        let (lo, hi) = bbox(st);
        text_h = text_h.max(hi.y - lo.y);
        glyph_boxes += 1;
        for o in &obstacles {
            for w in o.windows(2) {
                assert!(
                    !segment_meets_box(w[0], w[1], lo, hi),
                    "label stroke box {lo}–{hi} meets {:?}",
                    w
                );
            }
        }
        for q in st {
            assert!(poly::contains(&p.sew_polyline, *q));
        }
    }
    assert!(glyph_boxes > 20);
    // the label still reads: not shrunk to nothing by the obstacles
    assert!(text_h > 2.0, "{text_h}");
    // and a label centred on the piece would have met the grain line (the test has teeth)
    let (lo, hi) = bbox(&p.label_strokes.concat());
    let centred = (
        lo - (lo + hi) * 0.5 + DVec2::new(150., 70.),
        hi - (lo + hi) * 0.5 + DVec2::new(150., 70.),
    );
    assert!(segment_meets_box(
        DVec2::new(30., 70.),
        DVec2::new(270., 70.),
        centred.0,
        centred.1
    ));
}

#[test]
fn the_label_is_written_upright_along_plus_x() {
    let p = Piece::build(&busy_piece(), &PieceOptions::default()).unwrap();
    // the first stroke of the label is the first stroke of its first line, scaled and moved:
    // no rotation, no reflection
    let f = font::text_strokes(&p.label_lines()[0], DVec2::ZERO, 1.0, DVec2::X);
    let (a, b) = (&f[0], &p.label_strokes[0]);
    assert_eq!(a.len(), b.len());
    let k = (a.len() - 1).max(1);
    let scale = (b[k] - b[0]).length() / (a[k] - a[0]).length();
    assert!(scale > 0.0);
    for (pa, pb) in a.iter().zip(b) {
        let want = b[0] + (*pa - a[0]) * scale;
        assert!(want.distance(*pb) < 1e-9, "{want} {pb}");
    }
    // the first line sits above the others
    let last = p.label_strokes.last().unwrap();
    assert!(bbox(b).0.y > bbox(last).1.y);
}

#[test]
fn non_ascii_label_text_is_drawn_from_the_font_not_as_question_marks() {
    let mut input = PieceInput::new("manche", rect(300., 140.));
    input.label.quantity = 0;
    input.label.name = "±2° é".into();
    let p = Piece::build(&input, &PieceOptions::default()).unwrap();
    let f = font::text_strokes("±2° é", DVec2::ZERO, 1.0, DVec2::X);
    assert_eq!(p.label_strokes.len(), f.len());
    // the same glyphs, scaled and moved
    let (lo_f, hi_f) = bbox(&f.concat());
    let (lo_p, hi_p) = bbox(&p.label_strokes.concat());
    let s = (hi_p.x - lo_p.x) / (hi_f.x - lo_f.x);
    for (a, b) in f.iter().zip(&p.label_strokes) {
        for (pa, pb) in a.iter().zip(b) {
            assert!((lo_p + (*pa - lo_f) * s).distance(*pb) < 1e-9);
        }
    }
    for c in "±°é".chars() {
        assert!(font::has_glyph(c), "{c}");
    }
    // not what a '?' stand-in would draw
    assert_ne!(f, font::text_strokes("?2? ?", DVec2::ZERO, 1.0, DVec2::X));
}

/// The label's strokes on the sheet, moved so their box starts at the origin.
fn text_on_sheet(p: &Piece, placement: Placement) -> Vec<Vec<DVec2>> {
    let d = PlacedPiece {
        piece: p,
        instance: 1,
        placement,
    }
    .to_drawing();
    let text: Vec<Vec<DVec2>> = d
        .strokes
        .into_iter()
        .filter(|s| s.kind == StrokeKind::Text)
        .map(|s| s.points)
        .collect();
    let (lo, _) = bbox(&text.concat());
    text.into_iter()
        .map(|s| s.into_iter().map(|q| q - lo).collect())
        .collect()
}

#[test]
fn a_mirrored_placement_writes_the_label_readably_not_mirror_written() {
    let p = Piece::build(&busy_piece(), &PieceOptions::default()).unwrap();
    for rotation in [0.0, std::f64::consts::PI] {
        let plain = text_on_sheet(
            &p,
            Placement {
                rotation,
                mirror: false,
                translation: DVec2::new(40., 7.),
            },
        );
        let mirrored = text_on_sheet(
            &p,
            Placement {
                rotation,
                mirror: true,
                translation: DVec2::new(900., -3.),
            },
        );
        // the same strokes, point for point, up to where they are: the text is not reflected
        assert_eq!(plain.len(), mirrored.len());
        for (a, b) in plain.iter().zip(&mirrored) {
            for (pa, pb) in a.iter().zip(b) {
                assert!(pa.distance(*pb) < 1e-9, "{rotation}: {pa} vs {pb}");
            }
        }
        // a reflection of a label is not the label: the comparison has teeth
        let (_, hi) = bbox(&plain.concat());
        let reflected: Vec<Vec<DVec2>> = plain
            .iter()
            .map(|s| s.iter().map(|q| DVec2::new(hi.x - q.x, q.y)).collect())
            .collect();
        assert!(
            plain
                .iter()
                .zip(&reflected)
                .any(|(a, b)| a.iter().zip(b).any(|(x, y)| x.distance(*y) > 1e-3))
        );
    }
    // the text stays in its room under the mirror: every glyph inside the mirrored sew line
    let pl = Placement {
        rotation: 0.4,
        mirror: true,
        translation: DVec2::new(5., 5.),
    };
    let d = PlacedPiece {
        piece: &p,
        instance: 1,
        placement: pl,
    }
    .to_drawing();
    let sew = &d
        .strokes
        .iter()
        .find(|s| s.kind == StrokeKind::Sew)
        .unwrap()
        .points;
    let mut sew_ccw = sew.clone();
    if poly::signed_area(&sew_ccw) < 0.0 {
        sew_ccw.reverse();
    }
    for s in d.strokes.iter().filter(|s| s.kind == StrokeKind::Text) {
        for q in &s.points {
            assert!(poly::contains(&sew_ccw, *q));
        }
    }
}
