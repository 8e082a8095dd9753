//! The plotter's HP-GL/1 interpreter: `IN`, `SP`, `PU`, `PD`, `PA`, `PR`, `VS`, `FS` (others
//! are accepted and counted), coordinates in plotter units (0.025 mm), pen-down motion traced.

use serde::Serialize;

use super::UNITS_PER_MM;

/// A pen-down (or knife-down) motion, mm.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PenSegment {
    pub from: [f64; 2],
    pub to: [f64; 2],
    pub pen: u32,
}

/// Interpreter state.
#[derive(Clone, Debug, Default)]
pub struct Interpreter {
    /// Position in plotter units.
    pub pos: [i64; 2],
    pub pen_down: bool,
    pub pen: u32,
    pub relative: bool,
    pub velocity_cm_s: Option<f64>,
    pub force: Option<f64>,
    pub commands: u64,
    pub unknown: u64,
    pub trace: Vec<PenSegment>,
    /// Pen travel executed, mm (for the device's timing).
    pub travel_mm: f64,
}

impl Interpreter {
    /// Runs one instruction (`PD100,200,300,400` without the terminator).
    pub fn execute(&mut self, instr: &str) {
        let instr = instr.trim_matches(|c: char| c.is_whitespace());
        if instr.len() < 2 {
            return;
        }
        self.commands += 1;
        let (op, args) = instr.split_at(2);
        let nums: Vec<f64> = args
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|t| !t.is_empty())
            .filter_map(|t| t.parse().ok())
            .collect();
        match op.to_ascii_uppercase().as_str() {
            "IN" => {
                let trace = std::mem::take(&mut self.trace);
                let (c, u, t) = (self.commands, self.unknown, self.travel_mm);
                *self = Interpreter::default();
                (self.trace, self.commands, self.unknown, self.travel_mm) = (trace, c, u, t);
            }
            "SP" => {
                self.pen = nums.first().map_or(0, |v| *v as u32);
                self.pen_down = false;
            }
            "PA" => {
                self.relative = false;
                self.moves(&nums);
            }
            "PR" => {
                self.relative = true;
                self.moves(&nums);
            }
            "PU" => {
                self.pen_down = false;
                self.moves(&nums);
            }
            "PD" => {
                self.pen_down = true;
                self.moves(&nums);
            }
            "VS" => self.velocity_cm_s = nums.first().copied(),
            "FS" => self.force = nums.first().copied(),
            _ => self.unknown += 1,
        }
    }

    fn moves(&mut self, nums: &[f64]) {
        for p in nums.chunks_exact(2) {
            let (x, y) = (p[0].round() as i64, p[1].round() as i64);
            let to = if self.relative {
                [self.pos[0] + x, self.pos[1] + y]
            } else {
                [x, y]
            };
            let mm = |q: [i64; 2]| [q[0] as f64 / UNITS_PER_MM, q[1] as f64 / UNITS_PER_MM];
            let (a, b) = (mm(self.pos), mm(to));
            self.travel_mm += ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
            if self.pen_down && self.pen != 0 && to != self.pos {
                self.trace.push(PenSegment {
                    from: a,
                    to: b,
                    pen: self.pen,
                });
            }
            self.pos = to;
        }
    }
}
