//! Bounded fuzzing in `cargo test`: seeded mutations of real inputs (bundled designs in TOML
//! and JSON, OBJ/STL/PLY meshes, pattern and foreign SVGs) fed to the readers. Each reader must
//! answer every input with a value or an error, never a panic, and whatever it accepts must lie
//! within the sane range (`flatcut::geom::limits`). Seeds and case counts are fixed, so a run
//! is reproducible and takes a few seconds; a failure prints the mutated input.

use std::path::{Path, PathBuf};

use flatcut::design::Design;
use flatcut::geom::limits;
use flatcut::mesh::io::{parse_obj, parse_ply, parse_stl};
use flatcut::pattern::ColourTable;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Tokens a mutation splices in: extreme and malformed numbers, and the syntax of the formats.
const TOKENS: &[&str] = &[
    "1e308",
    "-1e308",
    "1e9",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "4294967296",
    "18446744073709551616",
    "-1",
    "0",
    "-0",
    "1e-320",
    "3",
    "%",
    "100%",
    "\"",
    "'",
    "[",
    "]",
    "{",
    "}",
    "<",
    ">",
    "=",
    ",",
    "\n",
    " ",
    "#",
    "/",
    "//",
    "-",
    "e",
    ".",
    "\u{0}",
    "é",
    "v 1e308 0 0\n",
    "f 1 2 99999\n",
    "f -5 1 2\n",
    "vt 1e30 0\n",
    "element vertex 4000000000\n",
    "counts = [4294967296, 2]\n",
    "degree = [4294967295, 1]\n",
    "type = \"bspline\"\n",
    "<text>A</text>",
    "<image href=\"x.png\"/>",
    "width=\"100%\"",
    "stroke=\"#00ff00\"",
    "fill=\"red\"",
    "transform=\"scale(1e30)\"",
];

/// One mutation of a byte string.
#[derive(Clone, Debug)]
enum Mutation {
    Flip { at: f64, bit: u8 },
    Delete { at: f64, len: usize },
    Duplicate { at: f64, len: usize, to: f64 },
    Insert { at: f64, token: usize },
    ReplaceNumber { nth: usize, token: usize },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let at = 0.0..1.0f64;
    prop_oneof![
        (at.clone(), 0u8..8).prop_map(|(at, bit)| Mutation::Flip { at, bit }),
        (at.clone(), 1usize..40).prop_map(|(at, len)| Mutation::Delete { at, len }),
        (at.clone(), 1usize..80, 0.0..1.0f64).prop_map(|(at, len, to)| Mutation::Duplicate {
            at,
            len,
            to
        }),
        (at, 0..TOKENS.len()).prop_map(|(at, token)| Mutation::Insert { at, token }),
        (0usize..200, 0..TOKENS.len())
            .prop_map(|(nth, token)| Mutation::ReplaceNumber { nth, token }),
    ]
}

fn apply(input: &[u8], muts: &[Mutation]) -> Vec<u8> {
    let mut b = input.to_vec();
    for m in muts {
        let pos = |f: f64, b: &Vec<u8>| ((f * b.len() as f64) as usize).min(b.len());
        match *m {
            Mutation::Flip { at, bit } => {
                let i = pos(at, &b);
                if i < b.len() {
                    b[i] ^= 1 << bit;
                }
            }
            Mutation::Delete { at, len } => {
                let i = pos(at, &b);
                let j = (i + len).min(b.len());
                b.drain(i..j);
            }
            Mutation::Duplicate { at, len, to } => {
                let i = pos(at, &b);
                let j = (i + len).min(b.len());
                let chunk = b[i..j].to_vec();
                let k = pos(to, &b);
                b.splice(k..k, chunk);
            }
            Mutation::Insert { at, token } => {
                let i = pos(at, &b);
                b.splice(i..i, TOKENS[token].bytes());
            }
            Mutation::ReplaceNumber { nth, token } => {
                let mut starts = Vec::new();
                let mut in_num = false;
                for (i, c) in b.iter().enumerate() {
                    let d = c.is_ascii_digit();
                    if d && !in_num {
                        starts.push(i);
                    }
                    in_num = d || (in_num && matches!(c, b'.' | b'e' | b'E' | b'-' | b'+'));
                }
                if starts.is_empty() {
                    continue;
                }
                let i = starts[nth % starts.len()];
                let mut j = i;
                while j < b.len() && (b[j].is_ascii_digit() || matches!(b[j], b'.' | b'e' | b'E')) {
                    j += 1;
                }
                b.splice(i..j, TOKENS[token].bytes());
            }
        }
    }
    b
}

