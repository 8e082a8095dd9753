//! Architecture invariants as ordinary tests: the crate graph keeps its promises (2D crates know
//! nothing of 3D, the simulator shares no code with the sender or the G-code writer, only the
//! binary uses `anyhow`), every dependency is named by its sources, and every source file opens
//! with a `//!` module doc.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Package name → set of its normal (non-dev) dependency names, for every workspace member.
fn workspace_deps() -> BTreeMap<String, Vec<String>> {
    let mut out = BTreeMap::new();
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(root().join("crates"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.join("Cargo.toml").exists())
        .collect();
    dirs.push(root().join("firmware-sim"));
    dirs.sort();
    for d in dirs {
        let text = std::fs::read_to_string(d.join("Cargo.toml")).unwrap();
        let v: toml::Value = toml::from_str(&text).unwrap();
        let name = v["package"]["name"].as_str().unwrap().to_string();
        let deps = v
            .get("dependencies")
            .and_then(|d| d.as_table())
            .map(|t| t.keys().cloned().collect())
            .unwrap_or_default();
        out.insert(name, deps);
    }
    out
}

/// All packages reachable from `name` through normal dependencies inside the workspace.
fn closure(graph: &BTreeMap<String, Vec<String>>, name: &str) -> Vec<String> {
    let mut seen = Vec::new();
    let mut stack = vec![name.to_string()];
    while let Some(n) = stack.pop() {
        for d in graph.get(&n).into_iter().flatten() {
            if graph.contains_key(d) && !seen.contains(d) {
                seen.push(d.clone());
                stack.push(d.clone());
            }
        }
    }
    seen.sort();
    seen
}

#[test]
fn simulator_is_independent_of_every_workspace_crate() {
    let g = workspace_deps();
    assert_eq!(
        closure(&g, "flatcut-firmware-sim"),
        Vec::<String>::new(),
        "firmware-sim must share no code with the sender or the G-code writer"
    );
}

#[test]
fn sender_is_independent_of_the_gcode_writer_and_geometry() {
    let g = workspace_deps();
    assert_eq!(
        closure(&g, "flatcut-grbl"),
        vec!["flatcut-motion".to_string()],
        "flatcut-grbl streams any file: no workspace dependency but the motion model"
    );
}

#[test]
fn the_motion_model_stands_alone_and_is_the_only_one() {
    let g = workspace_deps();
    assert_eq!(
        closure(&g, "flatcut-motion"),
        Vec::<String>::new(),
        "flatcut-motion depends on no workspace crate"
    );
    for user in ["flatcut-gcode", "flatcut-grbl"] {
        assert!(
            g[user].contains(&"flatcut-motion".to_string()),
            "{user} times jobs with flatcut-motion"
        );
    }
    // No IO in the model: it is physics, not plumbing.
    let mut files = Vec::new();
    rust_files(&root().join("crates/motion/src"), &mut files);
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap();
        for io in ["std::fs", "std::io", "std::net", "std::process"] {
            assert!(!text.contains(io), "{}: uses {io}", f.display());
        }
    }
}

#[test]
fn two_dimensional_crates_know_nothing_of_surfaces() {
    let g = workspace_deps();
    for krate in ["flatcut-pattern", "flatcut-nest", "flatcut-gcode"] {
        for forbidden in [
            "flatcut-surface",
            "flatcut-mesh",
            "flatcut-flatten",
            "flatcut-design",
            "flatcut-report",
            "flatcut-grbl",
            "flatcut-firmware-sim",
        ] {
            assert!(
                !closure(&g, krate).contains(&forbidden.to_string()),
                "{krate} must not depend on {forbidden}"
            );
        }
    }
}

/// Package name → names in its `[dev-dependencies]`.
fn workspace_dev_deps() -> BTreeMap<String, Vec<String>> {
    let mut out = BTreeMap::new();
    let mut manifests: Vec<PathBuf> = std::fs::read_dir(root().join("crates"))
        .unwrap()
        .map(|e| e.unwrap().path().join("Cargo.toml"))
        .filter(|p| p.exists())
        .collect();
    manifests.push(root().join("firmware-sim/Cargo.toml"));
    manifests.push(root().join("Cargo.toml"));
    for m in manifests {
        let v: toml::Value = toml::from_str(&std::fs::read_to_string(&m).unwrap()).unwrap();
        let name = v["package"]["name"].as_str().unwrap().to_string();
        let deps = v
            .get("dev-dependencies")
            .and_then(|d| d.as_table())
            .map(|t| t.keys().cloned().collect())
            .unwrap_or_default();
        out.insert(name, deps);
    }
    out
}

