//! A piece's orientation in its own frame: a flattening leaves it at whatever rotation the solver
//! found, so before it is built the piece is turned with its grain line along +x (the roll's
//! length in nesting), or, without a grain line, with its minimum-area bounding box axis-aligned
//! and its longer side along x.

use super::PieceInput;
use flatcut_geom::DVec2;

/// Rotations smaller than this (radians) are none: an outline already square to the axes keeps
/// its exact coordinates.
const NO_TURN: f64 = 1e-12;

/// The rotation (radians, counter-clockwise) that orients an outline: the grain along +x when
/// there is one, else the minimum-area bounding rectangle of its convex hull (geo's
/// `MinimumRotatedRect`: every hull edge tried as a side) square to the axes, its longer side
/// along x, by the smallest such turn.
pub fn orientation(outline: &[DVec2], grain: Option<(DVec2, DVec2)>) -> f64 {
    if let Some((a, b)) = grain {
        let d = b - a;
        if d.length() > 0.0 && d.is_finite() {
            return -d.y.atan2(d.x);
        }
    }
    min_area_rect_angle(outline).map_or(0.0, |a| -a)
}

/// The direction (radians, in (−π/2, π/2]) of the longer side of the minimum-area bounding
/// rectangle of `pts`.
fn min_area_rect_angle(pts: &[DVec2]) -> Option<f64> {
    use geo::MinimumRotatedRect;
    let mp: geo::MultiPoint<f64> = pts.iter().map(|p| geo::Point::new(p.x, p.y)).collect();
    let rect = mp.minimum_rotated_rect()?;
    let c: Vec<DVec2> = rect
        .exterior()
        .coords()
        .map(|c| DVec2::new(c.x, c.y))
        .collect();
    if c.len() < 3 {
        return None;
    }
    let (e0, e1) = (c[1] - c[0], c[2] - c[1]);
    let side = if e0.length() >= e1.length() { e0 } else { e1 };
    if side.length() == 0.0 {
        return None;
    }
    // a side's direction is defined up to a half turn: the one in (−π/2, π/2]
    let mut a = side.y.atan2(side.x);
    if a <= -std::f64::consts::FRAC_PI_2 {
        a += std::f64::consts::PI;
    } else if a > std::f64::consts::FRAC_PI_2 {
        a -= std::f64::consts::PI;
    }
    Some(a)
}

impl PieceInput {
    /// Turns the piece about the origin so it is oriented ([`orientation`]): outline, marks,
    /// internal and inner sew lines and grain together. Returns the rotation applied (radians).
    pub fn orient(&mut self) -> f64 {
        let angle = orientation(&self.outline, self.grain);
        if angle.abs() < NO_TURN || !angle.is_finite() {
            return 0.0;
        }
        self.rotate(angle);
        angle
    }

    /// Turns everything in the piece's frame by `angle` radians about the origin.
    pub fn rotate(&mut self, angle: f64) {
        let r = DVec2::from_angle(angle);
        self.outline.iter_mut().for_each(|p| *p = r.rotate(*p));
        self.marks.iter_mut().for_each(|m| m.pos = r.rotate(m.pos));
        self.lines
            .iter_mut()
            .chain(self.sew_lines.iter_mut())
            .flatten()
            .for_each(|p| *p = r.rotate(*p));
        self.grain = self.grain.map(|(a, b)| (r.rotate(a), r.rotate(b)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn turned(pts: &[DVec2], angle: f64) -> Vec<DVec2> {
        pts.iter()
            .map(|p| DVec2::from_angle(angle).rotate(*p))
            .collect()
    }

    fn extent(pts: &[DVec2]) -> DVec2 {
        let (lo, hi) = pts.iter().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        hi - lo
    }

    /// A 50 × 200 strip standing upright.
    fn strip() -> [DVec2; 4] {
        [
            DVec2::ZERO,
            DVec2::new(50.0, 0.0),
            DVec2::new(50.0, 200.0),
            DVec2::new(0.0, 200.0),
        ]
    }

    #[test]
    fn a_square_at_45_degrees_comes_out_axis_aligned() {
        let sq = [DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y].map(|p| p * 100.0);
        let mut input = PieceInput::new("square", turned(&sq, std::f64::consts::FRAC_PI_4));
        assert!((extent(&input.outline).x - 141.421).abs() < 1e-3);
        input.orient();
        let e = extent(&input.outline);
        assert!(
            (e.x - 100.0).abs() < 1e-9 && (e.y - 100.0).abs() < 1e-9,
            "{e}"
        );
    }

    #[test]
    fn without_grain_the_longer_side_runs_along_x() {
        let r = strip();
        for deg in [0.0f64, 19.0, 90.0, 135.0, -71.0] {
            let mut input = PieceInput::new("strip", turned(&r, deg.to_radians()));
            input.orient();
            let e = extent(&input.outline);
            assert!(
                (e.x - 200.0).abs() < 1e-9 && (e.y - 50.0).abs() < 1e-9,
                "{deg}°: {e}"
            );
        }
    }

    #[test]
    fn the_grain_runs_along_plus_x_and_everything_turns_with_it() {
        let r = strip();
        let mut input = PieceInput::new("strip", r.to_vec());
        // grain across the strip at 30°: the piece turns by −30°
        let g = (
            DVec2::new(10.0, 100.0),
            DVec2::new(10.0, 100.0) + DVec2::from_angle(std::f64::consts::FRAC_PI_6),
        );
        input.grain = Some(g);
        input
            .lines
            .push(vec![DVec2::new(5.0, 5.0), DVec2::new(45.0, 5.0)]);
        input.marks.push(crate::Mark {
            kind: crate::MarkKind::Drill,
            pos: DVec2::new(25.0, 50.0),
            boundary_index: None,
        });
        let before = input.clone();
        let a = input.orient();
        assert!((a + std::f64::consts::FRAC_PI_6).abs() < 1e-12);
        let (ga, gb) = input.grain.unwrap();
        assert!((gb - ga).y.abs() < 1e-12 && (gb - ga).x > 0.0);
        // rigid: distances between the outline, a line and a mark are kept
        let d0 = before.marks[0].pos.distance(before.lines[0][1]);
        let d1 = input.marks[0].pos.distance(input.lines[0][1]);
        assert!((d0 - d1).abs() < 1e-9);
        assert!(
            (before.outline[2].distance(before.marks[0].pos)
                - input.outline[2].distance(input.marks[0].pos))
            .abs()
                < 1e-9
        );
    }
}
