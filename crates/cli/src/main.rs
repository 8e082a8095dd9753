//! The `flatcut` binary: everything lives in the library so tests can call it in-process.

fn main() -> std::process::ExitCode {
    flatcut_cli::main()
}
