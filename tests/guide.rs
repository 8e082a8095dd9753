//! The user guide against the command line: every `flatcut …` line of an `sh` block in
//! `docs/guide/` parses as a command, the blocks tagged plain `sh` run (in a temporary folder, in
//! order, page by page) and write the `out/…` files they name, and every command line of the
//! README's table is on a guide page.

use clap::Parser as _;
use std::path::{Path, PathBuf};

use crate::pipeline::root;

/// An example block of a guide page: whether it runs, and its `flatcut` command lines.
struct Block {
    runs: bool,
    commands: Vec<String>,
}

/// The `sh` blocks of a page (`sh` runs; `sh no-run` is only parsed) and its `text` blocks.
fn blocks(page: &str) -> (Vec<Block>, Vec<String>) {
    let (mut sh, mut text) = (Vec::new(), Vec::new());
    let mut open: Option<(String, Vec<String>)> = None;
    for line in page.lines() {
        match (&mut open, line.strip_prefix("```")) {
            (None, Some(info)) => open = Some((info.trim().to_string(), Vec::new())),
            (Some(_), Some(_)) => {
                let Some((info, lines)) = open.take() else {
                    continue;
                };
                if info == "text" {
                    text.extend(lines);
                } else if info.split_whitespace().next() == Some("sh") {
                    sh.push(Block {
                        runs: info == "sh",
                        commands: lines
                            .into_iter()
                            .filter(|l| l.starts_with("flatcut "))
                            .collect(),
                    });
                }
            }
            (Some((_, lines)), None) => lines.push(line.to_string()),
            (None, None) => {}
        }
    }
    (sh, text)
}

fn pages() -> Vec<(PathBuf, String)> {
    let dir = root().join("docs/guide");
    let mut pages: Vec<(PathBuf, String)> = std::fs::read_dir(&dir)
        .expect("docs/guide")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .map(|p| {
            let text = std::fs::read_to_string(&p).expect("page");
            (p, text)
        })
        .collect();
    pages.sort();
    pages
}

/// A guide command's words as the test runs them: `out/…` inside `out`, files of the repository
/// by their absolute path.
fn resolve(command: &str, out: &Path) -> Vec<String> {
    command
        .split_whitespace()
        .map(|w| match w.strip_prefix("out/") {
            Some(rest) => out.join(rest).display().to_string(),
            None if w.contains('/') && root().join(w).exists() => {
                root().join(w).display().to_string()
            }
            None => w.to_string(),
        })
        .collect()
}

#[test]
fn every_guide_example_parses_and_the_runnable_ones_write_what_they_name() {
    let mut ran = 0;
    let mut parsed = 0;
    for (path, page) in pages() {
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
        let name = name.unwrap_or_default();
        let tmp = tempfile::tempdir().expect("temporary folder");
        let out = tmp.path().join("out");
        std::fs::create_dir_all(&out).expect("out folder");
        for block in blocks(&page).0 {
            for command in &block.commands {
                let words = resolve(command, &out);
                let cli = flatcut_cli::Cli::try_parse_from(&words)
                    .unwrap_or_else(|e| panic!("{name}: `{command}` does not parse: {e}"));
                parsed += 1;
                if !block.runs {
                    continue;
                }
                let code = flatcut_cli::run(cli)
                    .unwrap_or_else(|e| panic!("{name}: `{command}` failed: {e:#}"));
                assert_eq!(
                    format!("{code:?}"),
                    format!("{:?}", std::process::ExitCode::SUCCESS),
                    "{name}: `{command}`"
                );
                for w in command.split_whitespace() {
                    if let Some(rest) = w.strip_prefix("out/") {
                        assert!(out.join(rest).exists(), "{name}: `{command}` wrote no {w}");
                    }
                }
                ran += 1;
            }
        }
    }
    assert!(parsed >= 25, "only {parsed} guide commands found");
    assert!(ran >= 15, "only {ran} guide commands run");
}

#[test]
fn every_command_line_of_the_readme_table_is_on_a_guide_page() {
    let readme = std::fs::read_to_string(root().join("README.md")).expect("README.md");
    let usages: Vec<String> = pages()
        .into_iter()
        .flat_map(|(_, p)| blocks(&p).1)
        .collect();
    let rows: Vec<String> = readme
        .lines()
        .filter_map(|l| l.strip_prefix("| `"))
        .filter_map(|l| l.split_once("` |").map(|(c, _)| c.replace("\\|", "|")))
        .filter(|c| c.starts_with("flatcut "))
        .collect();
    assert!(
        rows.len() >= 10,
        "the README's table has {} rows",
        rows.len()
    );
    let missing: Vec<&String> = rows.iter().filter(|r| !usages.contains(r)).collect();
    assert!(missing.is_empty(), "not in docs/guide: {missing:#?}");
}

#[test]
fn the_block_reader_tells_runnable_blocks_from_the_others() {
    let (sh, text) = blocks(
        "```text\nflatcut a B\n```\n```sh\nflatcut x\necho y\n```\n```sh no-run\nflatcut z\n```\n",
    );
    assert_eq!(text, ["flatcut a B"]);
    assert_eq!(sh.len(), 2);
    assert!(sh[0].runs && !sh[1].runs);
    assert_eq!(sh[0].commands, ["flatcut x"]);
    assert_eq!(sh[1].commands, ["flatcut z"]);
}
