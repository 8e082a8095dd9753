//! A computation for one revision of the design (a flattening, a nest), run on a blocking thread
//! and awaited by any number of requests: asking again for the same revision joins the running
//! one (or takes its result), asking for a newer one cancels the old one first. A cancelled
//! result is never kept, so the next request starts afresh.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use tokio::sync::watch;

use crate::error::ApiError;

type Outcome<T> = Option<Result<Arc<T>, ApiError>>;

struct Running<T> {
    revision: u64,
    cancel: Arc<AtomicBool>,
    rx: watch::Receiver<Outcome<T>>,
}

/// The latest computation of one kind.
pub struct Slot<T> {
    current: Option<Running<T>>,
}

impl<T> Default for Slot<T> {
    fn default() -> Self {
        Slot { current: None }
    }
}

impl<T: Send + Sync + 'static> Slot<T> {
    /// The computation for `revision`: the one running or done, or `start` run now (with a
    /// cancel flag) after cancelling an older one.
    pub fn get_or_start(
        &mut self,
        revision: u64,
        start: impl FnOnce(Arc<AtomicBool>) -> Result<T, ApiError> + Send + 'static,
    ) -> watch::Receiver<Outcome<T>> {
        if let Some(r) = &self.current {
            let cancelled = matches!(&*r.rx.borrow(), Some(Err(e)) if e.is_cancelled());
            if r.revision == revision && !cancelled {
                return r.rx.clone();
            }
            r.cancel.store(true, Ordering::Relaxed);
        }
        let (tx, rx) = watch::channel(None);
        let cancel = Arc::new(AtomicBool::new(false));
        let flag = cancel.clone();
        tokio::task::spawn_blocking(move || {
            let out = start(flag).map(Arc::new);
            let _ = tx.send(Some(out));
        });
        self.current = Some(Running {
            revision,
            cancel,
            rx: rx.clone(),
        });
        rx
    }

    /// The finished result for `revision`, if there is one.
    pub fn done(&self, revision: u64) -> Option<Arc<T>> {
        let r = self.current.as_ref().filter(|r| r.revision == revision)?;
        match &*r.rx.borrow() {
            Some(Ok(v)) => Some(v.clone()),
            _ => None,
        }
    }

    /// Cancels the running computation; true when one was running.
    pub fn cancel(&self) -> bool {
        match &self.current {
            Some(r) if r.rx.borrow().is_none() => {
                r.cancel.store(true, Ordering::Relaxed);
                true
            }
            _ => false,
        }
    }
}

/// Waits for a computation's result.
pub async fn wait<T>(mut rx: watch::Receiver<Outcome<T>>) -> Result<Arc<T>, ApiError> {
    match rx.wait_for(Option::is_some).await {
        Ok(v) => match &*v {
            Some(r) => r.clone(),
            None => Err(ApiError::internal("a computation ended without a result")),
        },
        Err(_) => Err(ApiError::internal("a computation stopped before its end")),
    }
}
