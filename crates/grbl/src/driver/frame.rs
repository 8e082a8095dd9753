//! The controller's work frame — active coordinate system (G54..G59), G92 offset and tool length
//! offset — read with `$#` and `$G` before the connection's soft reset, and put back after it:
//! GRBL 1.1h's reset (`gc_init`) returns to G54 and zeroes G92 and the tool length offset,
//! keeping only the stored G54..G59 offsets, so without this a job meant for the operator's
//! origin would run at another place.

use super::SendOptions;
use super::error::SendError;
use super::session::{Session, transport};
use crate::job::fmt_num;
use crate::transport::Transport;
use std::time::Duration;

/// The work frame of a controller.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Frame {
    /// Active coordinate system, 54..=59.
    pub wcs: u8,
    /// Stored G54..G59 offsets, mm (machine coordinates of each system's origin).
    pub systems: [[f64; 3]; 6],
    /// G92 offset, mm.
    pub g92: [f64; 3],
    /// Tool length offset (G43.1), mm.
    pub tlo: f64,
}

impl Frame {
    /// Whether a reset would change this frame (anything but G54 without G92 and TLO).
    fn differs_from_reset(&self) -> bool {
        self.wcs != 54 || self.g92 != [0.0; 3] || self.tlo != 0.0
    }

    /// The offset of machine coordinates from the G92-free work coordinates of system `wcs`
    /// (54..=59): its stored origin and the tool length offset (on Z).
    pub fn origin_of(&self, wcs: u8) -> [f64; 3] {
        let k = usize::from(wcs.clamp(54, 59) - 54);
        let mut o = self.systems[k];
        o[2] += self.tlo;
        o
    }

    /// The frame in millimetres, from `$#` values reported in inches when `inches` (`$13=1`).
    pub fn in_mm(mut self, inches: bool) -> Frame {
        if inches {
            let k = 25.4;
            for v in self
                .systems
                .iter_mut()
                .chain(std::iter::once(&mut self.g92))
            {
                for x in v.iter_mut() {
                    *x *= k;
                }
            }
            self.tlo *= k;
        }
        self
    }

    /// How the frame reads, for messages: `G55, G92 X100 Y0 Z0`.
    pub fn describe(&self) -> String {
        let mut s = format!("G{}", self.wcs);
        if self.g92 != [0.0; 3] {
            let g = self.g92;
            s.push_str(&format!(
                ", G92 offset X{} Y{} Z{}",
                fmt_num(g[0]),
                fmt_num(g[1]),
                fmt_num(g[2])
            ));
        }
        if self.tlo != 0.0 {
            s.push_str(&format!(", tool length offset Z{}", fmt_num(self.tlo)));
        }
        s
    }
}

fn triple(s: &str) -> Option<[f64; 3]> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .ok()?;
    (v.len() >= 3 && v.iter().all(|x| x.is_finite())).then(|| [v[0], v[1], v[2]])
}

/// Reads the frame with `$#` (offsets, as reported: see [`Frame::in_mm`]) and `$G` (active
/// system), each waiting at most `timeout`. `Err(code)` when the controller refuses (`$#`
/// needs Idle or Alarm).
pub(super) fn read<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    timeout: Duration,
) -> Result<Result<Frame, u8>, SendError> {
    sess.feedback.clear();
    if let Err(code) = sess.command("$#", timeout)? {
        return Ok(Err(code));
    }
    let mut f = Frame {
        wcs: 54,
        systems: [[0.0; 3]; 6],
        g92: [0.0; 3],
        tlo: 0.0,
    };
    for line in std::mem::take(&mut sess.feedback) {
        let Some((name, value)) = line.split_once(':') else {
            continue;
        };
        match name {
            "G54" | "G55" | "G56" | "G57" | "G58" | "G59" => {
                if let (Ok(n), Some(v)) = (name[1..].parse::<usize>(), triple(value)) {
                    f.systems[n - 54] = v;
                }
            }
            "G92" => f.g92 = triple(value).unwrap_or(f.g92),
            "TLO" => f.tlo = value.trim().parse().unwrap_or(0.0),
            _ => {}
        }
    }
    sess.last_gc = None;
    if let Err(code) = sess.command("$G", timeout)? {
        return Ok(Err(code));
    }
    if let Some(gc) = &sess.last_gc {
        for w in gc.trim_start_matches("GC:").split_whitespace() {
            if let Some(n) = w.strip_prefix('G').and_then(|n| n.parse::<u8>().ok())
                && (54..=59).contains(&n)
            {
                f.wcs = n;
            }
        }
    }
    Ok(Ok(f))
}

/// After the connection's soft reset: puts the frame `before` back (the coordinate system
/// selected, the G92 offset re-applied from the position now reported, the tool length offset)
/// unless `opts.discard_offsets`; returns what was done, for the report. `before` is what `$#`
/// and `$G` said before the reset (`Err(code)`: the controller refused them).
pub(super) fn restore<T: Transport + ?Sized>(
    sess: &mut Session<'_, T>,
    before: Result<Frame, u8>,
    opts: &SendOptions,
) -> Result<Option<String>, SendError> {
    let before = match before {
        Ok(f) => f,
        Err(_) if opts.discard_offsets => return Ok(None),
        Err(code) => {
            return Err(SendError::OffsetsUnknown {
                why: format!(
                    "the controller refused `$#` or `$G` (error:{code}: {})",
                    crate::codes::error_meaning(code).unwrap_or("unknown code")
                ),
            });
        }
    };
    if !before.differs_from_reset() {
        return Ok(None);
    }
    let what = before.describe();
    if opts.discard_offsets {
        return Ok(Some(format!(
            "the soft reset at connection cleared the controller's work frame ({what}), and it was left so as asked: the job runs in G54 without G92"
        )));
    }
    if before.wcs != 54 {
        sess.command_ok(&format!("G{}", before.wcs), opts.command_timeout)?;
    }
    if before.tlo != 0.0 {
        sess.command_ok(
            &format!("G43.1Z{}", fmt_num(before.tlo)),
            opts.command_timeout,
        )?;
    }
    if before.g92 != [0.0; 3] {
        // G92 makes the current position read as the values given: the reported work position
        // (no G92 after the reset) less the offset re-creates the offset.
        sess.query_status(opts.command_timeout)
            .map_err(|e| transport(e, None))?;
        let Some(p) = sess.work_position() else {
            return Err(SendError::OffsetsUnknown {
                why: "the controller reported no position to re-apply the G92 offset from".into(),
            });
        };
        let g = before.g92;
        sess.command_ok(
            &format!(
                "G92X{}Y{}Z{}",
                fmt_num(p[0] - g[0]),
                fmt_num(p[1] - g[1]),
                fmt_num(p[2] - g[2])
            ),
            opts.command_timeout,
        )?;
    }
    Ok(Some(format!(
        "kept the controller's work frame across the soft reset at connection ({what}; GRBL's reset returns to G54 and clears G92)"
    )))
}
