//! Writes a sample two-piece layout SVG and the expected cut-line figures for
//! `tools/check_svg.py`: `cargo run -p flatcut-pattern --example sample_svg -- OUT.svg OUT.json`.

use flatcut_geom::DVec2;
use flatcut_pattern::{
    Mark, MarkKind, Piece, PieceInput, PieceOptions, PlacedPiece, Placement, svg,
};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (svg_path, json_path) = (&args[1], &args[2]);
    // a vamp-like piece: a straight throat line and a rounded toe
    let mut outline = vec![DVec2::new(0., 0.), DVec2::new(120., 0.)];
    for i in 1..40 {
        let a = -std::f64::consts::FRAC_PI_2 + i as f64 / 40.0 * std::f64::consts::PI;
        outline.push(DVec2::new(120., 45.) + 45.0 * DVec2::from_angle(a));
    }
    outline.push(DVec2::new(120., 90.));
    outline.push(DVec2::new(0., 90.));
    let mut input = PieceInput::new("vamp", outline);
    input.marks.push(Mark {
        kind: MarkKind::Notch,
        pos: DVec2::new(60., 0.),
        boundary_index: None,
    });
    input.grain = Some((DVec2::new(20., 45.), DVec2::new(140., 45.)));
    input.label.size = "42".into();
    input.label.material = "CALF 1.4MM".into();
    let piece = Piece::build(&input, &PieceOptions::default()).expect("piece");
    let sheet = DVec2::new(600., 400.);
    let placed = [
        PlacedPiece {
            piece: &piece,
            instance: 1,
            placement: Placement {
                rotation: 0.0,
                mirror: false,
                translation: DVec2::new(20., 20.),
            },
        },
        PlacedPiece {
            piece: &piece,
            instance: 2,
            placement: Placement {
                rotation: 0.7,
                mirror: true,
                translation: DVec2::new(400., 150.),
            },
        },
    ];
    let text = svg::write_pieces(&placed, Some(sheet));
    flatcut_pattern::write_atomic(std::path::Path::new(svg_path), text.as_bytes())
        .expect("write svg");
    let mut cuts = Vec::new();
    for p in &placed {
        let pts: Vec<DVec2> = p.piece.cut.iter().map(|q| p.placement.apply(*q)).collect();
        let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
        for q in &pts {
            lo = lo.min(*q);
            hi = hi.max(*q);
        }
        // SVG frame: y down from the sheet's top edge; coordinates rounded as written (3 decimals)
        cuts.push(format!(
            "\"{}-cut\": {{\"length_mm\": {:.6}, \"bbox_mm\": [{:.6}, {:.6}, {:.6}, {:.6}]}}",
            p.piece.instance_id(p.instance),
            p.piece.cut_length(),
            lo.x,
            sheet.y - hi.y,
            hi.x,
            sheet.y - lo.y
        ));
    }
    let json = format!(
        "{{\"width_mm\": {}, \"height_mm\": {}, \"cuts\": {{{}}}}}\n",
        sheet.x,
        sheet.y,
        cuts.join(", ")
    );
    flatcut_pattern::write_atomic(std::path::Path::new(json_path), json.as_bytes())
        .expect("write json");
}
