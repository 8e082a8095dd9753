//! The events every open page hears at `/api/events` (server-sent events): the design changed,
//! a solve's progress, a stage started or finished, and later the devices' state. One broadcast
//! channel; a page that falls behind skips what it missed (the next event carries the state).

use std::convert::Infallible;
use std::time::Duration;

use axum::response::sse::{Event, KeepAlive, Sse};
use futures_util::Stream;
use serde_json::Value as Json;
use tokio::sync::{broadcast, watch};

/// Events kept for a slow page before it starts skipping.
const BACKLOG: usize = 256;

/// The events' sender, shared by every part of the server.
#[derive(Clone)]
pub struct Events {
    tx: broadcast::Sender<(String, String)>,
    /// Set when the server stops: every stream ends, so no open page holds the shutdown up.
    closing: watch::Sender<bool>,
}

impl Default for Events {
    fn default() -> Self {
        Events {
            tx: broadcast::channel(BACKLOG).0,
            closing: watch::channel(false).0,
        }
    }
}

impl Events {
    /// Sends `data` (a JSON object) as an event of type `kind` to every page listening.
    pub fn publish(&self, kind: &str, data: Json) {
        // No page listening is not an error.
        let _ = self.tx.send((kind.to_string(), data.to_string()));
    }

    /// A new listener: the events, and whether the server is stopping.
    pub fn subscribe(&self) -> Listener {
        Listener {
            rx: self.tx.subscribe(),
            closing: self.closing.subscribe(),
        }
    }

    /// Ends every stream (the server is stopping).
    pub fn close(&self) {
        self.closing.send_replace(true);
    }
}

/// One page's end of the events.
pub struct Listener {
    rx: broadcast::Receiver<(String, String)>,
    closing: watch::Receiver<bool>,
}

impl Listener {
    /// The next event; `None` once the server stops.
    async fn next(&mut self) -> Option<(String, String)> {
        loop {
            tokio::select! {
                r = self.rx.recv() => match r {
                    Ok(e) => return Some(e),
                    Err(broadcast::error::RecvError::Lagged(_)) => continue,
                    Err(broadcast::error::RecvError::Closed) => return None,
                },
                c = self.closing.wait_for(|c| *c) => {
                    let _ = c;
                    return None;
                }
            }
        }
    }
}

/// The SSE response for one page: `hello` (the state when it connects) first, then every event
/// published while it listens, with a keep-alive comment every 15 s, until the server stops.
pub fn stream(hello: Json, rx: Listener) -> Sse<impl Stream<Item = Result<Event, Infallible>>> {
    let first = Some(Event::default().event("hello").data(hello.to_string()));
    let s = futures_util::stream::unfold((first, rx), |(first, mut rx)| async move {
        if let Some(e) = first {
            return Some((Ok(e), (None, rx)));
        }
        let (kind, data) = rx.next().await?;
        Some((Ok(Event::default().event(kind).data(data)), (None, rx)))
    });
    Sse::new(s).keep_alive(KeepAlive::new().interval(Duration::from_secs(15)))
}
