//! `flatcut serve`: the workbench in the browser. A local HTTP server (axum on tokio) with a JSON
//! API (`API.md`) and the page that uses only that API (three.js, bundled by
//! `tools/web/build.sh` into `assets/` and compiled in).
//!
//! Every job runs through the `flatcut` facade — the design loader for lines and regions,
//! `flatcut::run::flatten_project` and `finish_project` for the pieces, pattern, nest and jobs —
//! so what the page shows and serves is what `flatcut run` writes for the same design.
//!
//! Safety: it listens on 127.0.0.1 and ::1 only unless `--bind` names another address, which
//! then needs the token printed at start with every request; every request's `Host` must name
//! the server (DNS rebinding); bodies are limited to 32 MiB (413 beyond); only the embedded
//! assets are served (no path reaches the disk); a design the loader refuses is 400 with the
//! loader's located message and changes nothing; stopping the server (Ctrl-C, SIGTERM) cancels
//! any solve and stops a running job with the tool off (its journal written).
//!
//! Module map: `opened` (what was opened), `document` (the TOML edited in place), `bench` (the
//! design state: undo, redo, save), `edit` (lines and regions as tree edits), `views` (the
//! JSON the page draws), `task` (per-revision computations), `events` (server-sent events),
//! `guard` (host, token), `assets` (the page), `error` (errors as responses), `app` (the shared
//! state), `routes` (the router), `design_routes`, `solve_routes`, `device_routes` (the
//! handlers), `device_state` (the device panel's state: the devices open, their jobs),
//! `devices` (what the pages ask of them), `device_watch` (each device's events and each job's
//! end turned into that state and the pages' events),
//! `device_views` (their JSON), `plotters` (HP-GL plotters: the embedded one's id, the profile
//! and link a plotter is opened with).
#![warn(missing_docs)]

pub mod app;
pub mod assets;
pub mod bench;
pub mod design_routes;
pub mod device_routes;
pub mod device_state;
pub mod device_views;
pub mod device_watch;
pub mod devices;
pub mod document;
pub mod edit;
pub mod error;
pub mod events;
pub mod guard;
pub mod opened;
pub mod plotters;
pub mod routes;
pub mod solve_routes;
pub mod task;
pub mod views;

use std::future::Future;
use std::io::Read as _;
use std::net::{IpAddr, Ipv4Addr, Ipv6Addr, SocketAddr};
use std::path::PathBuf;
use std::sync::Arc;

use tokio::net::TcpListener;

use crate::app::App;
use crate::bench::Bench;
use crate::guard::Guard;

/// How `flatcut serve` was asked to run.
#[derive(Clone, Debug)]
pub struct ServeOptions {
    /// The project, design or model (default: `project.toml` or `design.toml` here).
    pub input: Option<PathBuf>,
    /// The port (0: any free one).
    pub port: u16,
    /// An address to listen on instead of the loopback ones; beyond loopback it needs a token.
    pub bind: Option<IpAddr>,
}

