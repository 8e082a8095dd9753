//! The events every open page hears at `/api/events` (server-sent events): the design changed,
//! a solve's progress, a stage started or finished, and later the devices' state. One broadcast
//! channel; a page that falls behind skips what it missed (the next event carries the state).

use std::convert::Infallible;
use std::time::Duration;

use axum::response::sse::{Event, KeepAlive, Sse};
use futures_util::Stream;
use serde_json::Value as Json;
use tokio::sync::broadcast;

/// Events kept for a slow page before it starts skipping.
const BACKLOG: usize = 256;

/// The events' sender, shared by every part of the server.
#[derive(Clone)]
pub struct Events {
    tx: broadcast::Sender<(String, String)>,
}

impl Default for Events {
    fn default() -> Self {
        Events {
            tx: broadcast::channel(BACKLOG).0,
        }
    }
}

impl Events {
    /// Sends `data` (a JSON object) as an event of type `kind` to every page listening.
    pub fn publish(&self, kind: &str, data: Json) {
        // No page listening is not an error.
        let _ = self.tx.send((kind.to_string(), data.to_string()));
    }

    /// A new listener.
    pub fn subscribe(&self) -> broadcast::Receiver<(String, String)> {
        self.tx.subscribe()
    }
}

/// The SSE response for one page: `hello` (the state when it connects) first, then every event
/// published while it listens, with a keep-alive comment every 15 s.
pub fn stream(
    hello: Json,
    rx: broadcast::Receiver<(String, String)>,
) -> Sse<impl Stream<Item = Result<Event, Infallible>>> {
    let first = Some(Event::default().event("hello").data(hello.to_string()));
    let s = futures_util::stream::unfold((first, rx), |(first, mut rx)| async move {
        if let Some(e) = first {
            return Some((Ok(e), (None, rx)));
        }
        loop {
            match rx.recv().await {
                Ok((kind, data)) => {
                    return Some((Ok(Event::default().event(kind).data(data)), (None, rx)));
                }
                Err(broadcast::error::RecvError::Lagged(_)) => continue,
                Err(broadcast::error::RecvError::Closed) => return None,
            }
        }
    });
    Sse::new(s).keep_alive(KeepAlive::new().interval(Duration::from_secs(15)))
}
