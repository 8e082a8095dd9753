//! HP-GL streaming against the simulated plotter on a pseudo-terminal: a job many times larger
//! than the device's receive buffer arrives whole under XON/XOFF (and under `ESC.B` queries),
//! the device's pen traces exactly the job's pen-down moves, and an abort lifts the tool.

use std::sync::atomic::AtomicBool;
use std::time::Duration;

use flatcut_firmware_sim::hpgl::{HpglPtySim, PlotterConfig};
use flatcut_grbl::hpgl::{HpglFlow, HpglStreamOptions, stream_hpgl};

/// A job of `n` squares of pen-down moves (plotter units), each drawn once.
fn job(n: usize) -> (String, Vec<([i64; 2], [i64; 2])>) {
    let mut s = String::from("IN;\nSP1;\nVS40;\n");
    let mut segs = Vec::new();
    for k in 0..n {
        let (x, y) = (400 + 37 * (k as i64 % 40), 400 + 53 * (k as i64 / 40));
        let c = [
            [x, y],
            [x + 400, y],
            [x + 400, y + 300],
            [x, y + 300],
            [x, y],
        ];
        s.push_str(&format!("PU{},{};\nPD", x, y));
        for (i, p) in c[1..].iter().enumerate() {
            s.push_str(&format!(
                "{}{},{}",
                if i == 0 { "" } else { "," },
                p[0],
                p[1]
            ));
            segs.push((c[i], *p));
        }
        s.push_str(";\n");
    }
    s.push_str("PU0,0;\nSP0;\n");
    (s, segs)
}

fn device(buffer_query: bool) -> PlotterConfig {
    PlotterConfig {
        buffer: 512,
        xoff_free: 192,
        xon_free: 384,
        // slower than the 38400-baud link: the buffer fills and XOFF must hold the sender
        byte_time_s: 5e-4,
        speed_mm_s: 2000.0,
        buffer_query,
    }
}

fn run(buffer_query: bool) {
    let (text, segs) = job(300);
    assert!(text.len() > 20 * 512, "job {} bytes", text.len());
    let baud = 38_400;
    let sim = HpglPtySim::spawn(device(buffer_query), baud, 1.0).unwrap();
    let mut port = flatcut_grbl::open_port(&sim.path().display().to_string(), baud).unwrap();
    let opts = HpglStreamOptions::new(HpglFlow::XonXoff, buffer_query, baud);
    let abort = AtomicBool::new(false);
    let mut held = 0;
    let report = stream_hpgl(&mut port, text.as_bytes(), &opts, &abort, &mut |p| {
        held += usize::from(p.held)
    })
    .unwrap();
    assert!(sim.wait_idle(Duration::from_secs(60)));
    let (trace, st) = sim.stop();
    eprintln!(
        "HP-GL stream (ESC.B queries: {buffer_query}): {} bytes sent, device received {}, lost {}, buffer high-water {} of 512, XOFF {} / XON {} sent, {} XOFF / {} XON seen by the sender, {} queries, {:.2} s",
        report.bytes_sent,
        st.bytes_received,
        st.bytes_lost,
        st.high_water,
        st.xoff_sent,
        st.xon_sent,
        report.xoff_received,
        report.xon_received,
        report.queries,
        report.elapsed_s
    );
    assert_eq!(st.bytes_lost, 0, "no byte lost");
    assert!(st.high_water <= 512);
    if buffer_query {
        assert_eq!(report.device_buffer, Some(512));
        assert!(report.queries > 10);
    } else {
        // Every XOFF the device sent while bytes were still to come reached the sender; the
        // device may send one more after the last byte, when the sender has stopped listening.
        assert!(
            st.xoff_sent > 0 && report.xoff_received + 1 >= st.xoff_sent,
            "XOFF used: {} sent, {} seen",
            st.xoff_sent,
            report.xoff_received
        );
    }
    assert_eq!(report.bytes_sent, text.len());
    // Every pen-down move, once, in order (trace in mm, 40 units per mm).
    assert_eq!(trace.len(), segs.len());
    for (t, (a, b)) in trace.iter().zip(&segs) {
        let mm = |q: [i64; 2]| [q[0] as f64 / 40.0, q[1] as f64 / 40.0];
        assert_eq!((t.from, t.to), (mm(*a), mm(*b)));
    }
}

#[test]
fn large_job_under_xon_xoff_loses_no_byte() {
    run(false);
}

#[test]
fn large_job_under_buffer_queries_loses_no_byte() {
    run(true);
}

#[test]
fn abort_clears_the_device_and_lifts_the_pen() {
    let (text, _) = job(300);
    let baud = 38_400;
    let sim = HpglPtySim::spawn(device(false), baud, 1.0).unwrap();
    let mut port = flatcut_grbl::open_port(&sim.path().display().to_string(), baud).unwrap();
    let opts = HpglStreamOptions::new(HpglFlow::XonXoff, false, baud);
    let abort = AtomicBool::new(false);
    let e = stream_hpgl(&mut port, text.as_bytes(), &opts, &abort, &mut |p| {
        if p.sent > 2000 {
            abort.store(true, std::sync::atomic::Ordering::SeqCst);
        }
    })
    .unwrap_err();
    assert!(e.to_string().contains("aborted"), "{e}");
    std::thread::sleep(Duration::from_millis(300));
    let (_, st) = sim.stop();
    assert_eq!(st.aborts, 1);
}
