//! Parses the written G-code back with an independent little interpreter and checks it against
//! the drawing: every line within GRBL's rules, all motion inside the work area, and the traced
//! tool-on geometry within tolerance of the drawing (Hausdorff distance both ways).

use flatcut_gcode::{GcodeOptions, Profile, ToolKind, frame_job, plan};
use flatcut_geom::DVec2;
use flatcut_pattern::{Drawing, Layer, Stroke, StrokeKind};

/// Words GRBL 1.1 accepts that we may write.
const ALLOWED_G: [&str; 9] = ["0", "1", "2", "3", "4", "17", "21", "90", "94"];
const ALLOWED_M: [&str; 6] = ["2", "3", "4", "5", "8", "9"];

#[derive(Default)]
struct Trace {
    /// Tool-on polylines (densely sampled), machine coordinates.
    on: Vec<Vec<DVec2>>,
    max_xy: DVec2,
    min_xy: DVec2,
}

fn interpret(gcode: &str, kind: ToolKind, pen_down_s: f64) -> Trace {
    let mut t = Trace {
        min_xy: DVec2::splat(f64::INFINITY),
        max_xy: DVec2::splat(f64::NEG_INFINITY),
        ..Default::default()
    };
    let (mut x, mut y, mut z, mut s) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut spindle = false;
    let mut cur: Vec<DVec2> = Vec::new();
    assert!(gcode.ends_with("M2\n"), "job must end with M2");
    assert!(!gcode.contains('\r'), "\\n line endings only");
    for (n, raw) in gcode.lines().enumerate() {
        assert!(raw.len() <= 70, "line {} too long: {raw}", n + 1);
        assert!(!raw.contains('%'), "line {}: % is rejected by GRBL", n + 1);
        let code = match raw.find('(') {
            Some(i) => &raw[..i],
            None => raw,
        };
        let mut words: Vec<(char, f64, String)> = Vec::new();
        for w in code.split_whitespace() {
            let (l, v) = w.split_at(1);
            let c = l.chars().next().unwrap();
            assert!(
                "GMXYZIJFSP".contains(c),
                "line {}: unsupported word {w}",
                n + 1
            );
            match c {
                'G' => assert!(ALLOWED_G.contains(&v), "line {}: G{v}", n + 1),
                'M' => assert!(ALLOWED_M.contains(&v), "line {}: M{v}", n + 1),
                _ => {}
            }
            words.push((
                c,
                v.parse()
                    .unwrap_or_else(|_| panic!("line {}: bad number {w}", n + 1)),
                v.to_string(),
            ));
        }
        let get = |c: char| words.iter().find(|w| w.0 == c).map(|w| w.1);
        if let Some(v) = get('S') {
            s = v;
        }
        if let Some(m) = words.iter().find(|w| w.0 == 'M') {
            match m.2.as_str() {
                "3" | "4" => spindle = true,
                "5" | "2" => spindle = false,
                _ => {}
            }
        }
        let g = words
            .iter()
            .find(|w| w.0 == 'G' && ["0", "1", "2", "3"].contains(&w.2.as_str()))
            .map(|w| w.2.clone());
        let (nx, ny, nz) = (
            get('X').unwrap_or(x),
            get('Y').unwrap_or(y),
            get('Z').unwrap_or(z),
        );
        let tool_on = |g: &str, z: f64, s: f64| match kind {
            ToolKind::Pen => spindle && s >= pen_down_s - 1e-9 && g != "0",
            ToolKind::Knife => z < 0.0 && g != "0",
            ToolKind::Laser => spindle && s > 0.0 && g != "0",
        };
        if let Some(g) = g {
            let mut pts = Vec::new();
            let from = DVec2::new(x, y);
            let to = DVec2::new(nx, ny);
            if g == "2" || g == "3" {
                let c = from + DVec2::new(get('I').unwrap(), get('J').unwrap());
                // GRBL error:33: end radius must match the start radius.
                let (r0, r1) = (from.distance(c), to.distance(c));
                assert!(
                    (r0 - r1).abs() <= 0.005 || (r0 - r1).abs() <= 0.001 * r0,
                    "line {}: arc radius mismatch {r0} {r1}",
                    n + 1
                );
                pts = flatcut_gcode::arcs::sample_arc(from, to, c, g == "3", 0.001);
            } else {
                for k in 1..=20 {
                    pts.push(from + (to - from) * (k as f64 / 20.0));
                }
            }
            for p in &pts {
                t.min_xy = t.min_xy.min(*p);
                t.max_xy = t.max_xy.max(*p);
            }
            if tool_on(&g, nz, s) {
                if cur.is_empty() {
                    cur.push(from);
                }
                for q in pts {
                    if cur.last().is_none_or(|l: &DVec2| l.distance(q) > 1e-9) {
                        cur.push(q);
                    }
                }
            } else if !cur.is_empty() {
                t.on.push(std::mem::take(&mut cur));
            }
            x = nx;
            y = ny;
            z = nz;
        } else if (nz - z).abs() > 0.0 {
            z = nz;
        }
        if !tool_on("1", z, s) && !cur.is_empty() {
            t.on.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        t.on.push(cur);
    }
    t
}

fn dist_to_polyline(p: DVec2, poly: &[DVec2]) -> f64 {
    poly.windows(2)
        .map(|w| {
            let (a, b) = (w[0], w[1]);
            let ab = b - a;
            let t = if ab.length_squared() > 0.0 {
                ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            p.distance(a + ab * t)
        })
        .fold(f64::INFINITY, f64::min)
}

fn hausdorff(a: &[Vec<DVec2>], b: &[Vec<DVec2>]) -> f64 {
    let one = |a: &[Vec<DVec2>], b: &[Vec<DVec2>]| {
        a.iter()
            .flatten()
            .map(|p| {
                b.iter()
                    .map(|q| dist_to_polyline(*p, q))
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max)
    };
    one(a, b).max(one(b, a))
}

fn sample() -> Drawing {
    let circle: Vec<DVec2> = (0..120)
        .map(|k| {
            DVec2::new(100.0, 80.0)
                + DVec2::from_angle(k as f64 * std::f64::consts::TAU / 120.0) * 40.0
        })
        .collect();
    let hole: Vec<DVec2> = (0..48)
        .map(|k| {
            DVec2::new(100.0, 80.0)
                + DVec2::from_angle(k as f64 * std::f64::consts::TAU / 48.0) * 5.0
        })
        .collect();
    let square = vec![
        DVec2::new(10.0, 10.0),
        DVec2::new(50.0, 10.0),
        DVec2::new(50.0, 50.0),
        DVec2::new(10.0, 50.0),
    ];
    let wave: Vec<DVec2> = (0..=100)
        .map(|k| DVec2::new(20.0 + k as f64 * 1.5, 150.0 + 10.0 * (k as f64 * 0.1).sin()))
        .collect();
    let st = |layer, points: Vec<DVec2>, closed, outer, id: &str| Stroke {
        layer,
        points,
        closed,
        piece: Some(0),
        kind: if outer {
            StrokeKind::Boundary
        } else {
            StrokeKind::Internal
        },
        id: id.into(),
    };
    Drawing::from_strokes(vec![
        st(Layer::Cut, circle, true, true, "disc/cut"),
        st(Layer::Cut, hole, true, false, "disc/hole"),
        st(Layer::Draw, wave, false, false, "disc/grain"),
        st(Layer::Cut, square, true, true, "square/cut"),
        st(
            Layer::Engrave,
            vec![DVec2::new(30.0, 120.0), DVec2::new(60.0, 120.0)],
            false,
            false,
            "disc/label",
        ),
    ])
}

fn expected(d: &Drawing, p: &Profile) -> Vec<Vec<DVec2>> {
    d.strokes
        .iter()
        .filter(|s| p.layer(s.layer).enabled)
        .map(|s| {
            let mut pts: Vec<DVec2> = s.points.iter().map(|q| p.to_machine(*q)).collect();
            if s.closed {
                pts.push(pts[0]);
            }
            pts
        })
        .collect()
}

#[test]
fn pen_job_traces_the_drawing_within_tolerance() {
    let p = Profile::pen();
    let d = sample();
    let plan = plan(&d, &p, &GcodeOptions::default()).unwrap();
    let g = plan.to_gcode();
    let t = interpret(&g, ToolKind::Pen, p.pen.as_ref().unwrap().down_s);
    assert_eq!(t.on.len(), 5, "one pen-down path per stroke");
    let h = hausdorff(&t.on, &expected(&d, &p));
    assert!(h <= p.arc_tolerance_mm + 1e-3, "Hausdorff {h}");
    assert!(t.min_xy.x >= 0.0 && t.min_xy.y >= 0.0 && t.max_xy.x <= 420.0 && t.max_xy.y <= 300.0);
    // Arcs were fitted: the 120-gon is a handful of arcs, far fewer lines than points.
    assert!(
        g.lines()
            .filter(|l| l.starts_with("G2") || l.starts_with("G3"))
            .count()
            >= 2
    );
    assert!(plan.summary().lines < 150, "{} lines", plan.summary().lines);
    assert!(g.starts_with("(flatcut job)\n"));
    assert!(g.contains("G21 G90"));
}

#[test]
fn layer_order_is_engrave_draw_inner_cuts_outer_cuts() {
    let plan = plan(&sample(), &Profile::pen(), &GcodeOptions::default()).unwrap();
    let ids: Vec<&str> = plan.paths.iter().map(|p| p.id.as_str()).collect();
    assert_eq!(ids[0], "disc/label");
    assert_eq!(ids[1], "disc/grain");
    assert_eq!(ids[2], "disc/hole");
    assert!(ids[3..].contains(&"disc/cut") && ids[3..].contains(&"square/cut"));
}

#[test]
fn laser_job_uses_dynamic_power_passes_and_turns_off_on_travel() {
    let p = Profile::laser();
    let d = sample();
    let g = plan(&d, &p, &GcodeOptions::default()).unwrap().to_gcode();
    assert!(g.contains("M4 S0\n") && g.contains("M8\n") && g.contains("M9\n"));
    for l in g.lines().filter(|l| l.starts_with("G0 X")) {
        assert!(l.ends_with(" S0"), "travel with laser on: {l}");
    }
    // Cut layer at 90 % of $30 = 1000, two passes of each cut.
    assert!(g.contains("S900.000"));
    let t = interpret(&g, ToolKind::Laser, 0.0);
    // A second pass of a closed loop starts where the first ended: one continuous burn each.
    assert_eq!(t.on.len(), 5);
    let burned: f64 =
        t.on.iter()
            .map(|p| p.windows(2).map(|w| w[0].distance(w[1])).sum::<f64>())
            .sum();
    let want = 2.0 * d.length(Layer::Cut) + d.length(Layer::Draw) + d.length(Layer::Engrave);
    assert!((burned - want).abs() < 0.01 * want, "{burned} vs {want}");
    assert!(hausdorff(&t.on, &expected(&d, &p)) <= p.arc_tolerance_mm + 1e-3);
}

#[test]
fn knife_blade_tip_follows_the_drawing() {
    let p = Profile::knife();
    let d = sample();
    let plan = plan(&d, &p, &GcodeOptions::default()).unwrap();
    // The knife profile runs only the cut layer.
    assert!(plan.paths.iter().all(|tp| tp.layer == Layer::Cut));
    let g = plan.to_gcode();
    let t = interpret(&g, ToolKind::Knife, 0.0);
    assert_eq!(t.on.len(), 3);
    // Simulate the trailing blade tip along each axis path and compare with the cut strokes.
    let r = p.knife.as_ref().unwrap().blade_offset_mm;
    let tips: Vec<Vec<DVec2>> =
        t.on.iter()
            .map(|axis| {
                let d0 = (axis[1] - axis[0]).normalize();
                let mut tip = axis[0] - d0 * r;
                let mut out = vec![tip];
                for &a in axis {
                    let v = a - tip;
                    if v.length() > r {
                        tip = a - v.normalize() * r;
                    }
                    out.push(tip);
                }
                out
            })
            .collect();
    let want: Vec<Vec<DVec2>> = expected(&d, &p)
        .into_iter()
        .filter(|s| s.len() > 2)
        .collect();
    // One way: every tip point lies on the outline (the overcut retraces it).
    let worst = tips
        .iter()
        .flatten()
        .map(|q| {
            want.iter()
                .map(|w| dist_to_polyline(*q, w))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max);
    assert!(worst < 0.05, "blade tip strays {worst} mm from the outline");
}

#[test]
fn same_input_same_bytes_and_frame_job() {
    let p = Profile::pen();
    let a = plan(&sample(), &p, &GcodeOptions::default()).unwrap();
    let b = plan(&sample(), &p, &GcodeOptions::default()).unwrap();
    assert_eq!(a.to_gcode(), b.to_gcode());
    let f = frame_job(a.bbox(), &p);
    let t = interpret(&f, ToolKind::Pen, 1000.0);
    assert!(t.on.is_empty(), "frame runs with the tool off");
    assert!(
        (t.max_xy.x - a.bbox().max.x).abs() < 1e-3
            && (t.min_xy.y - a.bbox().min.y.min(0.0)).abs() < 1e-3
    );
}

#[test]
fn outside_the_work_area_is_refused_with_the_stroke_named() {
    let mut d = sample();
    d.strokes[3].points[1].x = 900.0;
    let e = plan(&d, &Profile::pen(), &GcodeOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("square/cut") && e.contains("work area"), "{e}");
    let e = plan(
        &Drawing::default(),
        &Profile::pen(),
        &GcodeOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("nothing to do"), "{e}");
}

#[test]
fn summary_estimates_time_and_lengths() {
    let plan = plan(&sample(), &Profile::pen(), &GcodeOptions::default()).unwrap();
    let s = plan.summary();
    let d = sample();
    let expect_cut: f64 = Layer::ALL.iter().map(|l| d.length(*l)).sum();
    assert!(
        (s.cut_length_mm - expect_cut).abs() < 1e-3 * expect_cut,
        "{} vs {expect_cut}",
        s.cut_length_mm
    );
    // Time at least cut length / feed plus the pen dwells.
    assert!(s.est_time_s > s.cut_length_mm / 50.0);
    assert!(s.travel_length_mm > 0.0);
}
