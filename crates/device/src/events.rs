//! What a device tells whoever watches it: [`DeviceEvent`]s, delivered to every
//! [`Subscription`] in order. The device never waits for a subscriber: a subscriber that is
//! behind (a paused terminal, a slow web client) finds the newest progress or status in place of
//! the ones it missed (only the newest matters), and every other event kept.

use crate::plotter::PlotProgress;
use flatcut_grbl::driver::LineRef;
use flatcut_grbl::{ControllerInfo, MachineStatus, Progress, Question};
use std::collections::VecDeque;
use std::sync::{Arc, Condvar, Mutex, MutexGuard, Weak};
use std::time::{Duration, Instant};

/// A question asked of the operator: answer it by its `id` ([`crate::Device::answer`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Asked {
    /// The number to answer with.
    pub id: u64,
    /// What the sender knows and asks; its `Display` is the whole story, and
    /// [`Question::prompt`] the yes/no question ("no" is the safe answer).
    pub question: Question,
}

/// Something a device did or noticed.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum DeviceEvent {
    /// Connected: what the controller said of itself.
    Connected(ControllerInfo),
    /// A status report between jobs: state, work and machine position.
    Status(MachineStatus),
    /// The controller restarted by itself (power, a reset button, the reset of opening the
    /// port): its position and G92 offset are gone.
    Restarted,
    /// A job started.
    JobStarted {
        /// The job's name.
        name: String,
    },
    /// A job's progress: lines, path done, ETA (machine time), state, live work position.
    Progress(Box<Progress>),
    /// A plot's progress on an HP-GL device: the bytes the link accepted (never what was drawn),
    /// the device's hold (XOFF), the operator's pause, the ETA of the rest at the rate so far.
    Plot(PlotProgress),
    /// Something the operator should know before the machine runs (a feed over a max rate, a
    /// work frame kept across the reset, a homing before a resume), once each.
    Notice(String),
    /// The job paused itself (`M0`) here and waits: resume or stop it.
    Paused(LineRef),
    /// A question only the operator can answer; answer it with [`crate::Device::answer`]. The
    /// job waits for the answer (a stop answers no).
    Question(Asked),
    /// A job ended.
    JobFinished {
        /// The job's name.
        name: String,
        /// Whether it completed.
        ok: bool,
        /// What happened: the sender's error when it stopped.
        message: String,
    },
    /// The link failed or the device was closed.
    Closed(String),
}

impl DeviceEvent {
    /// Events of which only the newest matters.
    fn supersedes(&self, older: &DeviceEvent) -> bool {
        matches!(
            (self, older),
            (DeviceEvent::Progress(_), DeviceEvent::Progress(_))
                | (DeviceEvent::Plot(_), DeviceEvent::Plot(_))
                | (DeviceEvent::Status(_), DeviceEvent::Status(_))
        )
    }
}

#[derive(Debug, Default)]
struct Queue {
    events: VecDeque<DeviceEvent>,
    closed: bool,
}

#[derive(Debug, Default)]
struct Inbox {
    q: Mutex<Queue>,
    ready: Condvar,
}

impl Inbox {
    fn lock(&self) -> MutexGuard<'_, Queue> {
        self.q.lock().unwrap_or_else(|p| p.into_inner())
    }
}

/// One watcher's view of a device: its events in order, from when it subscribed.
#[derive(Debug)]
pub struct Subscription {
    inbox: Arc<Inbox>,
}

impl Subscription {
    /// The next event, waiting for it; `None` once the device is closed and every event was
    /// taken.
    pub fn recv(&self) -> Option<DeviceEvent> {
        let mut q = self.inbox.lock();
        loop {
            if let Some(e) = q.events.pop_front() {
                return Some(e);
            }
            if q.closed {
                return None;
            }
            q = self.inbox.ready.wait(q).unwrap_or_else(|p| p.into_inner());
        }
    }

    /// The next event, waiting at most `timeout`; `None` when none came (or the device is
    /// closed and drained: see [`Subscription::is_closed`]).
    pub fn recv_timeout(&self, timeout: Duration) -> Option<DeviceEvent> {
        let until = Instant::now() + timeout;
        let mut q = self.inbox.lock();
        loop {
            if let Some(e) = q.events.pop_front() {
                return Some(e);
            }
            let now = Instant::now();
            if q.closed || now >= until {
                return None;
            }
            q = self
                .inbox
                .ready
                .wait_timeout(q, until - now)
                .unwrap_or_else(|p| p.into_inner())
                .0;
        }
    }

    /// The next event if one is waiting.
    pub fn try_recv(&self) -> Option<DeviceEvent> {
        self.inbox.lock().events.pop_front()
    }

    /// Whether the device is closed and every event was taken.
    pub fn is_closed(&self) -> bool {
        let q = self.inbox.lock();
        q.closed && q.events.is_empty()
    }
}

/// The device's side: publishes to every live subscription.
#[derive(Debug, Default)]
pub(crate) struct Hub {
    inboxes: Mutex<Vec<Weak<Inbox>>>,
}

impl Hub {
    fn inboxes(&self) -> MutexGuard<'_, Vec<Weak<Inbox>>> {
        self.inboxes.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// A new subscription, seeing every event published from now on.
    pub(crate) fn subscribe(&self) -> Subscription {
        let inbox = Arc::new(Inbox::default());
        self.inboxes().push(Arc::downgrade(&inbox));
        Subscription { inbox }
    }

    /// Delivers `e` to every live subscription without waiting for any: it replaces a
    /// superseded event still waiting at the end of a queue.
    pub(crate) fn publish(&self, e: DeviceEvent) {
        let mut inboxes = self.inboxes();
        inboxes.retain(|w| w.strong_count() > 0);
        for inbox in inboxes.iter().filter_map(Weak::upgrade) {
            let mut q = inbox.lock();
            match q.events.back_mut() {
                Some(last) if e.supersedes(last) => *last = e.clone(),
                _ => q.events.push_back(e.clone()),
            }
            drop(q);
            inbox.ready.notify_all();
        }
    }

    /// Closes every subscription: they drain what is queued, then end.
    pub(crate) fn close(&self, why: &str) {
        self.publish(DeviceEvent::Closed(why.to_string()));
        for inbox in self.inboxes().iter().filter_map(Weak::upgrade) {
            inbox.lock().closed = true;
            inbox.ready.notify_all();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_subscriber_behind_gets_the_newest_tick_and_every_other_event() {
        let hub = Hub::default();
        let sub = hub.subscribe();
        let status = |x: f64| {
            DeviceEvent::Status(MachineStatus {
                state: flatcut_grbl::MachineState::Idle,
                work: Some([x, 0.0, 0.0]),
                machine: None,
            })
        };
        hub.publish(status(1.0));
        hub.publish(status(2.0));
        hub.publish(DeviceEvent::Notice("n".into()));
        hub.publish(status(3.0));
        hub.publish(status(4.0));
        hub.close("done");
        let got: Vec<DeviceEvent> = std::iter::from_fn(|| sub.recv()).collect();
        assert_eq!(
            got,
            vec![
                status(2.0),
                DeviceEvent::Notice("n".into()),
                status(4.0),
                DeviceEvent::Closed("done".into())
            ]
        );
        assert!(sub.is_closed());
        // A dropped subscription is forgotten.
        drop(sub);
        hub.publish(DeviceEvent::Restarted);
        assert!(hub.inboxes().is_empty());
    }
}
