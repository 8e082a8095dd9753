//! The application's shared state: the design bench, the per-revision computations, the events
//! and the device panel, which every route handler takes (the routes are mounted in `routes`).

use std::sync::{Arc, Mutex, MutexGuard};

use flatcut::flat::Flat;
use flatcut::run::{ProjectOutputs, RunOptions};
use serde_json::json;

use crate::bench::Bench;
use crate::devices::Devices;
use crate::events::Events;
use crate::task::Slot;

/// A design flattened: its pieces and the page's view of them (serialised once).
pub struct Flattened {
    /// The design revision flattened (1 when opened, one more for each edit that changes it).
    pub revision: u64,
    /// The flattened pieces, in the design's order (every size's of a graded design when all
    /// sizes were asked for).
    pub flats: Vec<Flat>,
    /// The JSON answer of `POST /api/flatten`, serialised.
    pub view: String,
}

/// Everything after the flattening, for one revision: the files `flatcut run` writes.
pub struct Finished {
    /// The design revision they were made for.
    pub revision: u64,
    /// The outputs, held in memory (pattern, layouts, jobs, report).
    pub outputs: ProjectOutputs,
}

/// The server's state, shared by every request.
pub struct App {
    bench: Mutex<Bench>,
    /// The server-sent event stream the pages listen to.
    pub events: Events,
    /// The options the run stages take here (`RunOptions::default()`).
    pub run: RunOptions,
    /// The live flattening: a graded design's base size (every piece of an ungraded one).
    pub flatten: Mutex<Slot<Flattened>>,
    /// Every size of a graded design: for the pattern, nest and jobs, and on demand.
    pub graded: Mutex<Slot<Flattened>>,
    /// Everything after the flattening (pattern, nest, jobs) for the latest revision asked.
    pub finish: Mutex<Slot<Finished>>,
    /// The last regions view: (revision, JSON text).
    pub regions: Mutex<Option<(u64, Arc<String>)>>,
    /// The device panel: the device open and the jobs streamed to it.
    pub devices: Devices,
}

impl App {
    /// The state for a design bench: no computation yet, no device open.
    pub fn new(bench: Bench) -> App {
        let events = Events::default();
        App {
            bench: Mutex::new(bench),
            devices: Devices::new(events.clone()),
            events,
            run: RunOptions::default(),
            flatten: Mutex::new(Slot::default()),
            graded: Mutex::new(Slot::default()),
            finish: Mutex::new(Slot::default()),
            regions: Mutex::new(None),
        }
    }

    /// The design state (a poisoned lock is taken over: every change of the bench is made
    /// whole or not at all).
    pub fn bench(&self) -> MutexGuard<'_, Bench> {
        self.bench.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Tells every page the design changed.
    pub fn design_changed(&self, why: &str) {
        let b = self.bench();
        self.events.publish(
            "design",
            json!({
                "revision": b.revision(),
                "saved": b.saved(),
                "can_undo": b.can_undo(),
                "can_redo": b.can_redo(),
                "why": why,
            }),
        );
    }
}

/// Locks a mutex, taking over a poisoned one.
pub fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// The body of a request whose route takes none (`POST /api/flatten` with `{}`), read and
/// dropped: a connection closed with request bytes unread is reset by the kernel, and the client
/// loses the answer it was reading.
pub type Unread = axum::body::Bytes;
