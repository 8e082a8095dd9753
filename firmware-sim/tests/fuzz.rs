//! A bounded fuzz of firmware-sim's line handling and G-code parser: G-code-like lines (words,
//! numbers, comments, `$` commands, realtime bytes, bytes over 0x7F) fed to the core on virtual
//! time, with a fixed seed and case count so it runs in `cargo test` in seconds, the same way
//! every time. The core must never panic, must answer every line, and must keep its RX buffer
//! within 128 bytes. Inputs that once broke it are kept as regressions.

use flatcut_firmware_sim::{Grbl, SimConfig};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

const ALPHABET: &[u8] = b"GMXYZIJKRFSPLNT0123456789.-+ ();%$=/\t#HCI\xe9\x85?!~\x18";

fn feed(bytes: &[u8]) {
    let mut g = Grbl::new(&SimConfig::default().with_instant_motion(true));
    for chunk in bytes.chunks(32) {
        g.receive_all(chunk);
        g.tick(0.05);
        assert!(g.rx_len() <= 128);
    }
    g.run_until_idle(5.0);
    let out = String::from_utf8_lossy(&g.take_output()).into_owned();
    assert!(!out.contains("NaN") && !out.contains("inf"), "{out}");
}

proptest! {
    #![proptest_config(Config {
        cases: 300,
        rng_seed: RngSeed::Fixed(14),
        failure_persistence: None,
        ..Config::default()
    })]

    #[test]
    fn gcode_parser_never_panics(lines in proptest::collection::vec(
        proptest::collection::vec(proptest::sample::select(ALPHABET), 0..40), 0..12))
    {
        let mut bytes = Vec::new();
        for l in lines {
            bytes.extend_from_slice(&l);
            bytes.push(b'\n');
        }
        feed(&bytes);
    }
}

/// Inputs that broke the simulator once, or could.
#[test]
fn gcode_parser_regressions() {
    for text in [
        &b"G1 X1e38 Y-1e38 F1\n"[..],
        b"G2 X1 Y1 R0.0000001 F10\n",
        b"G91 G1 X99999999 F1\nX99999999\n",
        b"$J=G91 X-1e30 F100\n",
        b"G10 L20 P9 X1\n$#\n",
        b"\xe9\xe9G0X1\n",
        b"G38.2 Z-5 F10\n$X\n",
    ] {
        feed(text);
    }
}
