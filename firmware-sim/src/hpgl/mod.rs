//! An HP-GL/1 plotter (vinyl cutter or pen plotter) behind a serial line: a small receive
//! buffer that loses bytes when overrun, XON/XOFF flow control, the `ESC.B`/`ESC.L` buffer
//! queries and `ESC.K` abort, its own HP-GL interpreter, and a pen trace.
//!
//! Independent of the HP-GL writer and the sender (it shares no code with them): it is the
//! check that what they produce draws the pattern and never overruns the device.

pub mod interp;
pub mod plotter;
pub mod pty;

pub use interp::{Interpreter, PenSegment};
pub use plotter::{Plotter, PlotterConfig, PlotterStats};
pub use pty::HpglPtySim;

/// XON (DC1): the device has room again.
pub const XON: u8 = 0x11;
/// XOFF (DC3): the device's buffer is nearly full.
pub const XOFF: u8 = 0x13;
/// Plotter units per millimetre.
pub const UNITS_PER_MM: f64 = 40.0;

/// The pen trace as an SVG in mm (pen-down segments, y up flipped into SVG's y down).
pub fn trace_svg(segments: &[PenSegment]) -> String {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for s in segments {
        for p in [s.from, s.to] {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    if !lo[0].is_finite() {
        lo = [0.0; 2];
        hi = [1.0; 2];
    }
    let (w, h) = (hi[0] - lo[0] + 10.0, hi[1] - lo[1] + 10.0);
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w:.3}mm\" height=\"{h:.3}mm\" viewBox=\"0 0 {w:.3} {h:.3}\">\n<g fill=\"none\" stroke=\"#ff0000\" stroke-width=\"0.1\">\n"
    );
    for seg in segments {
        let m = |p: [f64; 2]| (p[0] - lo[0] + 5.0, h - (p[1] - lo[1] + 5.0));
        let (a, b) = (m(seg.from), m(seg.to));
        s.push_str(&format!(
            "<line x1=\"{:.3}\" y1=\"{:.3}\" x2=\"{:.3}\" y2=\"{:.3}\"/>\n",
            a.0, a.1, b.0, b.1
        ));
    }
    s.push_str("</g>\n</svg>\n");
    s
}
