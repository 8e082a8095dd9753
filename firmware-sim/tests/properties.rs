//! Property tests: arbitrary bytes never break the controller, and arbitrary straight-line programs are traced
//! continuously and end where they were sent.

use flatcut_firmware_sim::{BANNER, Grbl, SimConfig};
use proptest::prelude::*;

/// True when `l` is a line GRBL can send.
fn well_formed(l: &str) -> bool {
    l == "ok"
        || l.strip_prefix("error:")
            .is_some_and(|n| n.parse::<u8>().is_ok())
        || l.strip_prefix("ALARM:")
            .is_some_and(|n| n.parse::<u8>().is_ok())
        || (l.starts_with('<') && l.ends_with('>'))
        || (l.starts_with('[') && l.ends_with(']'))
        || l.starts_with('$')
        || l.starts_with('>')
        || l == BANNER.trim()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_bytes_give_well_formed_answers(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let mut g = Grbl::new(&SimConfig::default().with_instant_motion(true));
        for chunk in bytes.chunks(16) {
            g.receive_all(chunk);
            g.tick(0.05);
        }
        g.receive(0x18);
        g.tick(0.05);
        let out = String::from_utf8_lossy(&g.take_output()).into_owned();
        for l in out.split("\r\n").filter(|l| !l.is_empty()) {
            prop_assert!(well_formed(l), "{l:?}");
        }
        let p = g.machine_position();
        prop_assert!(p.iter().all(|v| v.is_finite()));
        prop_assert!(g.stats().max_rx_fill <= 128);
    }

    #[test]
    fn straight_programs_trace_continuously(
        pts in proptest::collection::vec((-50i32..50, -50i32..50, 1u32..40), 1..25)
    ) {
        let mut g = Grbl::new(&SimConfig::default().with_time_scale(1.0));
        g.take_output();
        let mut text = String::new();
        for (x, y, f) in &pts {
            text.push_str(&format!("G1 X{} Y{} F{}\n", *x as f64 * 0.5, *y as f64 * 0.5, f * 100));
        }
        // Send-response, so that nothing overflows.
        for line in text.lines() {
            g.receive_all(line.as_bytes());
            g.receive(b'\n');
            while !String::from_utf8(g.take_output()).unwrap().contains("ok") {
                g.tick(0.01);
            }
        }
        g.run_until_idle(10_000.0);
        let tr = g.trace();
        let last = pts.last().unwrap();
        prop_assert_eq!(g.machine_position(), [last.0 as f64 * 0.5, last.1 as f64 * 0.5, 0.0]);
        let mut prev = [0.0; 3];
        let mut t = 0.0;
        for s in tr {
            prop_assert_eq!(s.from, prev);
            prop_assert!(s.t_start >= t - 1e-9 && s.t_end > s.t_start);
            // Never faster than the programmed feed or the axis limits allow.
            let len = ((s.to[0] - s.from[0]).powi(2) + (s.to[1] - s.from[1]).powi(2)).sqrt();
            let v_max = (s.feed / 60.0).min(500.0 / 60.0 * 2f64.sqrt());
            prop_assert!(len / (s.t_end - s.t_start) <= v_max * (1.0 + 1e-9), "{s:?}");
            prev = s.to;
            t = s.t_end;
        }
    }
}
