//! Round trips through a real pseudo-terminal opened with the `serialport` crate, as a sender would.

use flatcut_firmware_sim::{PtySim, SimConfig};
use std::io::Write;
use std::time::{Duration, Instant};

/// Reads until `pat` appears in the accumulated text or the timeout passes.
fn read_until(
    port: &mut dyn serialport::SerialPort,
    acc: &mut String,
    pat: &str,
    timeout: Duration,
) -> bool {
    let t0 = Instant::now();
    let mut buf = [0u8; 256];
    while t0.elapsed() < timeout {
        if acc.contains(pat) {
            return true;
        }
        match port.read(&mut buf) {
            Ok(n) => acc.push_str(&String::from_utf8_lossy(&buf[..n])),
            Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
            Err(e) => panic!("read: {e}"),
        }
    }
    acc.contains(pat)
}

#[test]
fn serialport_round_trip() {
    let sim = PtySim::spawn(SimConfig {
        time_scale: 20.0,
        ..SimConfig::default()
    })
    .unwrap();
    let mut port = serialport::new(sim.path().to_string_lossy(), 115_200)
        .timeout(Duration::from_millis(20))
        .open()
        .unwrap();
    let mut acc = String::new();
    assert!(
        read_until(
            port.as_mut(),
            &mut acc,
            "Grbl 1.1h ['$' for help]\r\n",
            Duration::from_secs(3)
        ),
        "{acc:?}"
    );
    acc.clear();
    port.write_all(b"$I\n").unwrap();
    assert!(
        read_until(port.as_mut(), &mut acc, "ok\r\n", Duration::from_secs(3)),
        "{acc:?}"
    );
    assert!(acc.contains("[OPT:V,15,128]"), "{acc:?}");
    acc.clear();
    port.write_all(b"G1 X5 Y5 F3000\n").unwrap();
    assert!(
        read_until(port.as_mut(), &mut acc, "ok\r\n", Duration::from_secs(3)),
        "{acc:?}"
    );
    acc.clear();
    port.write_all(b"?").unwrap();
    assert!(
        read_until(port.as_mut(), &mut acc, ">\r\n", Duration::from_secs(3)),
        "{acc:?}"
    );
    assert!(
        acc.starts_with("<Run|MPos:") || acc.starts_with("<Idle|MPos:"),
        "{acc:?}"
    );
    // Wait for the move to finish (about 1.6 s simulated at 20x).
    let t0 = Instant::now();
    while sim.trace().is_empty() && t0.elapsed() < Duration::from_secs(3) {
        std::thread::sleep(Duration::from_millis(10));
    }
    assert_eq!(sim.lines_received(), 2);
    drop(port);
    let report = sim.stop();
    assert_eq!(report.trace.len(), 1);
    assert_eq!(report.trace[0].to, [5.0, 5.0, 0.0]);
    assert_eq!(report.stats.oks, 2);
}

fn open(path: &std::path::Path) -> Box<dyn serialport::SerialPort> {
    serialport::new(path.to_string_lossy(), 115_200)
        .timeout(Duration::from_millis(20))
        .open()
        .unwrap()
}

