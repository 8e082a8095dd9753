//! HP-GL/1 text for vinyl cutters and pen plotters: `IN;`, `SP`, `VS`, `FS` as the profile's
//! `[hpgl]` section says, then `PU`/`PD` with absolute coordinates in plotter units of 0.025 mm.
//!
//! The toolpaths are the same [`Plan`] the G-code writer prints (one planner: layer order,
//! inside before outside, travel order, drag-knife compensation with swivels and overcut, kerf,
//! tabs, lead-ins, sub-resolution moves dropped), so a vinyl cutter and a GRBL drag knife cut
//! the same path. Arcs become chords within the profile's arc tolerance (HP-GL/1 cutters differ
//! in their arc support; chords every device draws). Every coordinate is the exact machine
//! position rounded to the nearest plotter unit on its own, so rounding never accumulates: the
//! error of any point is at most half a unit (0.0125 mm), however long the job.

use std::fmt::Write as _;

use flatcut_geom::DVec2;

use crate::arcs;
use crate::plan::{Move, Plan, drop_sub_resolution};

/// Plotter units per millimetre (one unit is 0.025 mm).
pub const UNITS_PER_MM: f64 = 40.0;
/// Most coordinate pairs in one `PD` command: keeps every command well under the smallest
/// device buffers (a pair is at most 12 bytes).
pub const MAX_PAIRS_PER_COMMAND: usize = 16;

/// Why a plan cannot be written as HP-GL.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum HpglError {
    #[error(
        "profile {profile} has no [hpgl] section: it drives a GRBL controller (use `flatcut gcode`)"
    )]
    /// The profile drives a GRBL controller, not an HP-GL device.
    NotHpgl {
        /// The profile's name.
        profile: String,
    },
    #[error("profile {profile}: a laser is not an HP-GL device")]
    /// The profile is a laser's, which HP-GL does not drive.
    Laser {
        /// The profile's name.
        profile: String,
    },
}

/// Figures of an HP-GL job.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct HpglSummary {
    /// Bytes of the job.
    pub bytes: usize,
    /// HP-GL commands in the job.
    pub commands: usize,
    /// Tool-down length, every pass counted (mm).
    pub cut_length_mm: f64,
    /// Tool-up length between paths (mm).
    pub travel_length_mm: f64,
    /// Toolpaths in the job.
    pub paths: usize,
}

/// A point in plotter units, rounded to the nearest unit.
pub fn to_units(p: DVec2) -> (i64, i64) {
    (
        (p.x * UNITS_PER_MM).round() as i64,
        (p.y * UNITS_PER_MM).round() as i64,
    )
}

fn num(v: f64) -> String {
    let s = format!("{v:.1}");
    s.strip_suffix(".0").map(str::to_string).unwrap_or(s)
}

struct Writer {
    out: String,
    commands: usize,
}

impl Writer {
    fn cmd(&mut self, c: &str) {
        self.out.push_str(c);
        self.out.push_str(";\n");
        self.commands += 1;
    }
}

impl Plan {
    /// The job as HP-GL/1 (deterministic: the same plan gives the same bytes).
    pub fn to_hpgl(&self) -> Result<String, HpglError> {
        let p = &self.profile;
        let Some(h) = &p.hpgl else {
            return Err(HpglError::NotHpgl {
                profile: p.name.clone(),
            });
        };
        if p.kind == crate::ToolKind::Laser {
            return Err(HpglError::Laser {
                profile: p.name.clone(),
            });
        }
        let mut w = Writer {
            out: String::new(),
            commands: 0,
        };
        w.cmd("IN");
        w.cmd(&format!("SP{}", h.pen));
        if let Some(v) = h.velocity_cm_s {
            w.cmd(&format!("VS{}", num(v)));
        }
        if let Some(f) = h.force {
            w.cmd(&format!("FS{}", num(f)));
        }
        let tol = p.arc_tolerance_mm.max(1e-3);
        for tp in &self.paths {
            for _ in 0..tp.passes {
                let mut pts = vec![tp.start];
                let mut at = tp.start;
                for m in &tp.moves {
                    match *m {
                        Move::Line(q) => pts.push(q),
                        Move::Arc { to, center, ccw } => {
                            pts.extend(arcs::sample_arc(at, to, center, ccw, tol))
                        }
                    }
                    at = m.end();
                }
                let lines: Vec<Move> = pts[1..].iter().map(|&q| Move::Line(q)).collect();
                let unit = 1.0 / UNITS_PER_MM;
                let kept = drop_sub_resolution(pts[0], lines, unit);
                if kept.is_empty() {
                    continue;
                }
                let (x, y) = to_units(pts[0]);
                w.cmd(&format!("PU{x},{y}"));
                for chunk in kept.chunks(MAX_PAIRS_PER_COMMAND) {
                    let mut c = String::from("PD");
                    for (k, m) in chunk.iter().enumerate() {
                        let (x, y) = to_units(m.end());
                        let _ = write!(c, "{}{x},{y}", if k == 0 { "" } else { "," });
                    }
                    w.cmd(&c);
                }
            }
        }
        let (x, y) = to_units(self.home());
        w.cmd(&format!("PU{x},{y}"));
        w.cmd("SP0");
        Ok(w.out)
    }

