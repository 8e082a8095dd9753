//! The closed-loop check: how far what a device actually cut lies from the pattern it was given.
//! The device's trace (from a simulator or a machine that reports its path) is compared with the
//! drawing's strokes in machine coordinates.

use flatcut_gcode::Profile;
use flatcut_geom::DVec2;
use flatcut_pattern::Drawing;

/// One straight or circular motion a device made, in machine mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutSegment {
    /// Where the motion starts (mm).
    pub from: DVec2,
    /// Where it ends (mm).
    pub to: DVec2,
    /// Arc centre and direction (`true`: counter-clockwise) for a circular motion.
    pub arc: Option<(DVec2, bool)>,
}

/// Sampling step along a traced straight segment (mm).
const LINE_SAMPLE_MM: f64 = 0.5;
/// Chordal tolerance when sampling a traced arc (mm).
const ARC_SAMPLE_TOL_MM: f64 = 0.05;

/// The drawing's strokes on enabled layers, in machine coordinates, as segments.
fn stroke_segments(d: &Drawing, profile: &Profile) -> Vec<(DVec2, DVec2)> {
    let mut out = Vec::new();
    for s in d.strokes.iter().filter(|s| profile.layer(s.layer).enabled) {
        let mut p: Vec<DVec2> = s.points.iter().map(|q| profile.to_machine(*q)).collect();
        if s.closed && !p.is_empty() {
            p.push(p[0]);
        }
        out.extend(p.windows(2).map(|w| (w[0], w[1])));
    }
    out
}

