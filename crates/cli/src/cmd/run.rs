//! `flatcut run PROJECT.toml` (being written).

#[derive(Debug, clap::Args)]
pub struct Args {}

pub fn run(_a: Args) -> anyhow::Result<std::process::ExitCode> {
    anyhow::bail!("not available in this build")
}
