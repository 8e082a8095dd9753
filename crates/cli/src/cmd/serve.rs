//! `flatcut serve [PROJECT.toml | DESIGN | MODEL] [--port 8080] [--bind ADDR] [--open]`: the
//! workbench in the browser (crates/server). Prints where it listens (and the token, when bound
//! beyond this machine) and serves until Ctrl-C.

use std::net::IpAddr;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// A project file, a design (TOML or JSON) or a model (OBJ, STL, PLY, STEP); default:
    /// project.toml or design.toml in this directory.
    pub file: Option<PathBuf>,
    /// The port to listen on (0: any free port).
    #[arg(long, default_value_t = 8080)]
    pub port: u16,
    /// Listen on this address instead of 127.0.0.1 and ::1. Beyond loopback every request then
    /// needs the token printed at start.
    #[arg(long, value_name = "ADDR")]
    pub bind: Option<IpAddr>,
    /// Open the workbench in the default browser.
    #[arg(long)]
    pub open: bool,
}

pub fn run(a: Args) -> anyhow::Result<ExitCode> {
    let opts = flatcut_server::ServeOptions {
        input: a.file.clone(),
        port: a.port,
        bind: a.bind,
    };
    // Ctrl-C (SIGTERM, SIGHUP) comes through the binary's one handler: it stops the server,
    // which stops a running job with the tool off.
    flatcut_server::run(
        &opts,
        |l| {
            let mut text = String::new();
            for addr in &l.addrs {
                text.push_str(&format!("listening on {addr}\n"));
            }
            if let Some(t) = &l.token {
                text.push_str(&format!("token (send it with every request): {t}\n"));
            }
            text.push_str(&format!("workbench: {}\nCtrl-C stops it\n", l.url));
            // A closed standard output does not stop the server: its address is printed, or not.
            let _ = crate::stdout::write(format_args!("{text}"));
            if a.open {
                open_browser(&l.url);
            }
        },
        super::device::wait_for_interrupt,
    )?;
    Ok(ExitCode::SUCCESS)
}

/// Opens `url` in the desktop's browser (xdg-open); a machine without one just has the printed
/// address.
fn open_browser(url: &str) {
    if let Err(e) = std::process::Command::new("xdg-open")
        .arg(url)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
    {
        eprintln!("warning: cannot open a browser ({e}); open {url}");
    }
}