/// Fixed seed and case count: the same inputs every run, a few seconds in all.
fn config(seed: u64, cases: u32) -> Config {
    Config {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        ..Config::default()
    }
}

fn seeds(dir: &Path, ext: &str) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == ext))
        .map(|p| (p.display().to_string(), std::fs::read(&p).unwrap()))
        .collect();
    out.sort();
    out
}

fn design_seeds() -> Vec<(String, Vec<u8>)> {
    let mut s = seeds(&root().join("crates/design/examples"), "toml");
    s.extend(seeds(&root().join("tests/fuzz_seeds"), "toml"));
    s.extend(seeds(&root().join("tests/fuzz_seeds"), "json"));
    s
}

fn check_design(text: &str, json: bool) {
    let d = if json {
        Design::from_json_str(text, "fuzz.json")
    } else {
        Design::from_toml_str(text, "fuzz.toml")
    };
    let Ok(d) = d else { return };
    for p in &d.pieces {
        // Building checks every constructor against what the loader let through.
        let _ = p.build(Path::new("/nonexistent"));
    }
}

#[test]
fn fuzz_design_loader_toml_and_json() {
    let seeds = design_seeds();
    proptest!(config(0xDE51_6E00, 3000), |(k in 0..seeds.len(), muts in prop::collection::vec(mutation(), 1..6))| {
        let (name, bytes) = &seeds[k];
        let text = String::from_utf8_lossy(&apply(bytes, &muts)).into_owned();
        check_design(&text, name.ends_with(".json"));
    });
}

fn check_mesh(m: Result<flatcut::mesh::TriMesh, flatcut::mesh::MeshIoError>) {
    let Ok(m) = m else { return };
    assert!(m.positions.iter().all(|p| limits::in_range3(*p)));
    assert!(
        m.triangles
            .iter()
            .flatten()
            .all(|&i| (i as usize) < m.positions.len())
    );
    if let Some(f) = &m.flat {
        assert!(f.iter().all(|q| limits::in_range2(*q)));
    }
}

#[test]
fn fuzz_mesh_readers_obj_stl_ply() {
    let dir = root().join("tests/fuzz_seeds");
    let mut all = seeds(&dir, "obj");
    all.extend(seeds(&dir, "stl"));
    all.extend(seeds(&dir, "ply"));
    all.extend(seeds(&root().join("crates/design/examples"), "obj"));
    proptest!(config(0x3E5A_0B1E, 4000), |(k in 0..all.len(), muts in prop::collection::vec(mutation(), 1..6))| {
        let (name, bytes) = &all[k];
        let b = apply(bytes, &muts);
        let p = Path::new(name);
        if name.ends_with(".obj") {
            check_mesh(parse_obj(&String::from_utf8_lossy(&b), p));
        } else if name.ends_with(".stl") {
            check_mesh(parse_stl(&b, p, 1e-3));
        } else {
            check_mesh(parse_ply(&b, p, 1e-3));
        }
    });
}

#[test]
fn fuzz_svg_reader() {
    let mut all = seeds(&root().join("tests/fuzz_seeds"), "svg");
    all.extend(seeds(&root().join("patterns/golden/lampshade"), "svg"));
    let table = ColourTable::default();
    proptest!(config(0x5A6_12EA, 1500), |(k in 0..all.len(), muts in prop::collection::vec(mutation(), 1..6))| {
        let (_, bytes) = &all[k];
        let text = String::from_utf8_lossy(&apply(bytes, &muts)).into_owned();
        if let Ok(r) = flatcut::pattern::svg::read_svg(&text, "fuzz.svg", 0.05, &table) {
            for s in &r.drawing.strokes {
                assert!(s.points.iter().all(|q| limits::in_range2(*q)), "{text}");
            }
        }
    });
}
