//! From a drawing to ordered, compensated, arc-fitted toolpaths in machine coordinates.

use flatcut_geom::{Aabb2, DVec2};
use flatcut_pattern::{Drawing, Layer, Stroke};

use crate::arcs;
use crate::cutter;
use crate::knife;
pub use crate::moves::Move;
use crate::order::{self, OrderItem};
use crate::profile::{LayerConfig, Profile, ToolKind};

/// A continuous tool-down path.
#[derive(Clone, Debug, PartialEq)]
pub struct Toolpath {
    /// The drawing layer the path comes from; its settings (feed, power, passes) apply.
    pub layer: Layer,
    /// The stroke's id from the drawing.
    pub id: String,
    /// Where the tool goes down (mm, machine frame).
    pub start: DVec2,
    /// The tool-down moves from `start`, in order.
    pub moves: Vec<Move>,
    /// Feed while working, mm/min.
    pub feed: f64,
    /// Laser `S` value (0 for pens and knives).
    pub power_s: f64,
    /// How many times the path is run (laser passes).
    pub passes: u32,
}

impl Toolpath {
    /// Length of one pass in mm (arcs exactly).
    pub fn length(&self) -> f64 {
        let mut at = self.start;
        let mut sum = 0.0;
        for m in &self.moves {
            sum += match *m {
                Move::Line(p) => at.distance(p),
                Move::Arc { to, center, ccw } => {
                    let r = at.distance(center);
                    let mut sweep = (to - center).to_angle() - (at - center).to_angle();
                    if ccw && sweep <= 0.0 {
                        sweep += std::f64::consts::TAU;
                    }
                    if !ccw && sweep >= 0.0 {
                        sweep -= std::f64::consts::TAU;
                    }
                    r * sweep.abs()
                }
            };
            at = m.end();
        }
        sum
    }

    /// Where the tool lifts: the last move's end, or `start` for a path without moves.
    pub fn end(&self) -> DVec2 {
        self.moves.last().map_or(self.start, Move::end)
    }
}

/// Options of a plan beyond the profile.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct GcodeOptions {
    /// Reorder strokes to shorten travel (otherwise drawing order within each layer group).
    pub reorder: bool,
    /// Fit arcs (the profile's `arc_tolerance_mm`); off gives lines only.
    pub arcs: bool,
    /// A title written into the header comment.
    pub title: String,
}

impl Default for GcodeOptions {
    fn default() -> Self {
        Self {
            reorder: true,
            arcs: true,
            title: String::from("flatcut job"),
        }
    }
}

/// Why no G-code could be planned.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum GcodeError {
    #[error("nothing to do: the drawing has no strokes on a layer the {profile} profile runs")]
    /// No stroke of the drawing lies on a layer the profile runs.
    Empty {
        /// The profile's name.
        profile: String,
    },
    #[error(
        "stroke '{id}' leaves the work area of profile {profile} ({w} × {h} mm) by {excess:.3} mm at machine ({x:.3}, {y:.3}); move the drawing (offset_mm) or use a larger machine"
    )]
    /// A stroke falls outside the machine's travel.
    OutsideWorkArea {
        /// The stroke's id from the drawing.
        id: String,
        /// The profile's name.
        profile: String,
        /// The work area's width (mm).
        w: f64,
        /// The work area's height (mm).
        h: f64,
        /// How far the stroke leaves the work area (mm).
        excess: f64,
        /// Machine x of the point furthest out (mm).
        x: f64,
        /// Machine y of the point furthest out (mm).
        y: f64,
    },
    #[error("stroke '{id}' has a non-finite coordinate")]
    /// A stroke has a NaN or infinite coordinate.
    NonFinite {
        /// The stroke's id from the drawing.
        id: String,
    },
}

/// The planned job: toolpaths in execution order plus the profile that will run them.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// The machine profile that runs the job.
    pub profile: Profile,
    /// The toolpaths in execution order, in machine coordinates (mm).
    pub paths: Vec<Toolpath>,
    /// The job's title, written into the header comment.
    pub title: String,
}

