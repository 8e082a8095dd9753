//! Tests of the font: the Hershey data decodes, sizes are the asked cap height, non-ASCII text
//! is drawn (accents over their letters, symbols, Greek) and only unknown characters are boxes.

use super::*;
use crate::hershey::{Face, decode, glyph};

fn bbox(st: &[Vec<DVec2>]) -> (DVec2, DVec2) {
    st.iter().flatten().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    )
}

#[test]
fn every_glyph_of_the_three_faces_decodes() {
    for (face, src) in [
        (Face::Roman, include_str!("../data/futural.jhf")),
        (Face::Math, include_str!("../data/mathlow.jhf")),
        (Face::Greek, include_str!("../data/greek.jhf")),
    ] {
        let lines: Vec<&str> = src.lines().filter(|l| !l.trim().is_empty()).collect();
        assert_eq!(lines.len(), 96, "{face:?}: slots 32 to 127");
        for (k, l) in lines.iter().enumerate() {
            let g = decode(l).unwrap_or_else(|| panic!("{face:?} slot {}: {l}", k + 32));
            assert!(g.advance > 0.0, "{face:?} slot {}", k + 32);
            // every printable slot but the space has strokes
            assert_eq!(g.strokes.is_empty(), k == 0, "{face:?} slot {}", k + 32);
        }
    }
}

#[test]
fn capitals_are_the_asked_height_and_sit_on_the_baseline() {
    let st = text_strokes("H", DVec2::new(10.0, 5.0), 6.0, DVec2::X);
    let (lo, hi) = bbox(&st);
    assert!(
        (lo.y - 5.0).abs() < 1e-12 && (hi.y - 11.0).abs() < 1e-12,
        "{lo} {hi}"
    );
    // 'A' of the Roman simplex: bearings -9..9, apex at x 0 → 9 units from the pen
    let a = glyph(Face::Roman, 'A').unwrap();
    assert_eq!(a.advance, 18.0);
    assert!((text_width("A", 21.0) - 18.0).abs() < 1e-12);
    assert!((text_width("AB", 6.0) - text_width("A", 6.0) - text_width("B", 6.0)).abs() < 1e-12);
    let st = text_strokes("A", DVec2::ZERO, 21.0, DVec2::X);
    assert!(
        st.iter()
            .flatten()
            .any(|p| p.distance(DVec2::new(9.0, 21.0)) < 1e-12)
    );
}

#[test]
fn written_upward_the_glyph_turns_with_the_direction() {
    let st = text_strokes("I", DVec2::new(10.0, 0.0), 6.0, DVec2::Y);
    let (lo, hi) = bbox(&st);
    // up is −x: the letter's height runs from x = 10 to x = 4
    assert!(
        (hi.x - 10.0).abs() < 1e-12 && (lo.x - 4.0).abs() < 1e-12,
        "{lo} {hi}"
    );
    assert!(lo.y > 0.0);
}

#[test]
fn lowercase_is_drawn_as_lowercase() {
    let (_, hi_a) = bbox(&text_strokes("a", DVec2::ZERO, 21.0, DVec2::X));
    let (_, hi_cap) = bbox(&text_strokes("A", DVec2::ZERO, 21.0, DVec2::X));
    assert!((hi_a.y - 14.0).abs() < 1e-12 && hi_cap.y == 21.0, "{hi_a}");
    let (lo_g, _) = bbox(&text_strokes("g", DVec2::ZERO, 21.0, DVec2::X));
    assert!(lo_g.y < -5.0, "descender {lo_g}");
}

#[test]
fn non_ascii_text_is_drawn_not_replaced() {
    for c in "±°×÷≤≥≠µμδΔΩαπé".chars() {
        assert!(has_glyph(c), "{c}");
    }
    for c in "ÉÈÊËÀÁÂÃÄÅÇÑÖÕÜŮÝŘŠŽČĆŁØĐßæŒøłđıáâäåçèêëìíîïñòóôõöùúûüýÿăąęőűşţ²³¹".chars()
    {
        assert!(has_glyph(c), "{c}");
    }
    // the symbols are the mathematical glyphs, not question marks
    let q = text_strokes("?", DVec2::ZERO, 6.0, DVec2::X);
    for s in ["±", "°", "é", "中"] {
        assert_ne!(text_strokes(s, DVec2::ZERO, 6.0, DVec2::X), q, "{s}");
    }
    // a character Hershey did not draw is an empty box, and says so
    assert!(!has_glyph('中') && !has_glyph('€'));
    let boxed = text_strokes("中", DVec2::ZERO, 21.0, DVec2::X);
    assert_eq!(boxed.len(), 1);
    assert_eq!(boxed[0].len(), 5);
    assert_eq!(boxed[0][0], boxed[0][4]);
}

#[test]
fn an_accent_sits_over_its_letter_and_composed_equals_decomposed() {
    let e = text_strokes("e", DVec2::ZERO, 21.0, DVec2::X);
    let e_acute = text_strokes("é", DVec2::ZERO, 21.0, DVec2::X);
    assert_eq!(e_acute.len(), e.len() + 1);
    assert_eq!(e_acute[..e.len()], e[..]);
    let (lo_mark, hi_mark) = bbox(&e_acute[e.len()..]);
    let (lo_e, hi_e) = bbox(&e);
    assert!(lo_mark.y > hi_e.y, "the accent is above the letter");
    assert!(lo_mark.x > lo_e.x && hi_mark.x < hi_e.x, "and over it");
    assert_eq!(
        text_strokes("e\u{301}", DVec2::ZERO, 21.0, DVec2::X),
        e_acute
    );
    assert_eq!(text_width("é", 6.0), text_width("e", 6.0));
    // on a capital the accent clears the cap height
    let ea = text_strokes("É", DVec2::ZERO, 21.0, DVec2::X);
    assert!(bbox(&ea[ea.len() - 1..]).0.y > 21.0);
    // í loses the dot of the i
    let i = text_strokes("i", DVec2::ZERO, 21.0, DVec2::X);
    let i_acute = text_strokes("í", DVec2::ZERO, 21.0, DVec2::X);
    assert_eq!(i_acute.len(), i.len(), "the dot gives way to the accent");
    // a cedilla hangs below the baseline
    let c = text_strokes("ç", DVec2::ZERO, 21.0, DVec2::X);
    assert!(bbox(&c[c.len() - 1..]).0.y < 0.0);
}

#[test]
fn any_character_is_finite_and_never_panics() {
    let mut s = String::new();
    for u in (0..0x3400u32).chain(0x1f300..0x1f400) {
        if let Some(c) = char::from_u32(u) {
            s.push(c);
        }
    }
    s.push_str("\u{301}\u{308}x\u{330}\u{20dd}");
    let st = text_strokes(&s, DVec2::new(1.0, 2.0), 5.0, DVec2::X);
    assert!(st.iter().flatten().all(|p| p.is_finite()));
    assert!(st.iter().all(|s| !s.is_empty()));
    assert!(text_width(&s, 5.0).is_finite());
}
