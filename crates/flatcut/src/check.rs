//! The closed-loop check: how far what a device actually cut lies from the pattern it was given.
//! The device's trace (from a simulator or a machine that reports its path) is compared with the
//! drawing's strokes in machine coordinates.

use flatcut_gcode::Profile;
use flatcut_geom::DVec2;
use flatcut_pattern::Drawing;

/// One straight or circular motion a device made, in machine mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutSegment {
    pub from: DVec2,
    pub to: DVec2,
    /// Arc centre and direction (`true`: counter-clockwise) for a circular motion.
    pub arc: Option<(DVec2, bool)>,
}

/// Sampling step along a traced straight segment (mm).
const LINE_SAMPLE_MM: f64 = 0.5;
/// Chordal tolerance when sampling a traced arc (mm).
const ARC_SAMPLE_TOL_MM: f64 = 0.05;

/// Largest distance from a point the tool cut to the strokes of the drawing's enabled layers (a
/// one-sided Hausdorff distance, sampled every 0.5 mm along lines and to 0.05 mm along arcs).
/// Only tool-on cutting motions belong in `cut`.
pub fn trace_deviation(cut: &[CutSegment], d: &Drawing, profile: &Profile) -> f64 {
    let strokes: Vec<Vec<DVec2>> = d
        .strokes
        .iter()
        .filter(|s| profile.layer(s.layer).enabled)
        .map(|s| {
            let mut p: Vec<DVec2> = s.points.iter().map(|q| profile.to_machine(*q)).collect();
            if s.closed && !p.is_empty() {
                p.push(p[0]);
            }
            p
        })
        .collect();
    let dist = |q: DVec2| {
        strokes
            .iter()
            .flat_map(|s| s.windows(2))
            .map(|w| point_segment_distance(q, w[0], w[1]))
            .fold(f64::INFINITY, f64::min)
    };
    let mut worst: f64 = 0.0;
    for seg in cut {
        match seg.arc {
            Some((c, ccw)) => {
                for q in
                    flatcut_gcode::arcs::sample_arc(seg.from, seg.to, c, ccw, ARC_SAMPLE_TOL_MM)
                {
                    worst = worst.max(dist(q));
                }
            }
            None => {
                let n = ((seg.from.distance(seg.to) / LINE_SAMPLE_MM).ceil() as usize).max(1);
                for k in 0..=n {
                    worst = worst.max(dist(seg.from.lerp(seg.to, k as f64 / n as f64)));
                }
            }
        }
    }
    worst
}

fn point_segment_distance(q: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((q - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    q.distance(a + ab * t)
}
