//! GRBL-dialect text: `G21 G90` header, fixed-precision numbers, `\n` line endings, lines of at
//! most [`GRBL_MAX_LINE`] characters, nothing GRBL rejects (no `%`, no `M6`, no `N` words, no
//! tool words), an explicit end state (tool off, pen up, air off) and `M2`.

use std::fmt::Write as _;

use flatcut_geom::{Aabb2, DVec2};

use crate::plan::{Move, Plan, Summary};
use crate::profile::{PenMode, Profile, ToolKind};
use crate::time::{self, Motion, estimate};

/// Our longest line (GRBL's limit is 79 significant characters; we keep a margin).
pub const GRBL_MAX_LINE: usize = 70;

struct Writer<'a> {
    p: &'a Profile,
    out: String,
    lines: usize,
    motions: Vec<Motion>,
    pos: [f64; 3],
    tool_on: bool,
}

impl<'a> Writer<'a> {
    fn new(p: &'a Profile) -> Self {
        Self {
            p,
            out: String::new(),
            lines: 0,
            motions: Vec::new(),
            pos: [0.0, 0.0, 0.0],
            tool_on: false,
        }
    }

    fn num(&self, v: f64) -> String {
        let d = self.p.decimals as usize;
        let s = format!("{v:.d$}");
        // Avoid "-0.000".
        if s.trim_start_matches('-')
            .chars()
            .all(|c| c == '0' || c == '.')
        {
            format!("{:.d$}", 0.0)
        } else {
            s
        }
    }

    fn line(&mut self, s: &str) {
        debug_assert!(s.len() <= GRBL_MAX_LINE, "line too long: {s}");
        self.out.push_str(s);
        self.out.push('\n');
        self.lines += 1;
    }

    fn comment(&mut self, text: &str) {
        // Parentheses cannot nest in GRBL comments; keep the line short.
        let clean: String = text
            .chars()
            .filter(|c| *c != '(' && *c != ')' && c.is_ascii() && !c.is_ascii_control())
            .collect();
        let mut s = format!("({clean}");
        s.truncate(GRBL_MAX_LINE - 1);
        s.push(')');
        self.line(&s);
    }

    fn travel_xy(&mut self, to: DVec2) {
        if (to.x - self.pos[0]).abs() < 1e-12 && (to.y - self.pos[1]).abs() < 1e-12 {
            return;
        }
        let laser_off = if self.p.kind == ToolKind::Laser {
            " S0"
        } else {
            ""
        };
        let s = format!("G0 X{} Y{}{}", self.num(to.x), self.num(to.y), laser_off);
        self.line(&s);
        self.motion([to.x, to.y, self.pos[2]], None);
    }

    /// Records a move for the estimate (`feed` `None`: a rapid).
    fn motion(&mut self, to: [f64; 3], feed: Option<f64>) {
        self.motions.push(Motion::Move {
            from: self.pos,
            to,
            feed_mm_min: feed,
        });
        self.pos = to;
    }

    fn z(&mut self, z: f64, feed: Option<f64>) {
        if (z - self.pos[2]).abs() < 1e-12 {
            return;
        }
        let s = match feed {
            None => format!("G0 Z{}", self.num(z)),
            Some(f) => format!("G1 Z{} F{}", self.num(z), self.num(f)),
        };
        self.line(&s);
        self.motion([self.pos[0], self.pos[1], z], feed);
    }

    fn dwell(&mut self, s: f64) {
        let t = format!("G4 P{}", self.num(s));
        self.line(&t);
        self.motions.push(Motion::Dwell(s));
    }

    fn tool_up(&mut self) {
        match self.p.kind {
            ToolKind::Pen => {
                // An HP-GL pen profile has no [pen] section: its G-code lifts nothing.
                let Some(pen) = self.p.pen.as_ref() else {
                    self.tool_on = false;
                    return;
                };
                match pen.mode {
                    PenMode::Servo => {
                        let s = format!("M3 S{}", self.num(pen.up_s));
                        self.line(&s);
                        self.dwell(pen.dwell_s);
                    }
                    PenMode::Z => self.z(pen.z_up, None),
                }
            }
            ToolKind::Knife => {
                let k = self.p.knife.as_ref().expect("validated");
                self.z(k.z_up, None);
            }
            ToolKind::Laser => {}
        }
        self.tool_on = false;
    }

    fn tool_down(&mut self) {
        match self.p.kind {
            ToolKind::Pen => {
                let Some(pen) = self.p.pen.as_ref() else {
                    self.tool_on = true;
                    return;
                };
                match pen.mode {
                    PenMode::Servo => {
                        let s = format!("M3 S{}", self.num(pen.down_s));
                        self.line(&s);
                        self.dwell(pen.dwell_s);
                    }
                    PenMode::Z => self.z(pen.z_down, Some(pen.plunge_mm_min)),
                }
            }
            ToolKind::Knife => {
                let k = self.p.knife.as_ref().expect("validated");
                self.z(k.z_down, Some(k.plunge_mm_min));
            }
            ToolKind::Laser => {}
        }
        self.tool_on = true;
    }