/// Figures of a job.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Summary {
    /// Lines of G-code written.
    pub lines: usize,
    /// Tool-down length, every pass counted (mm).
    pub cut_length_mm: f64,
    /// Tool-up length between paths (mm).
    pub travel_length_mm: f64,
    /// Estimated run time (s) from the profile's feeds, acceleration and junction deviation.
    pub est_time_s: f64,
    /// Toolpaths in the job.
    pub paths: usize,
}

/// Consecutive points closer than this are merged (mm): below any machine's resolution.
const DEDUP_MM: f64 = 1e-4;

/// Plans the drawing for the profile: layer order (engrave, draw, inner cuts, outer cuts), travel
/// ordering, knife compensation, arc fitting, work-area check.
///
/// A 50 mm square cut with a pen profile: 200 mm of cut, in millimetres (`G21`).
///
/// ```
/// use flatcut_gcode::{GcodeOptions, Profile, plan};
/// use flatcut_geom::DVec2;
/// use flatcut_pattern::{Drawing, Layer, Stroke, StrokeKind};
///
/// let square = [(10., 10.), (60., 10.), (60., 60.), (10., 60.)].map(|(x, y)| DVec2::new(x, y)).to_vec();
/// let stroke = Stroke {
///     layer: Layer::Cut,
///     points: square,
///     closed: true,
///     piece: Some(1),
///     kind: StrokeKind::Boundary,
///     id: "square-cut".into(),
/// };
/// let job = plan(&Drawing::from_strokes(vec![stroke]), &Profile::pen(), &GcodeOptions::default())?;
/// assert!((job.summary().cut_length_mm - 200.0).abs() < 1e-6);
/// assert!(job.to_gcode().contains("G21"));
/// # Ok::<(), flatcut_gcode::GcodeError>(())
/// ```
pub fn plan(drawing: &Drawing, profile: &Profile, opts: &GcodeOptions) -> Result<Plan, GcodeError> {
    let strokes = machine_strokes(drawing, profile)?;
    if strokes.is_empty() {
        return Err(GcodeError::Empty {
            profile: profile.name.clone(),
        });
    }
    let mut paths = Vec::new();
    let mut at = profile.to_machine(DVec2::ZERO);
    at = DVec2::new(at.x.max(0.0), at.y.max(0.0));
    for (layer, outer) in LAYER_ORDER {
        let members: Vec<&MachineStroke> = strokes
            .iter()
            .filter(|s| s.layer == layer && outer.is_none_or(|o| s.outer == o))
            .collect();
        if members.is_empty() {
            continue;
        }
        plan_group(&members, layer, profile, opts, &mut at, &mut paths)?;
    }
    if let (Some(w), ToolKind::Knife) = (
        profile.hpgl.as_ref().and_then(|h| h.weed_border_mm),
        profile.kind,
    ) && !paths.is_empty()
        && let Some(tp) = weed_border(&paths, w, opts, profile)
    {
        check_work_area(&tp, profile)?;
        paths.push(tp);
    }
    Ok(Plan {
        profile: profile.clone(),
        paths,
        title: opts.title.clone(),
    })
}

/// The order in which strokes are cut, by layer and (for cuts) inner before outer: engrave,
/// draw, inner cuts, outer cuts.
const LAYER_ORDER: [(Layer, Option<bool>); 4] = [
    (Layer::Engrave, None),
    (Layer::Draw, None),
    (Layer::Cut, Some(false)),
    (Layer::Cut, Some(true)),
];

/// A stroke in machine coordinates, cleaned.
struct MachineStroke {
    layer: Layer,
    outer: bool,
    closed: bool,
    id: String,
    pts: Vec<DVec2>,
}

/// The drawing's strokes on enabled layers in machine coordinates, cleaned; an error for a
/// stroke with a non-finite point.
fn machine_strokes(drawing: &Drawing, profile: &Profile) -> Result<Vec<MachineStroke>, GcodeError> {
    let mut strokes = Vec::new();
    for s in &drawing.strokes {
        if !profile.layer(s.layer).enabled {
            continue;
        }
        if s.points.iter().any(|p| !flatcut_geom::finite2(*p)) {
            return Err(GcodeError::NonFinite { id: s.id.clone() });
        }
        if let Some(m) = machine_stroke(s, profile) {
            strokes.push(m);
        }
    }
    Ok(strokes)
}

