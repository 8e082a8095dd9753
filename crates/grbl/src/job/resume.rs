//! What to send before resuming a job part-way: the preamble that puts the machine into the state
//! the job had at that line, and the first line itself.

use super::modal::{MotionMode, Spindle, Units};
use super::parse::words;
use super::{Job, MAX_LINE_CHARS, add, fmt_num};

impl Job {
    /// Lines to send before resuming at line index `next` (0-based) so that the machine is in
    /// the modal state the job had there: tool off, pen/tool up to the job's safe Z, rapid to
    /// the position, back down, tool state, coolant, feed, feed mode, distance mode and units
    /// restored. The lines are stripped and at most 79 characters.
    pub fn resume_preamble(&self, next: usize) -> Vec<String> {
        let st = self.state_before(next);
        self.resume_preamble_from(next, add(st.position, st.g92), true)
    }

    /// [`Job::resume_preamble`] for a machine to be put at `at` (G92-free work coordinates, mm)
    /// rather than at the start of line `next`: the point where a stopped run left line `next`
    /// part-way, so that re-sending it (in G90) completes it without repeating the part done.
    /// With `travel` false the machine is known to stand at `at` already and the preamble only
    /// restores the modal state (no tool lift, no travel).
    pub fn resume_preamble_from(&self, next: usize, at: [f64; 3], travel: bool) -> Vec<String> {
        let st = self.state_before(next);
        let f = |v: f64| fmt_num(v);
        let mut out = vec![
            "G21G90G94".to_string(),
            format!("G{}G{}", st.plane, st.wcs),
            "M5M9".to_string(),
        ];
        if self.uses_g92 {
            out.push("G92.1".into());
        }
        // Absolute target in the G92-free frame.
        let p = at;
        if travel {
            if let Some(z) = self.safe_z {
                out.push(format!("G0Z{}", f(z)));
            }
            out.push(format!("G0X{}Y{}", f(p[0]), f(p[1])));
        }
        match st.spindle {
            Spindle::Off => out.push(format!("S{}", f(st.speed))),
            Spindle::Cw => out.push(format!("M3S{}", f(st.speed))),
            Spindle::Ccw => out.push(format!("M4S{}", f(st.speed))),
        }
        if st.mist {
            out.push("M7".into());
        }
        if st.flood {
            out.push("M8".into());
        }
        if self.safe_z.is_some() && travel {
            if st.feed > 0.0 && !st.inverse_time {
                // Down at the job's own plunge feed (its cutting feed would ram the tool in);
                // the cutting feed is restored below.
                let feed = self.plunge_feed(next).unwrap_or(st.feed);
                out.push(format!("G1Z{}F{}", f(p[2]), f(feed)));
            } else {
                out.push(format!("G0Z{}", f(p[2])));
            }
        }
        if self.uses_g92 {
            // The offset that makes `at` read as the job's own coordinates there.
            out.push(format!(
                "G92X{}Y{}Z{}",
                f(p[0] - st.g92[0]),
                f(p[1] - st.g92[1]),
                f(p[2] - st.g92[2])
            ));
        }
        if st.feed > 0.0 && !st.inverse_time {
            out.push(format!("F{}", f(st.feed)));
        }
        let mut modes = String::new();
        if st.inverse_time {
            modes.push_str("G93");
        }
        if st.incremental {
            modes.push_str("G91");
        }
        if st.units == Units::Inch {
            modes.push_str("G20");
        }
        match st.motion {
            MotionMode::Rapid => modes.push_str("G0"),
            MotionMode::Linear => modes.push_str("G1"),
            // G2/G3 without axis words is an error; the first resumed line gets the word instead
            // (see `resume_line`).
            MotionMode::ArcCw | MotionMode::ArcCcw => {}
            MotionMode::Cancel => modes.push_str("G80"),
        }
        if !modes.is_empty() {
            out.push(modes);
        }
        out
    }

    /// The text to send for line `index` when it is the first line after a resume preamble: an
    /// arc line that relies on a modal G2/G3 gets its motion word back.
    pub fn resume_line(&self, index: usize) -> String {
        let l = &self.lines[index];
        let has_motion = words(&l.text)
            .map(|ws| {
                ws.iter().any(|w| {
                    w.0 == 'G' && matches!((w.1 * 10.0).round() as i64, 0 | 10 | 20 | 30 | 800)
                })
            })
            .unwrap_or(true);
        let prefix = match l.before.motion {
            MotionMode::ArcCw if !has_motion => "G2",
            MotionMode::ArcCcw if !has_motion => "G3",
            _ => "",
        };
        let s = format!("{prefix}{}", l.text);
        if s.len() <= MAX_LINE_CHARS {
            s
        } else {
            l.text.clone()
        }
    }
}
