//! HP-GL plotters as devices: the embedded HP-GL plotter opened as a device, a job of squares
//! drawn with the pen held down across instructions (`PD;` then `PA` moves), paused, resumed and
//! stopped. The plotter's own record (its pen strokes, its pen) is the check: the strokes are the
//! job's segments exactly, a pause lifts the pen and draws nothing more until the resume, the
//! resume puts the pen back (the next `PA` draws), and after a stop nothing more is drawn.

use std::time::{Duration, Instant};

use flatcut_device::grbl::hpgl::{HpglError, HpglFlow};
use flatcut_device::{
    Device, DeviceError, DeviceEvent, JobRequest, PlotRequest, PlotterLink, PlotterReport,
    PlotterSimSetup, Subscription, Target,
};

/// Squares of 10 mm (400 plotter units) side by side: each `PU` to its corner, `PD;`, then four
/// `PA` moves with the pen down, then `PU;`.
fn squares(n: i64) -> (String, Vec<([f64; 2], [f64; 2])>) {
    let mut hpgl = String::from("IN;SP1;");
    let mut segs = Vec::new();
    for k in 0..n {
        let x = (k % 10) * 600;
        let y = (k / 10) * 600;
        let c = [
            [x, y],
            [x + 400, y],
            [x + 400, y + 400],
            [x, y + 400],
            [x, y],
        ];
        hpgl.push_str(&format!("PU{},{};PD;", x, y));
        for w in c.windows(2) {
            hpgl.push_str(&format!("PA{},{};", w[1][0], w[1][1]));
            let mm = |p: [i64; 2]| [p[0] as f64 / 40.0, p[1] as f64 / 40.0];
            segs.push((mm(w[0]), mm(w[1])));
        }
        hpgl.push_str("PU;");
    }
    hpgl.push_str("SP0;");
    (hpgl, segs)
}

fn open(speed: f64) -> Device {
    let link = PlotterLink {
        flow: HpglFlow::XonXoff,
        buffer_query: true,
        baud: 19_200,
    };
    Device::open(Target::PlotterSim(PlotterSimSetup { link, speed })).unwrap()
}

/// Waits for a plot event that `want` accepts.
fn until(events: &Subscription, what: &str, want: impl Fn(&DeviceEvent) -> bool) -> DeviceEvent {
    let t0 = Instant::now();
    loop {
        let e = events
            .recv_timeout(Duration::from_secs(60))
            .unwrap_or_else(|| panic!("no event: {what}"));
        if want(&e) {
            return e;
        }
        assert!(t0.elapsed() < Duration::from_secs(60), "never {what}");
    }
}

fn sent_past(e: &DeviceEvent, n: usize) -> bool {
    matches!(e, DeviceEvent::Plot(p) if p.bytes_sent > n)
}

/// Waits until the embedded plotter has drawn everything it received.
fn drained(device: &Device) -> PlotterReport {
    let t0 = Instant::now();
    loop {
        let r = device.plotter_report().unwrap();
        if r.idle {
            return r;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "the plotter never idled"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

fn strokes(r: &PlotterReport) -> Vec<([f64; 2], [f64; 2])> {
    r.strokes.iter().map(|s| (s.from, s.to)).collect()
}

#[test]
fn a_plot_paused_lifts_the_pen_and_resumed_draws_every_stroke_once() {
    let (hpgl, want) = squares(40);
    let device = open(4.0);
    // GRBL's commands and a G-code job are refused with the reason.
    let e = device.unlock().unwrap_err();
    assert!(matches!(e, DeviceError::NotGrbl { .. }), "{e}");
    assert!(e.to_string().contains("HP-GL plotter"), "{e}");
    let gcode = JobRequest::parse("g", "G0 X1\n").unwrap();
    assert!(matches!(
        device.start(gcode),
        Err(DeviceError::NotGrbl { .. })
    ));
    let events = device.subscribe();
    let handle = device
        .start_plot(PlotRequest::new("squares", hpgl.clone()))
        .unwrap();
    assert!(matches!(
        device.start_plot(PlotRequest::new("again", "IN;")),
        Err(DeviceError::Busy { .. })
    ));
    until(&events, "a third sent", |e| sent_past(e, hpgl.len() / 3));
    device.hold().unwrap();
    let DeviceEvent::Plot(p) = until(
        &events,
        "paused",
        |e| matches!(e, DeviceEvent::Plot(p) if p.paused),
    ) else {
        unreachable!()
    };
    // Paused at an instruction boundary.
    assert_eq!(hpgl.as_bytes()[p.bytes_sent - 1], b';', "{p:?}");
    assert!(p.eta.is_none());
    let at_pause = drained(&device);
    assert!(!at_pause.pen_down, "a pause lifts the pen");
    std::thread::sleep(Duration::from_millis(200));
    assert_eq!(
        device.plotter_report().unwrap().strokes.len(),
        at_pause.strokes.len()
    );
    assert!(at_pause.strokes.len() < want.len());
    device.resume().unwrap();
    until(&events, "ended", |e| {
        matches!(e, DeviceEvent::JobFinished { .. })
    });
    let outcome = handle.wait().unwrap();
    assert_eq!(outcome.report.bytes_sent, hpgl.len());
    assert_eq!(outcome.report.pauses, 1);
    let closed = device.close().plotter.unwrap();
    // Every segment of the job once, in order: the pen went back down on the resume.
    assert_eq!(strokes(&closed), want);
    assert_eq!(closed.stats.bytes_lost, 0);
    assert!(!closed.pen_down);
}

#[test]
fn a_plot_stopped_draws_nothing_more_and_ends_stopped() {
    let (hpgl, want) = squares(40);
    let device = open(4.0);
    let events = device.subscribe();
    let handle = device
        .start_plot(PlotRequest::new("squares", hpgl.clone()))
        .unwrap();
    until(&events, "a third sent", |e| sent_past(e, hpgl.len() / 3));
    device.stop().unwrap();
    let ended = until(&events, "ended", |e| {
        matches!(e, DeviceEvent::JobFinished { .. })
    });
    assert!(
        matches!(ended, DeviceEvent::JobFinished { ok: false, .. }),
        "{ended:?}"
    );
    let e = handle.wait().unwrap_err();
    assert!(matches!(e, HpglError::Aborted(..)), "{e}");
    let stopped = drained(&device);
    std::thread::sleep(Duration::from_millis(300));
    let closed = device.close().plotter.unwrap();
    assert_eq!(
        closed.strokes.len(),
        stopped.strokes.len(),
        "drawn after the stop"
    );
    assert!(!closed.pen_down);
    assert_eq!(closed.stats.aborts, 1);
    // What was drawn is the job's beginning, and not all of it.
    let got = strokes(&closed);
    assert!(
        !got.is_empty() && got.len() < want.len(),
        "{} of {}",
        got.len(),
        want.len()
    );
    assert_eq!(got[..], want[..got.len()]);
}
