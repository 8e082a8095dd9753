//! The README's command table against the command line: every flag a row lists for a command
//! is one that command's `--help` shows.

use clap::CommandFactory as _;
use std::path::Path;

/// The table's rows: the command line in each row's first cell (`flatcut CMD …`).
fn table_rows(readme: &str) -> Vec<String> {
    readme
        .lines()
        .filter_map(|l| l.strip_prefix("| `flatcut "))
        .filter_map(|l| l.split_once("` |").map(|(cmd, _)| cmd.replace("\\|", "|")))
        .collect()
}

/// The `--flag` words of a command line.
fn flags(cmd: &str) -> Vec<String> {
    cmd.split(|c: char| !(c.is_ascii_alphanumeric() || c == '-'))
        .filter(|w| w.starts_with("--") && w.len() > 2)
        .map(str::to_string)
        .collect()
}

/// Whether `help` shows `flag` as a flag of its own (not as the start of a longer one).
fn shows(help: &str, flag: &str) -> bool {
    help.match_indices(flag).any(|(i, _)| {
        !help[i + flag.len()..]
            .chars()
            .next()
            .is_some_and(|c| c.is_ascii_alphanumeric() || c == '-')
    })
}

#[test]
fn every_flag_in_the_readme_command_table_exists_on_its_command() {
    let readme = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md"))
        .expect("README.md");
    let rows = table_rows(&readme);
    assert!(
        rows.len() >= 10,
        "the command table has {} rows",
        rows.len()
    );
    let mut cli = flatcut_cli::Cli::command();
    let mut missing = Vec::new();
    let mut checked = 0;
    for row in &rows {
        let name = row.split_whitespace().next().unwrap_or_default();
        let Some(sub) = cli.find_subcommand_mut(name) else {
            missing.push(format!("`flatcut {name}`: no such command"));
            continue;
        };
        let help = sub.render_long_help().to_string();
        for f in flags(row) {
            checked += 1;
            if !shows(&help, &f) {
                missing.push(format!("`flatcut {name}` has no {f}"));
            }
        }
    }
    assert!(checked > 50, "only {checked} flags found in the table");
    assert!(missing.is_empty(), "README command table: {missing:#?}");
}

#[test]
fn the_table_reader_finds_flags_and_only_whole_ones() {
    let rows = table_rows(
        "| `flatcut send job.gcode [--port PATH] [--on-pause abort\\|resume]` | streams |\n| other |",
    );
    assert_eq!(
        rows,
        ["send job.gcode [--port PATH] [--on-pause abort|resume]"]
    );
    assert_eq!(flags(&rows[0]), ["--port", "--on-pause"]);
    assert!(shows("  --port <PATH>\n", "--port"));
    assert!(!shows("  --port-name <PATH>\n", "--port"));
}