/// One stroke in machine coordinates: repeated points dropped, a closed stroke's repeated end
/// dropped, closed cuts offset by half the kerf; `None` when fewer than two points remain.
fn machine_stroke(s: &Stroke, profile: &Profile) -> Option<MachineStroke> {
    let mut pts: Vec<DVec2> = Vec::with_capacity(s.points.len());
    for &p in &s.points {
        let q = profile.to_machine(p);
        if pts.last().is_none_or(|l: &DVec2| l.distance(q) > DEDUP_MM) {
            pts.push(q);
        }
    }
    let mut closed = s.closed;
    if closed && pts.len() > 2 && pts[0].distance(pts[pts.len() - 1]) <= DEDUP_MM {
        pts.pop();
    }
    if pts.len() < 2 {
        return None;
    }
    if pts.len() < 3 {
        closed = false;
    }
    if closed && s.layer == Layer::Cut && profile.kerf_mm > 0.0 {
        pts = cutter::kerf_offset(&pts, s.is_outer(), 0.5 * profile.kerf_mm);
    }
    Some(MachineStroke {
        layer: s.layer,
        outer: s.is_outer(),
        closed,
        id: s.id.clone(),
        pts,
    })
}

/// Plans one group of strokes of `layer`: in travel order from `at` (moved to where the last
/// path ends), each stroke's toolpaths appended to `paths`.
fn plan_group(
    members: &[&MachineStroke],
    layer: Layer,
    profile: &Profile,
    opts: &GcodeOptions,
    at: &mut DVec2,
    paths: &mut Vec<Toolpath>,
) -> Result<(), GcodeError> {
    let items: Vec<OrderItem<'_>> = members
        .iter()
        .map(|s| OrderItem {
            points: &s.pts,
            closed: s.closed,
        })
        .collect();
    let tour = if opts.reorder {
        order::order(&items, *at)
    } else {
        (0..items.len())
            .map(|i| order::Visit {
                item: i,
                reversed: false,
                start: 0,
            })
            .collect()
    };
    let cfg = profile.layer(layer);
    let feed = profile.layer_feed(layer);
    let power_s = match (&profile.laser, profile.kind) {
        (Some(l), ToolKind::Laser) => l.s_max * cfg.power_pct.unwrap_or(100.0) / 100.0,
        _ => 0.0,
    };
    let passes = if profile.kind == ToolKind::Laser {
        cfg.passes
    } else {
        1
    };
    for v in tour {
        let s = members[v.item];
        let pts = order::visit_points(&items[v.item], &v);
        for (run, closed) in stroke_runs(pts, s, &cfg) {
            let run = lead_and_overcut(run, closed, s, profile);
            let tp = toolpath(run, layer, &s.id, feed, power_s, passes, opts, profile);
            if tp.moves.is_empty() {
                continue;
            }
            check_work_area(&tp, profile)?;
            *at = tp.end();
            paths.push(tp);
        }
    }
    Ok(())
}

/// The runs a stroke is cut in (points as visited, and whether the run is closed): tabs split a
/// closed cut into open runs; anything else is one run.
fn stroke_runs(pts: Vec<DVec2>, s: &MachineStroke, cfg: &LayerConfig) -> Vec<(Vec<DVec2>, bool)> {
    let closed_cut = s.closed && s.layer == Layer::Cut;
    match cfg.tabs {
        Some(t) if closed_cut => cutter::split_tabs(&pts, t.count, t.width_mm)
            .into_iter()
            .map(|r| (r, false))
            .collect(),
        _ => vec![(pts, s.closed)],
    }
}

/// A run of stroke `s` extended by the profile's lead-in and lead-out (closed cuts) or the
/// knife's overcut (closed runs).
fn lead_and_overcut(
    run: Vec<DVec2>,
    closed: bool,
    s: &MachineStroke,
    profile: &Profile,
) -> Vec<DVec2> {
    let closed_cut = s.closed && s.layer == Layer::Cut;
    let overcut = match (&profile.knife, profile.kind) {
        (Some(k), ToolKind::Knife) if closed => k.overcut_mm,
        _ => 0.0,
    };
    match &profile.lead {
        Some(lead) if closed && closed_cut => {
            cutter::with_leads(&run, &s.pts, s.outer, lead, overcut)
        }
        // A piece of a closed cut that tabs split is entered and left in the scrap as the whole
        // cut would be.
        Some(lead) if closed_cut => cutter::with_open_leads(&run, &s.pts, s.outer, lead),
        _ if overcut > 0.0 => knife::with_overcut(&run, overcut),
        _ => run,
    }
}