#[test]
fn link_trace_files_and_reopen() {
    let dir = std::env::temp_dir().join(format!("fw-sim-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (jsonl, svg, link) = (dir.join("t.jsonl"), dir.join("t.svg"), dir.join("grbl"));
    let sim = PtySim::spawn(SimConfig {
        instant_motion: true,
        trace_jsonl: Some(jsonl.clone()),
        trace_svg: Some(svg.clone()),
        ..SimConfig::default()
    })
    .unwrap();
    sim.link(&link).unwrap();
    let mut port = open(&link);
    let mut acc = String::new();
    assert!(read_until(
        port.as_mut(),
        &mut acc,
        "for help]\r\n",
        Duration::from_secs(3)
    ));
    port.write_all(b"M3 S1000\nG1 X10 F1000\n").unwrap();
    acc.clear();
    assert!(
        read_until(
            port.as_mut(),
            &mut acc,
            "ok\r\nok\r\n",
            Duration::from_secs(3)
        ),
        "{acc:?}"
    );
    drop(port);
    // A second client opens the same device: like the DTR pulse of an Uno, the open resets the board, so it
    // reads one fresh banner (nothing stale) and the position restarts at zero.
    let mut port = open(&link);
    acc.clear();
    assert!(
        read_until(
            port.as_mut(),
            &mut acc,
            "for help]\r\n",
            Duration::from_secs(3)
        ),
        "{acc:?}"
    );
    assert_eq!(acc, "\r\nGrbl 1.1h ['$' for help]\r\n");
    // The reset also forgot the feed rate.
    port.write_all(b"G1 Y10\n").unwrap();
    acc.clear();
    assert!(
        read_until(
            port.as_mut(),
            &mut acc,
            "error:22\r\n",
            Duration::from_secs(3)
        ),
        "{acc:?}"
    );
    port.write_all(b"G1 Y10 F1000\n").unwrap();
    assert!(
        read_until(port.as_mut(), &mut acc, "ok\r\n", Duration::from_secs(3)),
        "{acc:?}"
    );
    acc.clear();
    port.write_all(b"?").unwrap();
    assert!(
        read_until(port.as_mut(), &mut acc, ">\r\n", Duration::from_secs(3)),
        "{acc:?}"
    );
    assert!(acc.starts_with("<Idle|MPos:0.000,10.000,0.000|"), "{acc:?}");
    assert_eq!(sim.connects(), 2);
    drop(port);
    let report = sim.stop();
    assert!(!link.exists(), "the link is removed at stop");
    assert_eq!(report.trace.len(), 2);
    let text = std::fs::read_to_string(&jsonl).unwrap();
    assert_eq!(text.lines().count(), 2);
    assert!(text.lines().next().unwrap().contains(r#""motion":"G1""#));
    let svg_text = std::fs::read_to_string(&svg).unwrap();
    assert!(svg_text.starts_with("<svg") && svg_text.contains("polyline"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn hangup_fault_closes_the_device() {
    let sim = PtySim::spawn(SimConfig {
        instant_motion: true,
        faults: flatcut_firmware_sim::Faults {
            hangup_at_line: Some(2),
            ..Default::default()
        },
        ..SimConfig::default()
    })
    .unwrap();
    let mut port = open(sim.path());
    port.write_all(b"G0 X1\nG0 X2\n").unwrap();
    let t0 = Instant::now();
    let mut buf = [0u8; 64];
    let mut broken = false;
    while t0.elapsed() < Duration::from_secs(3) {
        match port.read(&mut buf) {
            Ok(_) => {}
            Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
            Err(e) => {
                eprintln!("client error after hang-up: {e:?}");
                broken = true;
                break;
            }
        }
    }
    assert!(broken, "the client sees the hang-up");
    assert_eq!(sim.lines_received(), 2);
    assert!(sim.hung_up());
    drop(port);
    // The device comes back like a re-plugged USB adapter: new path, power-up banner, position zero.
    let t0 = Instant::now();
    while sim.replugs() == 0 && t0.elapsed() < Duration::from_secs(5) {
        std::thread::sleep(Duration::from_millis(20));
    }
    assert_eq!(sim.replugs(), 1);
    assert!(!sim.hung_up());
    let mut port = open(&sim.current_path());
    let mut acc = String::new();
    assert!(
        read_until(
            port.as_mut(),
            &mut acc,
            "for help]\r\n",
            Duration::from_secs(3)
        ),
        "{acc:?}"
    );
    port.write_all(b"?").unwrap();
    assert!(
        read_until(port.as_mut(), &mut acc, ">\r\n", Duration::from_secs(3)),
        "{acc:?}"
    );
    assert!(acc.contains("<Idle|MPos:0.000,0.000,0.000|"), "{acc:?}");
}

#[test]
fn response_delay_and_overflow_through_the_pty() {
    let sim = PtySim::spawn(SimConfig {
        faults: flatcut_firmware_sim::Faults {
            response_delay_ms: 150,
            ..Default::default()
        },
        ..SimConfig::default()
    })
    .unwrap();
    let mut port = open(sim.path());
    let mut acc = String::new();
    assert!(read_until(
        port.as_mut(),
        &mut acc,
        "for help]\r\n",
        Duration::from_secs(3)
    ));
    acc.clear();
    let t0 = Instant::now();
    port.write_all(b"G4 P0\n").unwrap();
    assert!(read_until(
        port.as_mut(),
        &mut acc,
        "ok\r\n",
        Duration::from_secs(3)
    ));
    let dt = t0.elapsed();
    assert!(dt >= Duration::from_millis(150), "{dt:?}");
    // 200 lines at once, no flow control: the device drops what does not fit.
    let text: String = (0..200).map(|i| format!("G1 X{} F200\n", i % 2)).collect();
    port.write_all(text.as_bytes()).unwrap();
    std::thread::sleep(Duration::from_millis(800));
    let st = sim.stats();
    assert!(st.bytes_dropped_overflow > 1000, "{st:?}");
    assert!(st.max_rx_fill == 128, "{st:?}");
    drop(port);
    let report = sim.stop();
    assert!(report.stats.lines_received < 60, "{:?}", report.stats);
}

#[test]
fn character_counting_through_the_pty_loses_nothing() {
    let sim = PtySim::spawn(SimConfig {
        time_scale: 50.0,
        ..SimConfig::default()
    })
    .unwrap();
    let mut port = open(sim.path());
    let mut acc = String::new();
    assert!(read_until(
        port.as_mut(),
        &mut acc,
        "for help]\r\n",
        Duration::from_secs(3)
    ));
    acc.clear();
    let lines: Vec<String> = (0..120)
        .map(|i| format!("G1X{}Y{}F2000", i % 9, (i * 7) % 5))
        .collect();
    let mut in_flight: std::collections::VecDeque<usize> = Default::default();
    let (mut next, mut answered, mut errors) = (0, 0, 0);
    let t0 = Instant::now();
    let mut buf = [0u8; 256];
    while answered < lines.len() && t0.elapsed() < Duration::from_secs(20) {
        while next < lines.len() && in_flight.iter().sum::<usize>() + lines[next].len() < 128 {
            port.write_all(format!("{}\n", lines[next]).as_bytes())
                .unwrap();
            in_flight.push_back(lines[next].len() + 1);
            next += 1;
        }
        match port.read(&mut buf) {
            Ok(n) => acc.push_str(&String::from_utf8_lossy(&buf[..n])),
            Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
            Err(e) => panic!("{e}"),
        }
        while let Some(i) = acc.find("\r\n") {
            let l: String = acc.drain(..i + 2).collect();
            if l.starts_with("ok") || l.starts_with("error:") {
                errors += usize::from(l.starts_with("error:"));
                in_flight.pop_front();
                answered += 1;
            }
        }
    }
    assert_eq!((answered, errors), (lines.len(), 0));
    let st = sim.stats();
    assert_eq!(st.bytes_dropped_overflow, 0, "{st:?}");
    assert!(st.max_rx_fill <= 128);
    assert!(
        st.max_planner_fill == 15,
        "the planner filled: the stream was limited by motion, {st:?}"
    );
    drop(port);
    sim.stop();
}

/// Writes `cmd` and reads until `pat`, returning what came.
fn ask(port: &mut dyn serialport::SerialPort, cmd: &[u8], pat: &str) -> String {
    port.write_all(cmd).unwrap();
    let mut acc = String::new();
    assert!(
        read_until(port, &mut acc, pat, Duration::from_secs(3)),
        "{cmd:?}: {acc:?}"
    );
    acc
}

/// Issue 39, item 2: `--boot-ms`: after the reset of opening the port the banner comes that much later, as from
/// a bootloader, and what arrives meanwhile is lost (a `$I` sent then gets no answer).
#[test]
fn the_bootloader_delays_the_banner_and_loses_what_comes_meanwhile() {
    let sim = PtySim::spawn(SimConfig::default().with_boot_ms(1200)).unwrap();
    let t0 = Instant::now();
    let mut port = open(sim.path());
    std::thread::sleep(Duration::from_millis(200));
    port.write_all(b"$I\n").unwrap();
    let mut acc = String::new();
    assert!(read_until(
        port.as_mut(),
        &mut acc,
        "for help]\r\n",
        Duration::from_secs(5)
    ));
    let waited = t0.elapsed();
    assert!(
        waited >= Duration::from_millis(1150) && waited < Duration::from_millis(2500),
        "{waited:?}"
    );
    // Only the banner: the `$I` went to the bootloader.
    std::thread::sleep(Duration::from_millis(300));
    read_until(port.as_mut(), &mut acc, "[VER:", Duration::from_millis(200));
    assert_eq!(acc, "\r\nGrbl 1.1h ['$' for help]\r\n");
    assert!(ask(port.as_mut(), b"$I\n", "ok\r\n").contains("[VER:1.1h"));
    drop(port);
    assert_eq!(sim.stop().stats.bytes_dropped_boot, 3);
}

/// Issue 39, item 2: a power cycle while no client has the port open (a board with auto-reset off and its own
/// supply, switched off and on) loses the position and the G92 offset, keeps the stored G54 offset, and its
/// banner is heard by nobody: the next client finds a fresh controller that says nothing of it. Without the
/// power cycle, the same reconnect finds everything where it was.
#[test]
fn a_power_cycle_with_no_client_loses_position_and_g92_and_its_banner() {
    let sim = PtySim::spawn(
        SimConfig::default()
            .with_instant_motion(true)
            .with_dtr_reset(false)
            .with_boot_ms(300),
    )
    .unwrap();
    // The board powered up as the simulator started: its banner comes after the boot delay.
    let mut port = open(sim.path());
    let mut acc = String::new();
    assert!(read_until(
        port.as_mut(),
        &mut acc,
        "for help]\r\n",
        Duration::from_secs(3)
    ));
    ask(
        port.as_mut(),
        b"G10 L2 P1 X2\nG0 X10 Y4\nG92 X1 Y1\n",
        "ok\r\nok\r\nok\r\n",
    );
    drop(port);
    let status = |port: &mut dyn serialport::SerialPort| ask(port, b"?", ">\r\n");
    let offsets = |port: &mut dyn serialport::SerialPort| ask(port, b"$#\n", "ok\r\n");
    // A reconnect alone changes nothing.
    let mut port = open(sim.path());
    assert!(
        status(port.as_mut()).starts_with("<Idle|MPos:12.000,4.000,0.000|"),
        "kept"
    );
    assert!(offsets(port.as_mut()).contains("[G92:9.000,3.000,0.000]"));
    drop(port);
    std::thread::sleep(Duration::from_millis(100));
    sim.power_cycle();
    std::thread::sleep(Duration::from_millis(600));
    let mut port = open(sim.path());
    acc = status(port.as_mut());
    assert!(acc.starts_with("<Idle|MPos:0.000,0.000,0.000|"), "{acc:?}");
    acc = offsets(port.as_mut());
    assert!(
        acc.contains("[G54:2.000,0.000,0.000]") && acc.contains("[G92:0.000,0.000,0.000]"),
        "{acc:?}"
    );
    assert!(!acc.contains("Grbl"), "a banner nobody heard: {acc:?}");
    drop(port);
    sim.stop();
}

/// A client that asks for the status the moment it opens the port is answered, however the simulator's loop is
/// scheduled: the open is seen before the byte is answered, and the previous client's close does not throw the
/// new client's byte away. Each round closes one client and opens the next at once (the race is between the
/// watch's events and the byte), on a board with auto-reset disabled, so nothing may be lost.
#[test]
fn a_query_sent_the_instant_a_client_reconnects_is_answered() {
    let sim = PtySim::spawn(
        SimConfig::default()
            .with_instant_motion(true)
            .with_dtr_reset(false),
    )
    .unwrap();
    let mut port = open(sim.path());
    let mut acc = String::new();
    assert!(read_until(
        port.as_mut(),
        &mut acc,
        "for help]\r\n",
        Duration::from_secs(3)
    ));
    for round in 0..600 {
        drop(port);
        port = open(sim.path());
        port.write_all(b"?").unwrap();
        let mut acc = String::new();
        assert!(
            read_until(port.as_mut(), &mut acc, ">\r\n", Duration::from_secs(2)),
            "round {round}: no answer to a status query sent right after opening: {acc:?}"
        );
        assert!(acc.starts_with("<Idle|MPos:"), "round {round}: {acc:?}");
    }
    drop(port);
    sim.stop();
}
