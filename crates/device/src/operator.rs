//! The operator's questions as events: when a job needs the operator's word (a resume whose
//! machine position is unknown, a job file edited since its journal), the sender's
//! [`flatcut_grbl::Operator`] hook publishes the question with a number, and the job waits
//! until [`crate::Device::answer`] gives the answer for that number. A stop answers no, at
//! once: nobody is left waiting for an answer that will not come.

use crate::events::{Asked, DeviceEvent, Hub};
use flatcut_grbl::{CancelToken, Operator, Question};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{RecvTimeoutError, Sender, channel};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// How often a question waiting for its answer looks whether the job was stopped.
const STOP_POLL: Duration = Duration::from_millis(50);

/// The questions waiting for an answer.
#[derive(Debug, Default)]
pub(crate) struct Questions {
    open: Mutex<BTreeMap<u64, Sender<bool>>>,
    next: AtomicU64,
}

impl Questions {
    fn open(&self) -> std::sync::MutexGuard<'_, BTreeMap<u64, Sender<bool>>> {
        self.open.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The sender's operator for one job: asks through `hub`, gives up (no) when `stop` is
    /// aborted.
    pub(crate) fn operator(self: &Arc<Self>, hub: Arc<Hub>, stop: CancelToken) -> Operator {
        let me = self.clone();
        Operator::new(move |q: &Question| {
            let id = me.next.fetch_add(1, Ordering::Relaxed) + 1;
            let (tx, rx) = channel();
            me.open().insert(id, tx);
            hub.publish(DeviceEvent::Question(Asked {
                id,
                question: q.clone(),
            }));
            let yes = loop {
                if stop.is_aborted() {
                    break false;
                }
                match rx.recv_timeout(STOP_POLL) {
                    Ok(a) => break a,
                    Err(RecvTimeoutError::Timeout) => {}
                    Err(RecvTimeoutError::Disconnected) => break false,
                }
            };
            me.open().remove(&id);
            yes
        })
    }

    /// Answers question `id`; false when it is not open.
    pub(crate) fn answer(&self, id: u64, yes: bool) -> bool {
        match self.open().remove(&id) {
            Some(tx) => tx.send(yes).is_ok(),
            None => false,
        }
    }

    /// Answers every open question no (the device is closing).
    pub(crate) fn withdraw_all(&self) {
        for (_, tx) in std::mem::take(&mut *self.open()) {
            let _ = tx.send(false);
        }
    }
}