/// The weeding border: a rectangle `w` mm around everything cut, cut last so the waste lifts in
/// one sheet. Where the job lies closer than `w` to the edge of the work area the border follows
/// the edge instead (the material ends there, nothing to weed beyond it), kept a blade offset
/// and a swivel inside so the compensated cut stays in the work area. `None` when no border fits
/// around the job.
fn weed_border(
    paths: &[Toolpath],
    w: f64,
    opts: &GcodeOptions,
    profile: &Profile,
) -> Option<Toolpath> {
    let k = profile.knife.as_ref()?;
    let mut b = Aabb2::EMPTY;
    paths.iter().for_each(|tp| b.add(tp.start));
    for tp in paths {
        tp.moves.iter().for_each(|m| b.add(m.end()));
    }
    // The compensated knife path swings up to the blade offset (plus the swivel's lift-off)
    // outside the programmed corner.
    let margin = 2.0 * k.blade_offset_mm + k.overcut_mm;
    let area = DVec2::from_array(profile.work_area_mm);
    let lo = (b.min - DVec2::splat(w)).max(DVec2::splat(margin));
    let hi = (b.max + DVec2::splat(w)).min(area - DVec2::splat(margin));
    if !(lo.x < b.min.x && lo.y < b.min.y && hi.x > b.max.x && hi.y > b.max.y) {
        return None;
    }
    let border = vec![lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y), lo];
    let run = knife::with_overcut(&border, k.overcut_mm);
    let feed = profile.layer_feed(Layer::Cut);
    Some(toolpath(
        run,
        Layer::Cut,
        "weed-border",
        feed,
        0.0,
        1,
        opts,
        profile,
    ))
}

/// One toolpath from a run of points: drag-knife compensation for knives, arc fitting, and
/// moves below the output's resolution dropped.
fn toolpath(
    run: Vec<DVec2>,
    layer: Layer,
    id: &str,
    feed: f64,
    power_s: f64,
    passes: u32,
    opts: &GcodeOptions,
    profile: &Profile,
) -> Toolpath {
    let (start, moves) = match (&profile.knife, profile.kind) {
        (Some(k), ToolKind::Knife) => {
            let (start, moves) = knife::compensate(&run, k);
            (start, refit_lines(start, moves, opts, profile))
        }
        _ => (run[0], arcs::fit(&run, arc_tolerance(opts, profile))),
    };
    Toolpath {
        layer,
        id: id.to_string(),
        start,
        moves: drop_sub_resolution(start, moves, resolution(profile)),
        feed,
        power_s,
        passes,
    }
}

/// Arc-fits the maximal runs of lines in a compensated knife path (swivel arcs stay as they are).
fn refit_lines(
    start: DVec2,
    moves: Vec<Move>,
    opts: &GcodeOptions,
    profile: &Profile,
) -> Vec<Move> {
    let tol = arc_tolerance(opts, profile);
    let mut out = Vec::with_capacity(moves.len());
    let mut run = vec![start];
    for m in moves {
        match m {
            Move::Line(p) => run.push(p),
            arc @ Move::Arc { .. } => {
                out.extend(arcs::fit(&run, tol));
                run = vec![arc.end()];
                out.push(arc);
            }
        }
    }
    out.extend(arcs::fit(&run, tol));
    out
}

/// The smallest step the output can express: one unit in the last printed digit (mm).
pub fn resolution(profile: &Profile) -> f64 {
    10f64.powi(-(profile.decimals as i32))
}

/// Drops the moves that would print as no motion: a line or arc whose end, rounded to the
/// output's resolution, is where the tool already stands (rounded the same way). Such moves
/// come from knife compensation and arc fitting around points closer than the resolution; on
/// the machine they are repeated identical lines, and between them the blade turns on the spot.
pub fn drop_sub_resolution(start: DVec2, moves: Vec<Move>, resolution: f64) -> Vec<Move> {
    let grid = |p: DVec2| ((p.x / resolution).round(), (p.y / resolution).round());
    let mut at = grid(start);
    let mut out = Vec::with_capacity(moves.len());
    for m in moves {
        let end = grid(m.end());
        if end == at {
            continue;
        }
        at = end;
        out.push(m);
    }
    out
}

