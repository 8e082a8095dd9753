//! Licences and bans of every third-party package the workspace can build, checked from
//! `cargo metadata` the way `cargo deny check licenses bans` checks them, without a tool to
//! install: each package's SPDX expression must be satisfiable with the accepted licences, every
//! package comes from crates.io, and no banned package is in the graph.
//!
//! The accepted list is the one place the project states which licences it takes in. flatcut is
//! `MIT OR Apache-2.0`; everything it links must allow shipping under those terms. MPL-2.0 is
//! accepted because it binds only the files of the library itself (serialport, jagua-rs), which
//! flatcut uses unmodified.

use serde_json::Value;
use std::process::Command;

/// SPDX identifiers flatcut accepts in its dependencies (a licence `WITH` an exception is accepted
/// when the licence is).
const ACCEPTED: &[&str] = &[
    "MIT",
    "Apache-2.0",
    "BSD-2-Clause",
    "BSD-3-Clause",
    "ISC",
    "Zlib",
    "0BSD",
    "Unlicense",
    "BSL-1.0",
    "CC0-1.0",
    "Unicode-3.0",
    "Unicode-DFS-2016",
    "MPL-2.0",
];

/// Packages that must never enter the graph, and why.
const BANNED: &[(&str, &str)] = &[
    (
        "openssl-sys",
        "a system library CI's machines do not have; use rustls where TLS is needed",
    ),
    (
        "libudev-sys",
        "serialport is built without libudev, so the binary runs without it",
    ),
];

/// `cargo metadata` of the workspace, all features, every platform.
fn metadata() -> Value {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args([
            "metadata",
            "--format-version",
            "1",
            "--locked",
            "--all-features",
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo metadata runs");
    assert!(
        out.status.success(),
        "cargo metadata failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("cargo metadata prints JSON")
}

/// Third-party packages as (name, version, licence expression or None, source).
fn third_party() -> Vec<(String, String, Option<String>, String)> {
    let m = metadata();
    m["packages"]
        .as_array()
        .expect("packages")
        .iter()
        .filter(|p| !p["source"].is_null())
        .map(|p| {
            (
                p["name"].as_str().unwrap_or_default().to_string(),
                p["version"].as_str().unwrap_or_default().to_string(),
                p["license"].as_str().map(str::to_string),
                p["source"].as_str().unwrap_or_default().to_string(),
            )
        })
        .collect()
}

/// Splits an SPDX expression into tokens: identifiers, `(`, `)`. Crates.io still carries the old
/// `/` separator, read as `OR`.
fn tokens(expr: &str) -> Vec<String> {
    expr.replace('(', " ( ")
        .replace(')', " ) ")
        .replace('/', " OR ")
        .split_whitespace()
        .map(str::to_string)
        .collect()
}

/// Whether an SPDX expression can be satisfied with the accepted licences. Grammar (SPDX annex D,
/// with AND binding tighter than OR): or := and (OR and)*; and := with (AND with)*;
/// with := atom (WITH exception)?; atom := id | ( or ).
fn satisfiable(expr: &str) -> Result<bool, String> {
    struct P {
        t: Vec<String>,
        i: usize,
    }
    impl P {
        fn peek(&self) -> Option<&str> {
            self.t.get(self.i).map(String::as_str)
        }
        fn or(&mut self) -> Result<bool, String> {
            let mut v = self.and()?;
            while self.peek() == Some("OR") {
                self.i += 1;
                v |= self.and()?;
            }
            Ok(v)
        }
        fn and(&mut self) -> Result<bool, String> {
            let mut v = self.with()?;
            while self.peek() == Some("AND") {
                self.i += 1;
                v &= self.with()?;
            }
            Ok(v)
        }
        fn with(&mut self) -> Result<bool, String> {
            let v = self.atom()?;
            if self.peek() == Some("WITH") {
                self.i += 2;
            }
            Ok(v)
        }
        fn atom(&mut self) -> Result<bool, String> {
            let tok = self.peek().ok_or("expression ends early")?.to_string();
            self.i += 1;
            if tok == "(" {
                let v = self.or()?;
                if self.peek() != Some(")") {
                    return Err("unbalanced parenthesis".into());
                }
                self.i += 1;
                return Ok(v);
            }
            Ok(ACCEPTED.contains(&tok.trim_end_matches('+')))
        }
    }
    let mut p = P {
        t: tokens(expr),
        i: 0,
    };
    let v = p.or()?;
    if p.i != p.t.len() {
        return Err(format!("unexpected `{}`", p.t[p.i]));
    }
    Ok(v)
}

#[test]
fn the_expression_reader_follows_spdx_precedence() {
    assert_eq!(satisfiable("MIT"), Ok(true));
    assert_eq!(satisfiable("GPL-3.0-only"), Ok(false));
    assert_eq!(satisfiable("MIT OR GPL-3.0-only"), Ok(true));
    assert_eq!(satisfiable("MIT AND GPL-3.0-only"), Ok(false));
    assert_eq!(satisfiable("GPL-2.0-only OR MIT AND Apache-2.0"), Ok(true));
    assert_eq!(
        satisfiable("(GPL-2.0-only OR MIT) AND LGPL-2.1-only"),
        Ok(false)
    );
    assert_eq!(satisfiable("Apache-2.0 WITH LLVM-exception"), Ok(true));
    assert_eq!(satisfiable("MIT/Apache-2.0"), Ok(true));
    assert!(satisfiable("(MIT OR Apache-2.0").is_err());
}

#[test]
fn every_dependency_has_an_accepted_licence() {
    let mut refused = Vec::new();
    for (name, version, licence, _) in third_party() {
        match licence.as_deref().map(satisfiable) {
            Some(Ok(true)) => {}
            Some(Ok(false)) => {
                refused.push(format!("{name} {version}: {}", licence.unwrap_or_default()))
            }
            Some(Err(e)) => refused.push(format!("{name} {version}: unreadable licence ({e})")),
            None => refused.push(format!(
                "{name} {version}: no SPDX licence in its Cargo.toml"
            )),
        }
    }
    assert!(
        refused.is_empty(),
        "licences not accepted (see ACCEPTED in tests/licences.rs):\n{}",
        refused.join("\n")
    );
}

#[test]
fn every_dependency_comes_from_crates_io_and_none_is_banned() {
    let packages = third_party();
    assert!(
        packages.len() > 50,
        "cargo metadata lists the dependency graph"
    );
    for (name, version, _, source) in &packages {
        assert!(
            source.starts_with("registry+https://github.com/rust-lang/crates.io-index"),
            "{name} {version} comes from {source}, not crates.io"
        );
        if let Some((_, why)) = BANNED.iter().find(|(b, _)| b == name) {
            panic!("{name} {version} is banned: {why}");
        }
    }
}