    fn work(&mut self, from: DVec2, m: &Move, feed: f64, power: Option<f64>, first: bool) {
        let extra = match (first, power) {
            (true, Some(s)) => format!(" F{} S{}", self.num(feed), self.num(s)),
            (true, None) => format!(" F{}", self.num(feed)),
            _ => String::new(),
        };
        match *m {
            Move::Line(p) => {
                let s = format!("G1 X{} Y{}{}", self.num(p.x), self.num(p.y), extra);
                self.line(&s);
                self.motion([p.x, p.y, self.pos[2]], Some(feed));
            }
            Move::Arc { to, center, ccw } => {
                let off = center - from;
                let s = format!(
                    "{} X{} Y{} I{} J{}{}",
                    if ccw { "G3" } else { "G2" },
                    self.num(to.x),
                    self.num(to.y),
                    self.num(off.x),
                    self.num(off.y),
                    extra
                );
                self.line(&s);
                // Time the arc as the chords GRBL splits it into.
                let z = self.pos[2];
                let chords = flatcut_motion::arc_chords(
                    [from.x, from.y, z],
                    [to.x, to.y, z],
                    [center.x, center.y],
                    (0, 1, 2),
                    !ccw,
                    time::limits(self.p).arc_tolerance,
                );
                for q in chords.into_iter().skip(1) {
                    self.motion(q, Some(feed));
                }
            }
        }
    }

    fn header(&mut self, title: &str) {
        self.comment(title);
        let p = self.p;
        let tool = match p.kind {
            ToolKind::Pen => "pen plotter",
            ToolKind::Knife => "drag knife",
            ToolKind::Laser => "laser: needs $32=1",
        };
        self.comment(&format!("profile {} - {}", p.name, tool));
        self.comment("units mm, absolute coordinates");
        self.line("G21 G90 G17 G94");
        match p.kind {
            ToolKind::Laser => {
                self.line("M4 S0");
                if p.laser.as_ref().is_some_and(|l| l.air_assist) {
                    self.line("M8");
                }
            }
            _ => self.tool_up(),
        }
    }

    fn footer(&mut self, home: DVec2) {
        match self.p.kind {
            ToolKind::Laser => {
                self.line("M5 S0");
                if self.p.laser.as_ref().is_some_and(|l| l.air_assist) {
                    self.line("M9");
                }
            }
            ToolKind::Pen => {
                self.tool_up();
                if self
                    .p
                    .pen
                    .as_ref()
                    .is_some_and(|p| p.mode == PenMode::Servo)
                {
                    self.line("M5");
                }
            }
            ToolKind::Knife => self.tool_up(),
        }
        self.travel_xy(home);
        self.line("M2");
    }
}

impl Plan {
    /// The job as G-code text (deterministic: the same plan gives the same bytes).
    pub fn to_gcode(&self) -> String {
        self.write().0
    }

    /// Line count, lengths and the run-time estimate from GRBL's motion model.
    pub fn summary(&self) -> Summary {
        let (_, lines, motions) = self.write();
        Summary {
            lines,
            cut_length_mm: self.cut_length(),
            travel_length_mm: self.travel_length(),
            est_time_s: estimate(&motions, &time::limits(&self.profile)),
            paths: self.paths.len(),
        }
    }

    fn write(&self) -> (String, usize, Vec<Motion>) {
        let mut w = Writer::new(&self.profile);
        let home = self.home();
        w.pos = [home.x, home.y, 0.0];
        w.header(&self.title);
        let mut last_layer = None;
        for tp in &self.paths {
            if last_layer != Some(tp.layer) {
                w.comment(&format!("layer {}", tp.layer.name()));
                last_layer = Some(tp.layer);
            }
            for pass in 0..tp.passes {
                if pass == 0 {
                    w.comment(&tp.id);
                }
                w.travel_xy(tp.start);
                w.tool_down();
                let power = (self.profile.kind == ToolKind::Laser).then_some(tp.power_s);
                let mut at = tp.start;
                for (k, m) in tp.moves.iter().enumerate() {
                    w.work(at, m, tp.feed, power, k == 0);
                    at = m.end();
                }
                w.tool_up();
            }
        }
        w.footer(home);
        let lines = w.lines;
        (w.out, lines, w.motions)
    }
}

/// A framing job: traces the bounding box (machine coordinates) with the tool off, so the
/// operator can check where the material must lie.
pub fn frame_job(bbox: Aabb2, profile: &Profile) -> String {
    let mut w = Writer::new(profile);
    let home = DVec2::new(0.0, 0.0);
    w.comment("flatcut frame: bounding box, tool off");
    w.line("G21 G90 G17 G94");
    if profile.kind == ToolKind::Laser {
        w.line("M5 S0");
    } else {
        w.tool_up();
    }
    let corners = [
        bbox.min,
        DVec2::new(bbox.max.x, bbox.min.y),
        bbox.max,
        DVec2::new(bbox.min.x, bbox.max.y),
        bbox.min,
    ];
    for c in corners {
        let s = format!("G0 X{} Y{}", w.num(c.x), w.num(c.y));
        w.line(&s);
    }
    let s = format!("G0 X{} Y{}", w.num(home.x), w.num(home.y));
    w.line(&s);
    w.line("M2");
    let mut out = w.out;
    // Frame moves at feed speed would be `G1 … F`; rapid is what senders' frame buttons do.
    let _ = write!(out, "");
    out
}
