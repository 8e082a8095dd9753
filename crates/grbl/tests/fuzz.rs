//! A bounded fuzz of the sender's job parser: G-code-like text from an alphabet rich in the
//! characters that matter (words, numbers, comments, `$`, `%`, realtime bytes, non-ASCII),
//! a fixed seed and case count so it runs in `cargo test` in seconds and the same way every
//! time. A parse may fail, with an error naming the line, but never panic, and a parsed job
//! never carries a NaN or an infinity. Inputs that once broke it are kept below as regressions.

use flatcut_grbl::Job;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

/// Characters G-code lines are made of, and some they should not contain.
const ALPHABET: &[char] = &[
    'G', 'M', 'X', 'Y', 'Z', 'I', 'J', 'K', 'R', 'F', 'S', 'P', 'L', 'N', 'T', '0', '1', '2', '3',
    '5', '9', '.', '-', '+', ' ', '(', ')', ';', '%', '$', '=', '/', '\n', '\r', '\t', 'é', '?',
    '!', '~', 'e', 'x',
];

fn check(text: &str) {
    if let Ok(job) = Job::parse(text) {
        assert!(job.total_time.is_finite() && job.total_length.is_finite());
        for l in &job.lines {
            assert!(l.length.is_finite() && l.time.is_finite(), "{l:?}");
            assert!(l.before.position.iter().all(|v| v.is_finite()), "{l:?}");
        }
        for i in 0..job.len() {
            let _ = job.resume_preamble(i);
            let _ = job.resume_line(i);
        }
    }
}

proptest! {
    #![proptest_config(Config {
        cases: 400,
        rng_seed: RngSeed::Fixed(14),
        failure_persistence: None,
        ..Config::default()
    })]

    #[test]
    fn job_parser_never_panics(chars in proptest::collection::vec(proptest::sample::select(ALPHABET), 0..300)) {
        check(&chars.into_iter().collect::<String>());
    }
}

/// Inputs that broke the parser once.
#[test]
fn job_parser_regressions() {
    for text in [
        "é",
        "G1Xé1",
        "X1\u{80}",
        "G1 X1e308 Y1e308 F1",
        "G2 X1 Y1 R1e-300 F10",
        "G20 G91 G1 X99999999 F1\nX99999999\n",
        "G93 G1 X1 F0\n",
        "G2 X0 Y0 I0 J0 F100\n",
        "$$$=\n%\n(((\n;)",
    ] {
        check(text);
    }
    // A realtime character or a byte GRBL drops is refused, naming the line.
    for bad in ["G1 X1 F100\nG1 X2 ! (hold)\n", "G1 X1é\n"] {
        let e = Job::parse(bad).unwrap_err().to_string();
        assert!(e.contains("GRBL would not receive as written"), "{e}");
    }
}