/// Largest distance from a point the tool cut to the strokes of the drawing's enabled layers (a
/// one-sided Hausdorff distance, sampled every 0.5 mm along lines and to 0.05 mm along arcs).
/// Only tool-on cutting motions belong in `cut`. For a drag knife `cut` is the axis's path,
/// which runs the blade offset ahead of the cut: see [`blade_tip_deviation`] for the blade.
pub fn trace_deviation(cut: &[CutSegment], d: &Drawing, profile: &Profile) -> f64 {
    let near = Nearest::new(stroke_segments(d, profile));
    let dist = |q: DVec2| near.distance(q);
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

/// Step of the blade tip's model along the axis's path, as a fraction of the blade offset: the
/// drag is integrated in steps this small (the tractrix's error per step is of the order of the
/// step squared over the offset).
const TIP_STEP_PER_OFFSET: f64 = 0.02;

/// Where a drag knife's blade tip went when its axis made the cutting motions `cut` (machine
/// mm), the tip trailing the axis by `offset` mm: the blade swivels freely, so the tip is
/// dragged towards the axis and stays `offset` behind it (a tractrix; around a swivel arc of
/// radius `offset` it stands still). At the start of each contiguous cut the blade is aligned
/// with the first move, as the G-code writer's compensation assumes it is at the plunge.
/// One polyline per contiguous cut.
pub fn blade_tip_paths(cut: &[CutSegment], offset: f64) -> Vec<Vec<DVec2>> {
    let h = (offset * TIP_STEP_PER_OFFSET).max(1e-4);
    let mut paths: Vec<Vec<DVec2>> = Vec::new();
    let mut at: Option<(DVec2, DVec2)> = None; // (axis, tip)
    for seg in cut {
        let pts: Vec<DVec2> = match seg.arc {
            Some((c, ccw)) => {
                // Chords whose angle is a step's worth of arc.
                let r = seg.from.distance(c);
                let angle = (h / r.max(h)).min(1.0);
                let tol = (r * (1.0 - (0.5 * angle).cos())).max(1e-12);
                let mut v = vec![seg.from];
                v.extend(flatcut_gcode::arcs::sample_arc(
                    seg.from, seg.to, c, ccw, tol,
                ));
                v
            }
            None => {
                let n = ((seg.from.distance(seg.to) / h).ceil() as usize).max(1);
                (0..=n)
                    .map(|k| seg.from.lerp(seg.to, k as f64 / n as f64))
                    .collect()
            }
        };
        let continues = at.is_some_and(|(a, _)| a.distance(seg.from) <= 1e-6);
        if !continues {
            at = None;
        }
        for q in pts {
            match at {
                None => {
                    // A new cut: the blade lies along its first move (known once it moves).
                    let dir = (seg.to - seg.from).normalize_or_zero();
                    if dir == DVec2::ZERO {
                        continue;
                    }
                    let tip = q - dir * offset;
                    paths.push(vec![tip]);
                    at = Some((q, tip));
                }
                Some((a, tip)) if q.distance(a) > 0.0 => {
                    let pull = (q - tip).normalize_or_zero();
                    let tip = if pull == DVec2::ZERO {
                        tip
                    } else {
                        q - pull * offset
                    };
                    if let Some(p) = paths.last_mut() {
                        p.push(tip);
                    }
                    at = Some((q, tip));
                }
                Some(_) => {}
            }
        }
    }
    paths
}

/// Largest distance from the blade tip of a drag knife to the strokes of the drawing's enabled
/// layers while its axis made the cutting motions `cut` (see [`blade_tip_paths`]): what the
/// knife cut, where [`trace_deviation`] measures the axis. `None` for a profile that is not a
/// knife with a blade offset.
pub fn blade_tip_deviation(cut: &[CutSegment], d: &Drawing, profile: &Profile) -> Option<f64> {
    let offset = profile
        .knife
        .as_ref()
        .filter(|_| profile.kind == flatcut_gcode::ToolKind::Knife)
        .map(|k| k.blade_offset_mm)
        .filter(|r| *r > 0.0)?;
    let near = Nearest::new(stroke_segments(d, profile));
    Some(
        blade_tip_paths(cut, offset)
            .iter()
            .flatten()
            .map(|&q| near.distance(q))
            .fold(0.0, f64::max),
    )
}

/// Nearest-segment queries over many segments: a grid of cells `CELL_MM` wide holding the
/// segments that pass within a cell of them, so a query near the strokes looks at few.
struct Nearest {
    segs: Vec<(DVec2, DVec2)>,
    cells: std::collections::BTreeMap<(i64, i64), Vec<usize>>,
}

/// Cell size of [`Nearest`]'s grid, mm: about the distances measured (a blade offset, a cut's
/// error), so a point near the strokes finds its nearest segment in the 3 × 3 cells around it.
const CELL_MM: f64 = 1.0;

impl Nearest {
    fn new(segs: Vec<(DVec2, DVec2)>) -> Nearest {
        let mut cells: std::collections::BTreeMap<(i64, i64), Vec<usize>> = Default::default();
        let cell = |v: f64| (v / CELL_MM).floor() as i64;
        for (i, (a, b)) in segs.iter().enumerate() {
            let (lo, hi) = (a.min(*b), a.max(*b));
            // Bounded: a segment longer than the sheet is not a pattern's.
            let (x0, x1, y0, y1) = (cell(lo.x), cell(hi.x), cell(lo.y), cell(hi.y));
            if (x1 - x0 + 1) * (y1 - y0 + 1) > 1_000_000 {
                continue;
            }
            for x in x0..=x1 {
                for y in y0..=y1 {
                    cells.entry((x, y)).or_default().push(i);
                }
            }
        }
        Nearest { segs, cells }
    }

    /// Distance from `q` to the nearest segment (infinite when there is none).
    fn distance(&self, q: DVec2) -> f64 {
        let (cx, cy) = (
            (q.x / CELL_MM).floor() as i64,
            (q.y / CELL_MM).floor() as i64,
        );
        let mut best = f64::INFINITY;
        for x in cx - 1..=cx + 1 {
            for y in cy - 1..=cy + 1 {
                for &i in self.cells.get(&(x, y)).into_iter().flatten() {
                    let (a, b) = self.segs[i];
                    best = best.min(point_segment_distance(q, a, b));
                }
            }
        }
        // A segment nearer than a cell passes through the 3 × 3 cells: farther, look at all.
        if best <= CELL_MM {
            return best;
        }
        self.segs
            .iter()
            .map(|&(a, b)| point_segment_distance(q, a, b))
            .fold(f64::INFINITY, f64::min)
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use flatcut_gcode::Move;
    use flatcut_gcode::knife::compensate;

    /// The axis path the knife compensation makes for `pts`, as the motions a trace records.
    fn axis_cut(pts: &[DVec2], profile: &Profile) -> Vec<CutSegment> {
        let cfg = profile.knife.clone().unwrap();
        let (start, moves) = compensate(pts, &cfg);
        let mut at = start;
        moves
            .iter()
            .map(|m| {
                let seg = match *m {
                    Move::Line(p) => CutSegment {
                        from: at,
                        to: p,
                        arc: None,
                    },
                    Move::Arc { to, center, ccw } => CutSegment {
                        from: at,
                        to,
                        arc: Some((center, ccw)),
                    },
                };
                at = m.end();
                seg
            })
            .collect()
    }

    fn dist_to_polyline(q: DVec2, pts: &[DVec2]) -> f64 {
        pts.windows(2)
            .map(|w| point_segment_distance(q, w[0], w[1]))
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn the_blade_tip_trails_the_axis_and_stands_still_on_a_swivel() {
        let knife = Profile::knife();
        let r = knife.knife.as_ref().unwrap().blade_offset_mm;
        // A straight cut: the tip runs the offset behind the axis, on the line.
        let line = [CutSegment {
            from: DVec2::new(0.0, 0.0),
            to: DVec2::new(10.0, 0.0),
            arc: None,
        }];
        let tip = &blade_tip_paths(&line, r)[0];
        assert!(tip[0].distance(DVec2::new(-r, 0.0)) < 1e-12);
        assert!(tip.last().unwrap().distance(DVec2::new(10.0 - r, 0.0)) < 1e-12);
        // An L with a right-angle corner: the compensation swivels the axis around the tip,
        // which cuts the drawn L exactly while the axis runs up to r off it.
        let l = [
            DVec2::new(0.0, 0.0),
            DVec2::new(20.0, 0.0),
            DVec2::new(20.0, 15.0),
        ];
        let cut = axis_cut(&l, &knife);
        let tips = blade_tip_paths(&cut, r);
        assert_eq!(tips.len(), 1);
        let worst_tip = tips[0]
            .iter()
            .map(|&q| dist_to_polyline(q, &l))
            .fold(0.0, f64::max);
        assert!(worst_tip < 1e-9, "tip {worst_tip}");
        let worst_axis = cut
            .iter()
            .flat_map(|s| [s.from, s.to])
            .map(|q| dist_to_polyline(q, &l))
            .fold(0.0, f64::max);
        assert!((worst_axis - r).abs() < 1e-9, "axis {worst_axis}");
        // A bend below the swivel threshold (10° < 20°) is not swivelled: the tip cuts inside
        // it, by at most the offset times the bend (sin 10° · r); the axis strays by r.
        let bend = [
            DVec2::new(0.0, 0.0),
            DVec2::new(20.0, 0.0),
            DVec2::new(
                20.0 + 20.0 * 10f64.to_radians().cos(),
                20.0 * 10f64.to_radians().sin(),
            ),
        ];
        let cut = axis_cut(&bend, &knife);
        let worst = blade_tip_paths(&cut, r)[0]
            .iter()
            .map(|&q| dist_to_polyline(q, &bend))
            .fold(0.0, f64::max);
        assert!(
            worst > 1e-4 && worst < r * 10f64.to_radians().sin(),
            "tip {worst}"
        );
        // Two cuts apart are two tip paths, each starting aligned.
        let two: Vec<CutSegment> = [
            line[0],
            CutSegment {
                from: DVec2::new(0.0, 5.0),
                to: DVec2::new(0.0, 9.0),
                arc: None,
            },
        ]
        .to_vec();
        let tips = blade_tip_paths(&two, r);
        assert_eq!(tips.len(), 2);
        assert!(tips[1][0].distance(DVec2::new(0.0, 5.0 - r)) < 1e-12);
    }
}
