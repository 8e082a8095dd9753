//! SVG of a motion trace: tool-on moves (what was drawn or cut) as solid strokes, travel as thin dashed lines,
//! in millimetres with Y up (the SVG is flipped so that it looks like the sheet on the machine).

use crate::TraceSegment;
use std::fmt::Write as _;

/// Chord tolerance used to draw arcs as polylines, mm.
const ARC_CHORD_TOL_MM: f64 = 0.01;
/// Margin around the drawing, mm.
const MARGIN_MM: f64 = 5.0;

/// The XY points of a segment (arcs sampled within [`ARC_CHORD_TOL_MM`]).
pub fn segment_points(seg: &TraceSegment) -> Vec<[f64; 2]> {
    let (a, b) = ([seg.from[0], seg.from[1]], [seg.to[0], seg.to[1]]);
    let Some(c) = seg.arc_center else {
        return vec![a, b];
    };
    let cw = seg.motion == "G2";
    let (r0, r1) = (a[0] - c[0], a[1] - c[1]);
    let (t0, t1) = (b[0] - c[0], b[1] - c[1]);
    let radius = r0.hypot(r1);
    let mut ang = (r0 * t1 - r1 * t0).atan2(r0 * t0 + r1 * t1);
    if cw && ang >= -5e-7 {
        ang -= std::f64::consts::TAU;
    } else if !cw && ang <= 5e-7 {
        ang += std::f64::consts::TAU;
    }
    let step = if radius > ARC_CHORD_TOL_MM {
        2.0 * (1.0 - ARC_CHORD_TOL_MM / radius).acos()
    } else {
        ang.abs()
    };
    let n = ((ang.abs() / step.max(1e-6)).ceil() as usize).clamp(1, 100_000);
    let mut pts = Vec::with_capacity(n + 1);
    let start = r1.atan2(r0);
    for i in 0..n {
        let t = start + ang * i as f64 / n as f64;
        pts.push([c[0] + radius * t.cos(), c[1] + radius * t.sin()]);
    }
    pts.push(b);
    pts
}

/// Renders the trace as an SVG document.
pub fn trace_svg(trace: &[TraceSegment]) -> String {
    let polys: Vec<(bool, Vec<[f64; 2]>)> = trace
        .iter()
        .map(|s| (s.tool_on, segment_points(s)))
        .collect();
    let (mut x0, mut y0, mut x1, mut y1) = (
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    );
    for (_, pts) in &polys {
        for p in pts {
            x0 = x0.min(p[0]);
            y0 = y0.min(p[1]);
            x1 = x1.max(p[0]);
            y1 = y1.max(p[1]);
        }
    }
    if !x0.is_finite() {
        (x0, y0, x1, y1) = (0.0, 0.0, 0.0, 0.0);
    }
    let (w, h) = (x1 - x0 + 2.0 * MARGIN_MM, y1 - y0 + 2.0 * MARGIN_MM);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w:.3}mm" height="{h:.3}mm" viewBox="{:.3} {:.3} {w:.3} {h:.3}">"#,
        x0 - MARGIN_MM,
        -(y1 + MARGIN_MM)
    );
    let _ = writeln!(
        s,
        r#"<g transform="scale(1,-1)" fill="none" stroke-linecap="round" stroke-linejoin="round">"#
    );
    for (on, pts) in &polys {
        let d: Vec<String> = pts
            .iter()
            .map(|p| format!("{:.4},{:.4}", p[0], p[1]))
            .collect();
        let style = if *on {
            r##"stroke="#000" stroke-width="0.2""##
        } else {
            r##"stroke="#8ab" stroke-width="0.05" stroke-dasharray="0.5 0.5""##
        };
        let _ = writeln!(s, r#"<polyline {style} points="{}"/>"#, d.join(" "));
    }
    s.push_str("</g>\n</svg>\n");
    s
}