#[test]
fn the_testkit_is_only_ever_a_dev_dependency() {
    let g = workspace_deps();
    for (name, deps) in &g {
        assert!(
            !deps.contains(&"flatcut-testkit".to_string()),
            "{name}: flatcut-testkit is test code, a dev-dependency only"
        );
    }
    let dev = workspace_dev_deps();
    assert!(
        dev.values()
            .any(|d| d.contains(&"flatcut-testkit".to_string())),
        "the shared fixtures are used"
    );
    // Being dev-only, the testkit is the one library besides the CLI (which embeds the
    // simulator as a device) allowed to depend on the simulator.
    let users: Vec<&String> = g
        .iter()
        .filter(|(_, d)| d.contains(&"flatcut-firmware-sim".to_string()))
        .map(|(n, _)| n)
        .collect();
    assert_eq!(users, ["flatcut-cli", "flatcut-testkit"]);
    let manifest = std::fs::read_to_string(root().join("crates/testkit/Cargo.toml")).unwrap();
    let v: toml::Value = toml::from_str(&manifest).unwrap();
    assert_eq!(v["package"]["publish"].as_bool(), Some(false));
}

#[test]
fn only_the_binary_uses_anyhow() {
    for (name, deps) in workspace_deps() {
        if name != "flatcut-cli" {
            assert!(
                !deps.contains(&"anyhow".to_string()),
                "{name}: libraries return typed errors, anyhow is for the binary only"
            );
        }
    }
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

#[test]
fn every_source_file_opens_with_a_module_doc() {
    let mut files = Vec::new();
    for d in std::fs::read_dir(root().join("crates")).unwrap() {
        let src = d.unwrap().path().join("src");
        if src.exists() {
            rust_files(&src, &mut files);
        }
    }
    rust_files(&root().join("firmware-sim/src"), &mut files);
    let missing: Vec<_> = files
        .iter()
        .filter(|f| {
            let text = std::fs::read_to_string(f).unwrap();
            !text.trim_start().starts_with("//!")
        })
        .collect();
    assert!(
        missing.is_empty(),
        "files without a //! module doc: {missing:?}"
    );
}

/// The text of every `.rs` file under the given directories of a package (missing ones skipped).
fn sources(package: &Path, dirs: &[&str]) -> String {
    let mut files = Vec::new();
    for d in dirs {
        let p = package.join(d);
        if p.is_dir() {
            rust_files(&p, &mut files);
        } else if p.is_file() {
            files.push(p);
        }
    }
    files
        .iter()
        .map(|f| std::fs::read_to_string(f).unwrap())
        .collect::<Vec<_>>()
        .join("\n")
}

/// Whether `ident` occurs as a whole word (a path segment, a `use`, an attribute) in `text`.
fn mentions(text: &str, ident: &str) -> bool {
    let is_word = |c: char| c.is_alphanumeric() || c == '_';
    text.match_indices(ident).any(|(i, _)| {
        let before = text[..i].chars().next_back();
        let after = text[i + ident.len()..].chars().next();
        !before.is_some_and(is_word) && !after.is_some_and(is_word)
    })
}

#[test]
fn every_dependency_is_used() {
    // The root package holds the end-to-end tests; its own crates live elsewhere.
    let mut packages: Vec<PathBuf> = std::fs::read_dir(root().join("crates"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.join("Cargo.toml").exists())
        .collect();
    packages.push(root().join("firmware-sim"));
    packages.push(root());
    let mut unused = Vec::new();
    for p in &packages {
        let v: toml::Value =
            toml::from_str(&std::fs::read_to_string(p.join("Cargo.toml")).unwrap()).unwrap();
        let main: &[&str] = if *p == root() {
            &["src"]
        } else {
            &["src", "build.rs"]
        };
        let sections: [(&str, &[&str]); 2] = [
            ("dependencies", main),
            ("dev-dependencies", &["src", "tests", "benches", "examples"]),
        ];
        for (section, dirs) in sections {
            let text = sources(p, dirs);
            for name in v
                .get(section)
                .and_then(|d| d.as_table())
                .into_iter()
                .flatten()
            {
                let ident = name.0.replace('-', "_");
                // A package's dev-dependency on itself (to switch on a test feature) is used.
                let itself = v["package"]["name"].as_str() == Some(name.0.as_str());
                if !itself && !mentions(&text, &ident) {
                    unused.push(format!("{}: [{section}] {}", p.display(), name.0));
                }
            }
        }
    }
    assert!(
        unused.is_empty(),
        "dependencies no source names: {unused:#?}"
    );
}