    /// Size and lengths of the HP-GL job.
    pub fn hpgl_summary(&self) -> Result<HpglSummary, HpglError> {
        let text = self.to_hpgl()?;
        Ok(HpglSummary {
            bytes: text.len(),
            commands: text.matches(';').count(),
            cut_length_mm: self.cut_length(),
            travel_length_mm: self.travel_length(),
            paths: self.paths.len(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{GcodeOptions, Profile, plan};
    use flatcut_pattern::{Drawing, Layer, Stroke, StrokeKind};

    fn square(at: DVec2, s: f64, kind: StrokeKind) -> Stroke {
        Stroke {
            layer: Layer::Cut,
            points: vec![
                at,
                at + DVec2::new(s, 0.0),
                at + DVec2::new(s, s),
                at + DVec2::new(0.0, s),
            ],
            closed: true,
            piece: Some(0),
            kind,
            id: "sq".into(),
        }
    }

    #[test]
    fn header_units_and_no_accumulated_rounding() {
        // 2000 steps of 0.0101 mm: each point rounds on its own, the last lands on its unit.
        let pts: Vec<DVec2> = (0..=2000)
            .map(|k| DVec2::new(10.0 + 0.0101 * k as f64, 10.0 + (k % 2) as f64 * 0.3))
            .collect();
        let d = Drawing::from_strokes(vec![Stroke {
            layer: Layer::Draw,
            points: pts.clone(),
            closed: false,
            piece: None,
            kind: StrokeKind::Internal,
            id: "zig".into(),
        }]);
        let opts = GcodeOptions {
            reorder: false,
            ..GcodeOptions::default()
        };
        let text = plan(&d, &Profile::pen_hpgl(), &opts)
            .unwrap()
            .to_hpgl()
            .unwrap();
        assert!(text.starts_with("IN;\nSP1;\nVS38.1;\n"), "{}", &text[..40]);
        assert!(text.ends_with("PU0,0;\nSP0;\n"));
        let last = to_units(*pts.last().unwrap());
        assert!(
            text.contains(&format!("{},{};", last.0, last.1)),
            "ends at {last:?}"
        );
        assert_eq!(last, (((10.0 + 20.2) * 40.0_f64).round() as i64, 400));
        for c in text.split(';') {
            assert!(c.len() < 220, "command of {} bytes", c.len());
        }
    }

    #[test]
    fn vinyl_cuts_holes_first_then_the_weed_border() {
        let d = Drawing::from_strokes(vec![
            square(DVec2::new(10.0, 10.0), 50.0, StrokeKind::Boundary),
            square(DVec2::new(30.0, 30.0), 10.0, StrokeKind::InnerCut),
        ]);
        let plan = plan(&d, &Profile::vinyl(), &GcodeOptions::default()).unwrap();
        let ids: Vec<&str> = plan.paths.iter().map(|p| p.id.as_str()).collect();
        assert_eq!(ids, ["sq", "sq", "weed-border"]);
        assert!(
            plan.paths[0].length() < plan.paths[1].length(),
            "hole before outline"
        );
        let text = plan.to_hpgl().unwrap();
        assert!(text.contains("FS80;") && text.contains("VS20;"));
        assert!(Profile::knife().hpgl.is_none());
        let e = crate::plan(&d, &Profile::knife(), &GcodeOptions::default())
            .unwrap()
            .to_hpgl()
            .unwrap_err();
        assert!(matches!(e, HpglError::NotHpgl { .. }));
    }

    #[test]
    fn weed_border_follows_the_work_area_edge_where_the_job_touches_it() {
        // A piece drawn 2 mm from the sheet's corner: the border cannot go 5 mm below or left of it,
        // so it runs along the edge there, and the whole job stays in the work area.
        let d = Drawing::from_strokes(vec![square(DVec2::splat(2.0), 50.0, StrokeKind::Boundary)]);
        let plan = plan(&d, &Profile::vinyl(), &GcodeOptions::default()).unwrap();
        let border = plan.paths.iter().find(|p| p.id == "weed-border").unwrap();
        let k = Profile::vinyl().knife.unwrap();
        let margin = 2.0 * k.blade_offset_mm + k.overcut_mm;
        assert!((border.start.x - margin).abs() < 1e-9 || (border.start.y - margin).abs() < 1e-9);
        // Up and to the right the full 5 mm is kept.
        let far = border
            .moves
            .iter()
            .map(|m| m.end().x)
            .fold(f64::MIN, f64::max);
        assert!(far >= 57.0 - 1e-9, "border reaches x = {far}");
    }
}
