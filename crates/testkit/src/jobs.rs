//! Jobs for tests, every motion line with a unique text so a trace can be matched line by line.

/// Step of a machine at GRBL's default 250 steps/mm, mm.
pub const STEP_MM: f64 = 0.004;

/// `v` on the 250 steps/mm grid, so simulated positions are exact.
pub fn on_grid(v: f64) -> f64 {
    (v / STEP_MM).round() * STEP_MM
}

/// A pen-plotter job of `n` zig-zag strokes: pen down at the origin, then `G1` to
/// `(i·dx, (i mod 2)·dy)` at `feed` for `i = 1..=n`, pen up. Keep `dx` a multiple of
/// [`STEP_MM`] for exact positions.
pub fn zigzag(n: usize, dx: f64, dy: f64, feed: f64) -> String {
    let mut s = String::from("G21 G90\nG0 Z2\nG0 X0 Y0\nG1 Z-0.5 F300\n");
    for i in 1..=n {
        s.push_str(&format!(
            "G1 X{:.3} Y{} F{feed}\n",
            i as f64 * dx,
            (i % 2) as f64 * dy
        ));
    }
    s.push_str("G0 Z1.5\n");
    s
}

/// A pen-plotter job like the G-code writer's: `pieces` closed 48-gons at different places, each
/// drawn pen down (Z-0.5) after a rapid to its start, pen up (Z2) between pieces. Every drawing
/// line has a unique text.
pub fn pattern_job(pieces: usize) -> String {
    const SIDES: usize = 48;
    let mut s = String::from("G21 G90 G17\nG0 Z2\n");
    for k in 0..pieces {
        let (cx, cy) = (20.0 + 45.0 * k as f64, 30.0 + 7.0 * k as f64);
        let r = 12.0 + 1.5 * k as f64;
        let pts: Vec<(f64, f64)> = (0..SIDES)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / SIDES as f64;
                (on_grid(cx + r * a.cos()), on_grid(cy + r * a.sin()))
            })
            .collect();
        s.push_str(&format!("G0 X{:.3} Y{:.3}\n", pts[0].0, pts[0].1));
        s.push_str(&format!("G1 Z-0.5 F{}\n", 300 + k));
        for (i, p) in pts.iter().enumerate().skip(1) {
            if i == 1 {
                s.push_str(&format!("G1 X{:.3} Y{:.3} F{}\n", p.0, p.1, 2400 + k));
            } else {
                s.push_str(&format!("G1 X{:.3} Y{:.3}\n", p.0, p.1));
            }
        }
        s.push_str(&format!("G1 X{:.3} Y{:.3}\n", pts[0].0, pts[0].1));
        s.push_str("G0 Z2\n");
    }
    s.push_str("G0 X0 Y0\nM2\n");
    s
}

/// Long strokes along Y, each ending at an X with a first decimal digit: losing that digit on
/// the link moves a stroke's end by 0.8 mm across its direction, a line that still parses and
/// runs elsewhere.
pub fn long_strokes(n: usize) -> String {
    let mut s = String::from("G21 G90\nG1 F1200\n");
    for i in 0..n {
        let y = if i % 2 == 0 { 40 } else { 0 };
        s.push_str(&format!("G1 X{:.1} Y{y}\n", 2.8 + 2.0 * i as f64));
    }
    s
}
