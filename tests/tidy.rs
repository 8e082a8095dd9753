//! Architecture invariants as ordinary tests: the crate graph keeps its promises (2D crates know
//! nothing of 3D, the simulator shares no code with the sender or the G-code writer, only the
//! binary uses `anyhow`), every dependency is named by its sources, and every source file opens
//! with a `//!` module doc.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every package directory of the workspace (each crate under `crates/`, and firmware-sim), sorted.
fn package_dirs() -> Vec<PathBuf> {
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(root().join("crates"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.join("Cargo.toml").exists())
        .collect();
    dirs.push(root().join("firmware-sim"));
    dirs.sort();
    dirs
}

/// Package name → set of its normal (non-dev) dependency names, for every workspace member.
fn workspace_deps() -> BTreeMap<String, Vec<String>> {
    let mut out = BTreeMap::new();
    for d in package_dirs() {
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
fn the_device_library_sits_on_the_sender_and_the_simulator_only() {
    let g = workspace_deps();
    assert_eq!(
        closure(&g, "flatcut-device"),
        ["flatcut-firmware-sim", "flatcut-grbl", "flatcut-motion"],
        "flatcut-device streams any G-code: the sender, the simulator and the motion model, never \
         the G-code writer or the geometry"
    );
    // The command line streams through it, and the server will: the facade stays free of it.
    assert!(g["flatcut-cli"].contains(&"flatcut-device".to_string()));
    assert!(!closure(&g, "flatcut").contains(&"flatcut-device".to_string()));
}

#[test]
fn no_crate_is_its_own_dev_dependency_through_another() {
    let g = workspace_deps();
    for (name, dev) in workspace_dev_deps() {
        for d in dev.iter().filter(|d| g.contains_key(*d) && **d != name) {
            assert!(
                !closure(&g, d).contains(&name),
                "{name} dev-depends on {d}, which depends on {name}: the crate is built twice and \
                 its tests see two copies of it"
            );
        }
    }
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
            "flatcut-device",
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
    // Being dev-only, the testkit is the one library besides the device library (which embeds
    // the simulator as a device) allowed to depend on the simulator.
    let users: Vec<&String> = g
        .iter()
        .filter(|(_, d)| d.contains(&"flatcut-firmware-sim".to_string()))
        .map(|(n, _)| n)
        .collect();
    assert_eq!(users, ["flatcut-device", "flatcut-testkit"]);
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

/// Library crates whose public items must all be documented: each carries
/// `#![warn(missing_docs)]` in its `lib.rs`, which CI's clippy (`-D warnings`) turns into errors.
/// Add a crate here when it gains the lint; a listed crate that loses it fails.
const DOCUMENTED_CRATES: &[&str] = &[
    "crates/darts",
    "crates/design",
    "crates/device",
    "crates/flatcut",
    "crates/flatten",
    "crates/font",
    "crates/gcode",
    "crates/geom",
    "crates/grbl",
    "crates/mesh",
    "crates/motion",
    "crates/nest",
    "crates/pattern",
    "crates/report",
    "crates/server",
    "crates/step",
    "crates/surface",
    "crates/testkit",
];

#[test]
fn documented_crates_keep_the_missing_docs_lint() {
    let lost: Vec<_> = DOCUMENTED_CRATES
        .iter()
        .filter(|c| {
            let lib = std::fs::read_to_string(root().join(c).join("src/lib.rs")).unwrap();
            !lib.lines().any(|l| l.trim() == "#![warn(missing_docs)]")
        })
        .collect();
    assert!(
        lost.is_empty(),
        "crates listed as documented without `#![warn(missing_docs)]` in lib.rs: {lost:?}"
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

/// Rust source with comments, string and character literals blanked out (lifetimes kept), so
/// that paths are only found in code.
fn code_only(text: &str) -> String {
    let c: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < c.len() {
        let next = c.get(i + 1).copied();
        if c[i] == '/' && next == Some('/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if c[i] == '/' && next == Some('*') {
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
            out.push(' ');
        } else if c[i] == 'r' && (next == Some('"') || next == Some('#')) && {
            let mut k = i + 1;
            while c.get(k) == Some(&'#') {
                k += 1;
            }
            c.get(k) == Some(&'"') && !(i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_'))
        } {
            let mut hashes = 0;
            i += 1;
            while c[i] == '#' {
                hashes += 1;
                i += 1;
            }
            i += 1;
            while i < c.len() {
                if c[i] == '"' && (0..hashes).all(|h| c.get(i + 1 + h) == Some(&'#')) {
                    i += 1 + hashes;
                    break;
                }
                i += 1;
            }
            out.push_str("\"\"");
        } else if c[i] == '"' {
            i += 1;
            while i < c.len() && c[i] != '"' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("\"\"");
        } else if c[i] == '\''
            && (c.get(i + 2) == Some(&'\'') || (next == Some('\\') && c.get(i + 3) == Some(&'\'')))
        {
            i += if next == Some('\\') { 4 } else { 3 };
            out.push_str("' '");
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

/// The paths in `code`: every `a::b::c`, with `a::{b, c::d}` groups expanded one level.
fn paths_in(code: &str) -> Vec<Vec<String>> {
    let c: Vec<char> = code.chars().collect();
    let ident = |i: usize| -> (String, usize) {
        let mut j = i;
        while j < c.len() && (c[j].is_alphanumeric() || c[j] == '_') {
            j += 1;
        }
        (c[i..j].iter().collect(), j)
    };
    let skip_ws = |mut i: usize| {
        while i < c.len() && c[i].is_whitespace() {
            i += 1;
        }
        i
    };
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        let starts = (c[i].is_alphabetic() || c[i] == '_')
            && (i == 0 || !(c[i - 1].is_alphanumeric() || c[i - 1] == '_' || c[i - 1] == ':'));
        if !starts {
            i += 1;
            continue;
        }
        let (first, mut j) = ident(i);
        let mut path = vec![first];
        loop {
            let k = skip_ws(j);
            if !(c.get(k) == Some(&':') && c.get(k + 1) == Some(&':')) {
                break;
            }
            let k = skip_ws(k + 2);
            if c.get(k) == Some(&'{') {
                // A group: each member's first segment (and the rest up to a nested group).
                let mut depth = 0;
                let mut m = k;
                let mut member_start = k + 1;
                while m < c.len() {
                    match c[m] {
                        '{' => depth += 1,
                        '}' | ',' if depth == 1 => {
                            let member: String = c[member_start..m].iter().collect();
                            let segs: Vec<String> = member
                                .split("::")
                                .map(|s| s.trim().to_string())
                                .take_while(|s| {
                                    !s.is_empty()
                                        && s.chars().all(|x| x.is_alphanumeric() || x == '_')
                                })
                                .collect();
                            if !segs.is_empty() && segs[0] != "self" {
                                let mut p = path.clone();
                                p.extend(segs);
                                out.push(p);
                            }
                            member_start = m + 1;
                            if c[m] == '}' {
                                break;
                            }
                        }
                        '}' => depth -= 1,
                        _ => {}
                    }
                    m += 1;
                }
                j = m + 1;
                path.clear();
                break;
            }
            if !c.get(k).is_some_and(|x| x.is_alphabetic() || *x == '_') {
                break;
            }
            let (seg, e) = ident(k);
            path.push(seg);
            j = e;
        }
        if path.len() > 1 {
            out.push(path);
        }
        i = j.max(i + 1);
    }
    out
}

/// `code` without its `#[cfg(test)]` modules (tests may use any module of their crate), and the
/// names of the test modules kept in files of their own.
fn without_tests(code: &str) -> (String, Vec<String>) {
    let mut out = code.to_string();
    let mut files = Vec::new();
    let mut from = 0;
    while let Some(at) = out[from..].find("#[cfg(test)]").map(|i| i + from) {
        let rest = out[at + "#[cfg(test)]".len()..].trim_start();
        let start = out.len() - rest.len();
        let Some(decl) = rest.strip_prefix("mod ") else {
            from = start;
            continue;
        };
        let name: String = decl
            .trim_start()
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let after = decl.trim_start()[name.len()..].trim_start();
        if after.starts_with(';') {
            files.push(name);
            from = start;
            continue;
        }
        let open = out.len() - after.len();
        let mut depth = 0;
        let mut end = out.len();
        for (i, ch) in out[open..].char_indices() {
            match ch {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        end = open + i + 1;
                        break;
                    }
                }
                _ => {}
            }
        }
        out.replace_range(at..end, " ");
        from = at;
    }
    (out, files)
}

/// A crate's module graph: module path (`""` the root, `"driver::session"`) → the modules it
/// names, found from `src`. A module naming one of its own ancestors (a child using what its
/// parent declares) is not an edge: a parent holds what its children share.
fn module_graph(src: &Path) -> BTreeMap<String, Vec<String>> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let module_of = |f: &Path| {
        let rel = f.strip_prefix(src).unwrap().with_extension("");
        let mut segs: Vec<String> = rel
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect();
        if matches!(
            segs.last().map(String::as_str),
            Some("mod" | "lib" | "main")
        ) {
            segs.pop();
        }
        segs.join("::")
    };
    let all: BTreeMap<String, (String, Vec<String>)> = files
        .iter()
        .map(|f| {
            let code = code_only(&std::fs::read_to_string(f).unwrap());
            (module_of(f), without_tests(&code))
        })
        .collect();
    // Test modules kept in files of their own (`#[cfg(test)] mod tests;`) are left out too.
    let test_files: Vec<String> = all
        .iter()
        .flat_map(|(m, (_, tests))| {
            tests.iter().map(move |t| {
                if m.is_empty() {
                    t.clone()
                } else {
                    format!("{m}::{t}")
                }
            })
        })
        .collect();
    let texts: BTreeMap<String, String> = all
        .into_iter()
        .filter(|(m, _)| !test_files.contains(m))
        .map(|(m, (code, _))| (m, code))
        .collect();
    let join = |a: &str, b: &str| {
        if a.is_empty() {
            b.to_string()
        } else {
            format!("{a}::{b}")
        }
    };
    let parent = |m: &str| {
        m.rsplit_once("::")
            .map_or(String::new(), |(p, _)| p.to_string())
    };
    let is_ancestor = |a: &str, m: &str| a.is_empty() || m == a || m.starts_with(&format!("{a}::"));
    let mut graph = BTreeMap::new();
    for (m, text) in &texts {
        let mut edges: Vec<String> = Vec::new();
        for p in paths_in(text) {
            let (mut base, rest) = match p[0].as_str() {
                "crate" => (String::new(), &p[1..]),
                "self" => (m.clone(), &p[1..]),
                "super" => (parent(m), &p[1..]),
                child if texts.contains_key(&join(m, child)) => (m.clone(), &p[..]),
                _ => continue,
            };
            let mut rest = rest;
            while rest.first().is_some_and(|s| s == "super") {
                base = parent(&base);
                rest = &rest[1..];
            }
            let mut target = base;
            for seg in rest {
                let next = join(&target, seg);
                if !texts.contains_key(&next) {
                    break;
                }
                target = next;
            }
            if !is_ancestor(&target, m) && !edges.contains(&target) {
                edges.push(target);
            }
        }
        graph.insert(m.clone(), edges);
    }
    graph
}

/// The import circles of a module graph: each a set of modules that reach one another
/// (strongly connected components with more than one module), sorted.
fn circles(graph: &BTreeMap<String, Vec<String>>) -> Vec<Vec<String>> {
    let reach = |from: &String| {
        let mut seen = vec![from.clone()];
        let mut stack = vec![from.clone()];
        while let Some(n) = stack.pop() {
            for d in graph.get(&n).into_iter().flatten() {
                if !seen.contains(d) {
                    seen.push(d.clone());
                    stack.push(d.clone());
                }
            }
        }
        seen
    };
    let reaches: BTreeMap<&String, Vec<String>> = graph.keys().map(|m| (m, reach(m))).collect();
    let mut out: Vec<Vec<String>> = Vec::new();
    for m in graph.keys() {
        let mut scc: Vec<String> = reaches[m]
            .iter()
            .filter(|o| reaches.get(o).is_some_and(|r| r.contains(m)))
            .cloned()
            .collect();
        scc.sort();
        if scc.len() > 1 && !out.contains(&scc) {
            out.push(scc);
        }
    }
    out
}

#[test]
fn the_import_checker_finds_a_circle_and_only_a_circle() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path();
    std::fs::create_dir_all(src.join("dev")).unwrap();
    let write = |p: &str, t: &str| std::fs::write(src.join(p), t).unwrap();
    write("lib.rs", "//! x\nmod a;\nmod b;\nmod dev;\npub use a::A;\n");
    write(
        "a.rs",
        "//! x\nuse crate::b::B; // crate::dev in a comment\n",
    );
    write(
        "b.rs",
        "//! x\nfn f() { let _ = \"crate::a::A\"; crate::dev::g(); }\n",
    );
    write(
        "dev/mod.rs",
        "//! x\nmod p;\nmod q;\npub fn g() { p::h(); }\n",
    );
    write("dev/p.rs", "//! x\nuse super::{q::Q, g};\npub fn h() {}\n");
    write(
        "dev/q.rs",
        "//! x\nuse super::super::a::A;\npub struct Q;\n",
    );
    let g = module_graph(src);
    assert_eq!(g["a"], ["b"]);
    assert_eq!(g["b"], ["dev"]);
    assert_eq!(g["dev"], ["dev::p"]);
    assert_eq!(g["dev::p"], ["dev::q"]);
    assert_eq!(g["dev::q"], ["a"]);
    assert_eq!(
        circles(&g),
        [["a", "b", "dev", "dev::p", "dev::q"]
            .map(String::from)
            .to_vec()]
    );
    write("dev/q.rs", "//! x\npub struct Q;\n");
    assert!(circles(&module_graph(src)).is_empty());
    // Tests may use any module: in the file, or in a test file of their own.
    write(
        "dev/q.rs",
        "//! x\npub struct Q;\n#[cfg(test)]\nmod tests {\n    use crate::a::A;\n}\n#[cfg(test)]\nmod more;\n",
    );
    std::fs::create_dir_all(src.join("dev/q")).unwrap();
    write("dev/q/more.rs", "//! x\nuse crate::a::A;\n");
    assert!(circles(&module_graph(src)).is_empty());
    assert!(!module_graph(src).contains_key("dev::q::more"));
}

#[test]
fn the_device_session_and_the_sender_import_without_circles() {
    for krate in ["crates/device/src", "crates/grbl/src", "crates/motion/src"] {
        let found = circles(&module_graph(&root().join(krate)));
        assert!(found.is_empty(), "{krate}: import circles {found:?}");
    }
    // In the command line, the device layer and the file writer.
    let found: Vec<Vec<String>> = circles(&module_graph(&root().join("crates/cli/src")))
        .into_iter()
        .filter(|c| {
            c.iter()
                .any(|m| m.starts_with("cmd::device") || m == "output")
        })
        .collect();
    assert!(found.is_empty(), "crates/cli: import circles {found:?}");
}

#[test]
fn only_the_binary_installs_the_signal_handler() {
    let mut files = Vec::new();
    for d in std::fs::read_dir(root().join("crates")).unwrap() {
        let src = d.unwrap().path().join("src");
        if src.exists() {
            rust_files(&src, &mut files);
        }
    }
    let mut setters = Vec::new();
    let mut callers = Vec::new();
    for f in &files {
        let code = code_only(&std::fs::read_to_string(f).unwrap());
        let rel = f.strip_prefix(root()).unwrap().display().to_string();
        if code.contains("set_handler(") {
            setters.push(rel.clone());
        }
        if code.contains("install_signal_handler()") || code.contains("install_handler()") {
            callers.push(rel);
        }
    }
    assert_eq!(setters, ["crates/cli/src/cmd/device/signals.rs"]);
    // Defined there, re-exported for the binary, called by `main` alone: a file writer
    // (`OutputSet::new`) or a library installs nothing.
    callers.sort();
    assert_eq!(
        callers,
        [
            "crates/cli/src/cmd/device/signals.rs",
            "crates/cli/src/lib.rs"
        ]
    );
    let lib = code_only(&std::fs::read_to_string(root().join("crates/cli/src/lib.rs")).unwrap());
    let main_fn = &lib[lib.find("pub fn main()").unwrap()..];
    let main_body = &main_fn[..main_fn.find("\n}\n").unwrap()];
    assert!(
        main_body.contains("install_signal_handler()"),
        "{main_body}"
    );
}

/// No crate's modules import one another in a circle: each module's imports form a DAG, so every
/// module can be read knowing only the ones below it.
#[test]
fn every_crates_modules_import_without_circles() {
    let mut crates: Vec<PathBuf> = std::fs::read_dir(root().join("crates"))
        .unwrap()
        .map(|d| d.unwrap().path().join("src"))
        .filter(|s| s.exists())
        .collect();
    crates.push(root().join("firmware-sim/src"));
    crates.sort();
    let mut found = Vec::new();
    for src in &crates {
        let krate = src.strip_prefix(root()).unwrap().display().to_string();
        for circle in circles(&module_graph(src)) {
            found.push((krate.clone(), circle));
        }
    }
    assert!(found.is_empty(), "import circles inside crates: {found:#?}");
}

/// ARCHITECTURE.md's code map: one `### <dir> — `<package>`` section per section heading.
fn architecture_sections() -> Vec<(String, Vec<String>)> {
    let text = std::fs::read_to_string(root().join("ARCHITECTURE.md")).unwrap();
    let mut out: Vec<(String, Vec<String>)> = Vec::new();
    for line in text.lines() {
        if let Some(h) = line.strip_prefix("### ") {
            out.push((h.to_string(), Vec::new()));
        } else if line.starts_with("## ") {
            out.push((String::new(), Vec::new()));
        } else if let Some((_, body)) = out.last_mut() {
            body.push(line.to_string());
        }
    }
    out
}

/// Every package directory of the workspace with its package name.
fn packages() -> Vec<(String, String)> {
    let dirs = package_dirs();
    dirs.iter()
        .map(|d| {
            let v: toml::Value =
                toml::from_str(&std::fs::read_to_string(d.join("Cargo.toml")).unwrap()).unwrap();
            let dir = d.strip_prefix(root()).unwrap().display().to_string();
            (dir, v["package"]["name"].as_str().unwrap().to_string())
        })
        .collect()
}

#[test]
fn architecture_maps_every_crate_and_only_crates_that_exist() {
    let sections = architecture_sections();
    let packages = packages();
    for (dir, name) in &packages {
        let head = format!("{dir} — `{name}`");
        assert!(
            sections.iter().any(|(h, _)| h.starts_with(&head)),
            "ARCHITECTURE.md has no code-map section `### {head}`"
        );
    }
    for (h, _) in &sections {
        if let Some(dir) = h.split(" — ").next().filter(|d| d.starts_with("crates/")) {
            assert!(
                packages.iter().any(|(d, _)| d == dir),
                "ARCHITECTURE.md maps {dir}, which is not a workspace crate"
            );
        }
    }
}

/// A crate's section is a map, not an essay: the detail lives in the crate's module docs.
const MAX_SECTION_LINES: usize = 40;

#[test]
fn architecture_sections_are_maps_not_essays() {
    for (h, body) in architecture_sections() {
        let lines = body.iter().filter(|l| !l.trim().is_empty()).count();
        assert!(
            h.is_empty() || lines <= MAX_SECTION_LINES,
            "ARCHITECTURE.md section `{h}` has {lines} lines (at most {MAX_SECTION_LINES}): \
             move the detail into the module docs of the code it describes"
        );
    }
}

#[test]
fn every_file_architecture_names_exists() {
    let text = std::fs::read_to_string(root().join("ARCHITECTURE.md")).unwrap();
    let mut files = Vec::new();
    for d in ["crates", "firmware-sim", "tests"] {
        rust_files(&root().join(d), &mut files);
    }
    let files: Vec<String> = files
        .iter()
        .map(|f| f.strip_prefix(root()).unwrap().display().to_string())
        .collect();
    let named: Vec<&str> = text
        .split('`')
        .skip(1)
        .step_by(2)
        .filter(|s| s.ends_with(".rs") && !s.contains(' '))
        .collect();
    assert!(named.len() > 20, "too few file names found: {named:?}");
    let missing: Vec<_> = named
        .iter()
        .filter(|n| {
            !files
                .iter()
                .any(|f| f == *n || f.ends_with(&format!("/{n}")))
        })
        .collect();
    assert!(
        missing.is_empty(),
        "ARCHITECTURE.md names files that do not exist: {missing:?}"
    );
}

/// Words that only make sense inside the workplace a change was made in, not to a reader of a
/// clone: schedule talk, and paths to folders beside the repository that a clone does not have.
const PLACE_BOUND_PHRASES: &[&str] = &["this round", "main before this", "../shared", "/work/"];

#[test]
fn docs_speak_to_a_reader_of_a_clone() {
    let mut docs = vec![root().join("README.md"), root().join("ARCHITECTURE.md")];
    for d in ["docs", "docs/guide", "patterns"] {
        if let Ok(entries) = std::fs::read_dir(root().join(d)) {
            docs.extend(
                entries
                    .map(|e| e.unwrap().path())
                    .filter(|p| p.extension().is_some_and(|x| x == "md")),
            );
        }
    }
    let mut help = Vec::new();
    rust_files(&root().join("crates/cli/src"), &mut help);
    let mut found = Vec::new();
    for f in docs.iter().chain(&help) {
        let text = std::fs::read_to_string(f).unwrap();
        for (n, line) in text.lines().enumerate() {
            let lower = line.to_lowercase();
            for p in PLACE_BOUND_PHRASES {
                if lower.contains(p) {
                    found.push(format!("{}:{}: {p}", f.display(), n + 1));
                }
            }
        }
    }
    assert!(
        found.is_empty(),
        "text a clone's reader cannot follow: {found:#?}"
    );
}