/// The tolerance handed to the arc fitter: the profile's, less what rounding the printed
/// coordinates can add (half a unit in the last digit, in x and y), so the G-code as written stays
/// within the profile's tolerance of the drawing.
fn arc_tolerance(opts: &GcodeOptions, profile: &Profile) -> f64 {
    if !opts.arcs {
        return 0.0;
    }
    let rounding = 0.5 * 10f64.powi(-(profile.decimals as i32)) * std::f64::consts::SQRT_2;
    (profile.arc_tolerance_mm - rounding).max(0.0)
}

fn check_work_area(tp: &Toolpath, profile: &Profile) -> Result<(), GcodeError> {
    let [w, h] = profile.work_area_mm;
    let mut pts = vec![tp.start];
    let mut at = tp.start;
    for m in &tp.moves {
        match *m {
            Move::Line(p) => pts.push(p),
            Move::Arc { to, center, ccw } => {
                pts.extend(arcs::sample_arc(at, to, center, ccw, 0.01))
            }
        }
        at = m.end();
    }
    // Slack for the last printed digit.
    let slack = 0.5 * 10f64.powi(-(profile.decimals as i32));
    for p in pts {
        let excess = (-p.x).max(p.x - w).max(-p.y).max(p.y - h);
        if excess > slack {
            return Err(GcodeError::OutsideWorkArea {
                id: tp.id.clone(),
                profile: profile.name.clone(),
                w,
                h,
                excess,
                x: p.x,
                y: p.y,
            });
        }
    }
    Ok(())
}

impl Plan {
    /// Bounding box of all tool-down motion, machine coordinates.
    pub fn bbox(&self) -> Aabb2 {
        let mut b = Aabb2::EMPTY;
        for tp in &self.paths {
            b.add(tp.start);
            let mut at = tp.start;
            for m in &tp.moves {
                match *m {
                    Move::Line(p) => b.add(p),
                    Move::Arc { to, center, ccw } => arcs::sample_arc(at, to, center, ccw, 0.01)
                        .into_iter()
                        .for_each(|p| b.add(p)),
                }
                at = m.end();
            }
        }
        b
    }

    /// Tool-down length over all passes, mm.
    pub fn cut_length(&self) -> f64 {
        self.paths
            .iter()
            .map(|p| p.length() * p.passes as f64)
            .sum()
    }

    /// Tool-up travel from the start position through all paths and back to the origin, mm.
    pub fn travel_length(&self) -> f64 {
        let mut at = self.home();
        let mut sum = 0.0;
        for p in &self.paths {
            for _ in 0..p.passes {
                sum += at.distance(p.start);
                at = p.end();
            }
        }
        sum + at.distance(self.home())
    }

