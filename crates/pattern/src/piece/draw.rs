//! A piece as strokes on layers: what is cut (cut line, notches, drill holes), drawn (sew line,
//! points, internal and grain lines) and engraved (the label, LASTING in a lasting margin).

use super::Piece;
use crate::drawing::{Drawing, Layer, PieceInfo, Stroke, StrokeKind};
use flatcut_geom::DVec2;

/// Half-size of a reference point's cross (mm).
const CROSS: f64 = 1.5;

/// The layer a stroke of `kind` goes to.
fn layer_of(kind: StrokeKind) -> Layer {
    match kind {
        StrokeKind::Boundary | StrokeKind::InnerCut | StrokeKind::Notch | StrokeKind::Drill => {
            Layer::Cut
        }
        StrokeKind::Text => Layer::Engrave,
        _ => Layer::Draw,
    }
}

impl Piece {
    /// The piece as strokes: cut line (Boundary), drill holes and notches (Cut), sew line, points,
    /// internal and grain lines (Draw), label (Engrave). Ids are `{name}-{instance}-{what}`; the
    /// drawing's [`PieceInfo`] carries the label fields and the grain line.
    pub fn to_drawing(&self, instance: u32) -> Drawing {
        let id = self.instance_id(instance);
        let mk = |kind: StrokeKind, points: Vec<DVec2>, closed, what: String| Stroke {
            layer: layer_of(kind),
            points,
            closed,
            piece: Some(instance),
            kind,
            id: format!("{id}-{what}"),
        };
        let mut s = Vec::new();
        for (k, (c, d)) in self.drills.iter().enumerate() {
            let pts = circle(*c, d * 0.5, self.chord_tol);
            s.push(mk(StrokeKind::Drill, pts, true, format!("drill-{}", k + 1)));
        }
        for (k, nt) in self.notches.iter().enumerate() {
            // A named notch (a mating seam's) says which: `notch-<seam>_<n>`, with the name's
            // dashes and spaces as underscores so the id still splits into piece and notch.
            let what = match self.notch_names.get(k).filter(|n| !n.is_empty()) {
                Some(n) => format!("notch-{}", super::safe_name(n).replace('-', "_")),
                None => format!("notch-{}", k + 1),
            };
            s.push(mk(StrokeKind::Notch, nt.clone(), false, what));
        }
        s.push(mk(
            StrokeKind::Boundary,
            self.cut.clone(),
            true,
            "cut".into(),
        ));
        let sew = self.sew_polyline.clone();
        s.push(mk(StrokeKind::Sew, sew, true, "sew".into()));
        for (k, l) in self.sew_lines.iter().enumerate() {
            s.push(mk(
                StrokeKind::Sew,
                l.clone(),
                false,
                format!("dart-{}-sew", k + 1),
            ));
        }
        for (k, p) in self.points.iter().enumerate() {
            for (arm, d) in [("a", DVec2::X), ("b", DVec2::Y)] {
                let pts = vec![*p - d * CROSS, *p + d * CROSS];
                s.push(mk(
                    StrokeKind::Internal,
                    pts,
                    false,
                    format!("point-{}-{arm}", k + 1),
                ));
            }
        }
        for (k, l) in self.lines.iter().enumerate() {
            s.push(mk(
                StrokeKind::Internal,
                l.clone(),
                false,
                format!("line-{}", k + 1),
            ));
        }
        if let Some((a, b)) = self.grain {
            for (what, pts) in grain_arrow(a, b) {
                s.push(mk(StrokeKind::Grain, pts, false, what.into()));
            }
        }
        for (k, st) in self.label_strokes.iter().enumerate() {
            s.push(mk(
                StrokeKind::Text,
                st.clone(),
                false,
                format!("label-{}", k + 1),
            ));
        }
        for (k, st) in self.edge_labels.iter().enumerate() {
            s.push(mk(
                StrokeKind::Text,
                st.clone(),
                false,
                format!("label-lasting-{}", k + 1),
            ));
        }
        Drawing {
            strokes: s,
            pieces: vec![PieceInfo {
                piece: instance,
                label: self.label_with_name(),
                grain: self.grain,
            }],
        }
    }
}

/// A circle of radius `r` about `c` as a closed polygon within the chord tolerance (8 to 256
/// sides).
fn circle(c: DVec2, r: f64, chord_tol: f64) -> Vec<DVec2> {
    let step = 2.0 * (1.0 - (chord_tol / r).min(1.0)).acos();
    let m = ((std::f64::consts::TAU / step.max(1e-3)).ceil() as usize).clamp(8, 256);
    (0..m)
        .map(|i| c + r * DVec2::from_angle(i as f64 * std::f64::consts::TAU / m as f64))
        .collect()
}

/// The grain line from `a` to `b` with an arrow head at each end (a tenth of its length, at most
/// 8 mm): the line, the head at `b` and the tail at `a`, with their id suffixes.
fn grain_arrow(a: DVec2, b: DVec2) -> [(&'static str, Vec<DVec2>); 3] {
    let d = (b - a).normalize();
    let nrm = DVec2::new(-d.y, d.x);
    let head = (a.distance(b) * 0.1).min(8.0);
    [
        ("grain", vec![a, b]),
        (
            "grain-head",
            vec![
                b - d * head + nrm * head * 0.4,
                b,
                b - d * head - nrm * head * 0.4,
            ],
        ),
        (
            "grain-tail",
            vec![
                a + d * head + nrm * head * 0.4,
                a,
                a + d * head - nrm * head * 0.4,
            ],
        ),
    ]
}