/// Why the server could not start or stopped.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// The project, design or model given could not be opened.
    #[error(transparent)]
    Open(#[from] opened::OpenError),
    /// The design bench could not be set up from what was opened.
    #[error(transparent)]
    Bench(#[from] bench::BenchError),
    #[error("cannot listen on {addr}: {source}{hint}")]
    /// An address could not be bound.
    Listen {
        /// The address and port tried.
        addr: SocketAddr,
        /// The operating system's error.
        source: std::io::Error,
        /// Advice appended to the message (" (the port is taken: choose another with --port)"
        /// when the port is in use, else empty).
        hint: &'static str,
    },
    /// Serving failed after the start (accepting a connection, or the server task itself).
    #[error("{0}")]
    Io(#[from] std::io::Error),
}

/// A server listening: where, and the token requests need (when bound beyond loopback).
#[derive(Clone, Debug)]
pub struct Listening {
    /// The addresses bound, with the port actually chosen (the loopback ones, or the `--bind`
    /// address).
    pub addrs: Vec<SocketAddr>,
    /// The access token (32 hex digits) every request must carry when bound beyond loopback;
    /// `None` on loopback.
    pub token: Option<String>,
    /// The address to open in a browser (with the token, when one is needed).
    pub url: String,
}

/// A server prepared to run: listeners bound, design opened.
pub struct Server {
    listeners: Vec<TcpListener>,
    router: axum::Router,
    /// Where the server listens.
    pub listening: Listening,
    /// The state the routes share.
    pub app: Arc<App>,
}

/// A random token of 128 bits, hex-encoded, from the system's random source.
fn new_token() -> Result<String, std::io::Error> {
    let mut b = [0u8; 16];
    std::fs::File::open("/dev/urandom")?.read_exact(&mut b)?;
    Ok(b.iter().map(|x| format!("{x:02x}")).collect())
}

async fn listen(addr: SocketAddr) -> Result<TcpListener, ServeError> {
    TcpListener::bind(addr).await.map_err(|source| {
        let hint = if source.kind() == std::io::ErrorKind::AddrInUse {
            " (the port is taken: choose another with --port)"
        } else {
            ""
        };
        ServeError::Listen { addr, source, hint }
    })
}

impl Server {
    /// Opens the input and binds the listeners.
    pub async fn bind(opts: &ServeOptions) -> Result<Server, ServeError> {
        let opened = opened::open(opts.input.as_deref())?;
        let bench = Bench::new(opened)?;
        let mut listeners = Vec::new();
        let (token, host_addr) = match opts.bind {
            Some(ip) => {
                listeners.push(listen(SocketAddr::new(ip, opts.port)).await?);
                let token = (!ip.is_loopback()).then(new_token).transpose()?;
                (token, ip)
            }
            None => {
                let v4 = listen(SocketAddr::new(Ipv4Addr::LOCALHOST.into(), opts.port)).await?;
                let port = v4.local_addr()?.port();
                listeners.push(v4);
                // A machine without IPv6 still serves on 127.0.0.1.
                if let Ok(v6) =
                    TcpListener::bind(SocketAddr::new(Ipv6Addr::LOCALHOST.into(), port)).await
                {
                    listeners.push(v6);
                }
                (None, IpAddr::V4(Ipv4Addr::LOCALHOST))
            }
        };
        let addrs: Vec<SocketAddr> = listeners
            .iter()
            .map(TcpListener::local_addr)
            .collect::<Result<_, _>>()?;
        let port = addrs[0].port();
        let beyond = !host_addr.is_loopback();
        let guard = Guard {
            hosts: guard::hosts_for(host_addr, beyond),
            port,
            token: token.clone(),
        };
        let host = match host_addr {
            IpAddr::V4(a) if a.is_unspecified() => "127.0.0.1".to_string(),
            IpAddr::V4(a) => a.to_string(),
            IpAddr::V6(a) if a.is_unspecified() => "[::1]".to_string(),
            IpAddr::V6(a) => format!("[{a}]"),
        };
        let url = match &token {
            Some(t) => format!("http://{host}:{port}/?token={t}"),
            None => format!("http://{host}:{port}/"),
        };
        let app = Arc::new(App::new(bench));
        let router = routes::router(app.clone(), guard);
        Ok(Server {
            listeners,
            router,
            listening: Listening { addrs, token, url },
            app,
        })
    }

    /// Serves until `shutdown` completes; then cancels any solve and returns once open
    /// requests have ended.
    pub async fn run(
        self,
        shutdown: impl Future<Output = ()> + Send + 'static,
    ) -> Result<(), ServeError> {
        let (stop_tx, stop_rx) = tokio::sync::watch::channel(false);
        let app = self.app.clone();
        tokio::spawn(async move {
            shutdown.await;
            app.events.close();
            app::lock(&app.flatten).cancel();
            app::lock(&app.graded).cancel();
            app::lock(&app.finish).cancel();
            // A running job stops with the tool off and its journal written before the
            // server ends.
            let closing = app.clone();
            let _ = tokio::task::spawn_blocking(move || closing.devices.close_all()).await;
            let _ = stop_tx.send(true);
        });
        let mut servers = Vec::new();
        for l in self.listeners {
            let mut rx = stop_rx.clone();
            let svc = self.router.clone();
            servers.push(tokio::spawn(async move {
                axum::serve(l, svc)
                    .with_graceful_shutdown(async move {
                        let _ = rx.wait_for(|s| *s).await;
                    })
                    .await
            }));
        }
        for s in servers {
            s.await.map_err(std::io::Error::other)??;
        }
        Ok(())
    }
}

/// Runs `flatcut serve` to the end: a runtime of its own, the server, until `wait_for_stop`
/// returns (the binary passes its Ctrl-C, SIGTERM and SIGHUP handler's wait: signals belong to
/// the program). `started` is told where it listens before the first request is taken. A job
/// running then is stopped with the tool off before this returns.
pub fn run(
    opts: &ServeOptions,
    started: impl FnOnce(&Listening),
    wait_for_stop: impl FnOnce() + Send + 'static,
) -> Result<(), ServeError> {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()?;
    rt.block_on(async {
        let server = Server::bind(opts).await?;
        started(&server.listening);
        let (tx, rx) = tokio::sync::oneshot::channel::<()>();
        // A thread of its own: the wait blocks, and it is not the runtime's to wait for.
        std::thread::Builder::new()
            .name("flatcut-serve-stop".into())
            .spawn(move || {
                wait_for_stop();
                let _ = tx.send(());
            })?;
        server
            .run(async move {
                let _ = rx.await;
            })
            .await
    })
}

/// A server running on a thread of its own (for tests and embedding): where it listens, and how
/// to stop it.
pub struct Background {
    /// Where the server listens.
    pub listening: Listening,
    /// The state the routes share, for inspection by the embedding program.
    pub app: Arc<App>,
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<std::thread::JoinHandle<Result<(), ServeError>>>,
}

impl Background {
    /// Starts a server with `opts` and returns once it listens.
    pub fn start(opts: &ServeOptions) -> Result<Background, ServeError> {
        let rt = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()?;
        let server = rt.block_on(Server::bind(opts))?;
        let listening = server.listening.clone();
        let app = server.app.clone();
        let (tx, rx) = tokio::sync::oneshot::channel::<()>();
        let thread = std::thread::spawn(move || {
            rt.block_on(server.run(async move {
                let _ = rx.await;
            }))
        });
        Ok(Background {
            listening,
            app,
            stop: Some(tx),
            thread: Some(thread),
        })
    }

    /// The first address it listens on.
    pub fn addr(&self) -> SocketAddr {
        self.listening.addrs[0]
    }

    /// Stops the server as Ctrl-C does and waits for it to end.
    pub fn stop(mut self) -> Result<(), ServeError> {
        self.shutdown()
    }

    fn shutdown(&mut self) -> Result<(), ServeError> {
        if let Some(tx) = self.stop.take() {
            let _ = tx.send(());
        }
        match self.thread.take() {
            Some(t) => t
                .join()
                .map_err(|_| ServeError::Io(std::io::Error::other("the server thread panicked")))?,
            None => Ok(()),
        }
    }
}

impl Drop for Background {
    fn drop(&mut self) {
        let _ = self.shutdown();
    }
}