    /// Where the job starts and ends (machine coordinates of the drawing origin, clamped into the
    /// work area).
    pub fn home(&self) -> DVec2 {
        let o = self.profile.to_machine(DVec2::ZERO);
        DVec2::new(
            o.x.clamp(0.0, self.profile.work_area_mm[0]),
            o.y.clamp(0.0, self.profile.work_area_mm[1]),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::{LeadConfig, LeadKind, TabsConfig};
    use flatcut_pattern::{Stroke, StrokeKind};

    /// Issue 38, item 7: a laser profile with tabs keeps its lead-ins. Every piece the tabs leave
    /// of a closed cut is entered and left in the scrap, a lead's length off the part (the
    /// laser pierces there, not on the part's edge), as the whole cut is without tabs.
    #[test]
    fn tabs_keep_the_lead_ins() {
        let (w, h) = (60.0, 30.0);
        let d = Drawing::from_strokes(vec![Stroke {
            layer: Layer::Cut,
            points: vec![
                DVec2::new(50.0, 50.0),
                DVec2::new(50.0 + w, 50.0),
                DVec2::new(50.0 + w, 50.0 + h),
                DVec2::new(50.0, 50.0 + h),
            ],
            closed: true,
            piece: Some(0),
            kind: StrokeKind::Boundary,
            id: "plate".into(),
        }]);
        // Distance of a point from the part's outline, and whether it is inside.
        let off = |p: DVec2| {
            let (x, y) = (p.x - 50.0, p.y - 50.0);
            let inside = x > 0.0 && x < w && y > 0.0 && y < h;
            let dx = (-x).max(x - w).max(0.0);
            let dy = (-y).max(y - h).max(0.0);
            let d = if inside {
                x.min(w - x).min(y).min(h - y)
            } else {
                dx.hypot(dy)
            };
            (inside, d)
        };
        for kind in [LeadKind::Line, LeadKind::Arc] {
            let mut laser = Profile::laser();
            laser.lead = Some(LeadConfig {
                kind,
                length_mm: 3.0,
            });
            let mut cut = laser.layer(Layer::Cut);
            cut.tabs = Some(TabsConfig {
                count: 4,
                width_mm: 2.0,
            });
            laser.layers.insert("cut".into(), cut);
            let opts = GcodeOptions {
                arcs: false,
                ..GcodeOptions::default()
            };
            let p = plan(&d, &laser, &opts).unwrap();
            let pieces: Vec<&Toolpath> = p.paths.iter().filter(|t| t.layer == Layer::Cut).collect();
            assert_eq!(
                pieces.len(),
                4,
                "{kind:?}: one cut per piece between the tabs"
            );
            for t in pieces {
                for end in [t.start, t.end()] {
                    // A line lead ends 3 mm off the part; an arc lead 3 mm off the outline's
                    // line, or farther where it swings back past a corner.
                    let (inside, d) = off(end);
                    let far = match kind {
                        LeadKind::Line => (d - 3.0).abs() < 1e-9,
                        LeadKind::Arc => d >= 3.0 - 1e-9,
                    };
                    assert!(
                        !inside && far,
                        "{kind:?}: a piece starts or ends at {end}, {d} mm from the part"
                    );
                }
                // Between its leads (one point each for a line, eight for an arc) the piece
                // runs on the outline.
                let (lead_in, lead_out) = match kind {
                    LeadKind::Line => (0, 1),
                    LeadKind::Arc => (7, 8),
                };
                let on_outline = t.moves[lead_in..t.moves.len() - lead_out]
                    .iter()
                    .all(|m| off(m.end()).1 < 1e-9);
                assert!(on_outline, "{kind:?}: {t:?}");
            }
        }
    }

    /// A closed outline whose vertices come in clusters closer than the output resolution (as
    /// offsets of fine meshes give): a knife job must not repeat a line or turn on the spot.
    #[test]
    fn no_repeated_or_sub_resolution_moves() {
        let mut pts = Vec::new();
        for k in 0..90 {
            let c =
                DVec2::new(100.0, 100.0) + 40.0 * DVec2::from_angle(k as f64 * 4f64.to_radians());
            pts.push(c);
            pts.push(c + DVec2::new(0.0003, -0.0002));
            pts.push(c + DVec2::new(-0.0002, 0.0004));
        }
        let d = Drawing::from_strokes(vec![Stroke {
            layer: Layer::Cut,
            points: pts,
            closed: true,
            piece: Some(0),
            kind: StrokeKind::Boundary,
            id: "disc".into(),
        }]);
        for profile in [Profile::knife(), Profile::laser(), Profile::pen()] {
            let opts = GcodeOptions {
                arcs: false,
                ..GcodeOptions::default()
            };
            let text = plan(&d, &profile, &opts).unwrap().to_gcode();
            let moves: Vec<&str> = text.lines().filter(|l| l.starts_with("G1 X")).collect();
            for w in moves.windows(2) {
                let xy = |l: &str| l.split(' ').take(3).collect::<Vec<_>>().join(" ");
                assert_ne!(xy(w[0]), xy(w[1]), "{}: repeated move", profile.name);
            }
            let pos = |l: &str| -> DVec2 {
                let v = |a: char| {
                    l.split(' ')
                        .find_map(|w| w.strip_prefix(a))
                        .unwrap()
                        .parse::<f64>()
                        .unwrap()
                };
                DVec2::new(v('X'), v('Y'))
            };
            let res = resolution(&profile);
            for w in moves.windows(2) {
                assert!(
                    pos(w[0]).distance(pos(w[1])) >= res * 0.999,
                    "{}: {w:?}",
                    profile.name
                );
            }
        }
    }
}
