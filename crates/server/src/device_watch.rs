//! The watchers of the devices open: one thread per device turns its events into the panel's
//! state and the pages' `device` and `job` events (tagged with the device's id), and one thread
//! per job waits for its end and records it.

use flatcut_device::{DeviceEvent, JobHandle, PlotHandle, Subscription};
use serde_json::json;

use crate::device_state::{JobState, Shared, closed_view};
use crate::device_views::{
    controller_view, doubt_view, plot_progress_view, plot_report_view, progress_view, report_view,
    status_view,
};

/// Turns device `id`'s events (of its opening `generation`) into the panel's state and the pages'
/// events, until it closes.
pub(crate) fn forward(shared: &Shared, id: &str, generation: u64, sub: &Subscription) {
    while let Some(e) = sub.recv() {
        let mut inner = shared.lock();
        let mine = inner
            .open
            .get(id)
            .is_some_and(|o| o.generation == generation);
        let job = inner.open.get(id).filter(|_| mine).and_then(|o| o.job);
        match e {
            DeviceEvent::Connected(info) => {
                if let Some(o) = inner.open.get_mut(id).filter(|_| mine) {
                    o.controller = Some(controller_view(&info));
                }
                shared.publish_device(&inner, id, "connected");
            }
            DeviceEvent::Status(s) => {
                if let Some(o) = inner.open.get_mut(id).filter(|_| mine) {
                    o.status = Some(status_view(&s));
                }
                shared.publish_device(&inner, id, "status");
            }
            DeviceEvent::Restarted => {
                shared.events.publish(
                    "device",
                    json!({"event": "restarted", "open": mine, "id": id,
                        "message": "the controller restarted: its position and G92 offset are gone"}),
                );
            }
            DeviceEvent::Progress(p) => {
                let live = job
                    .and_then(|j| inner.jobs.get_mut(&j))
                    .filter(|j| !j.state.ended());
                if let Some(j) = live {
                    j.progress = Some(progress_view(&p, j.wall_per_machine_s));
                    j.state = match (j.state, p.holding, &p.paused_at) {
                        (JobState::Asking, _, _) => JobState::Asking,
                        (_, _, Some(_)) => JobState::Paused,
                        (_, true, _) => JobState::Held,
                        _ => JobState::Running,
                    };
                }
                if let Some(j) = job {
                    shared.publish_job(&inner, j);
                }
            }
            DeviceEvent::Plot(p) => {
                let live = job
                    .and_then(|j| inner.jobs.get_mut(&j))
                    .filter(|j| !j.state.ended());
                if let Some(j) = live {
                    j.progress = Some(plot_progress_view(&p));
                    // A pause asked for holds the state until the resume, even while the feed
                    // still runs to the instruction's end.
                    j.state = if p.paused || j.control.pause_asked() {
                        JobState::Held
                    } else {
                        JobState::Running
                    };
                }
                if let Some(j) = job {
                    shared.publish_job(&inner, j);
                }
            }
            DeviceEvent::Notice(n) => {
                if let Some(j) = job.and_then(|j| inner.jobs.get_mut(&j)) {
                    j.notices.push(n);
                }
                if let Some(j) = job {
                    shared.publish_job(&inner, j);
                }
            }
            DeviceEvent::Paused(l) => {
                if let Some(j) = job.and_then(|j| inner.jobs.get_mut(&j)) {
                    j.state = JobState::Paused;
                    j.message = format!("the job paused itself at {l}: resume or stop it");
                }
                if let Some(j) = job {
                    shared.publish_job(&inner, j);
                }
            }
            DeviceEvent::Question(a) => {
                if let Some(j) = job.and_then(|j| inner.jobs.get_mut(&j)) {
                    j.state = JobState::Asking;
                    j.question = Some(a);
                }
                if let Some(j) = job {
                    shared.publish_job(&inner, j);
                }
            }
            DeviceEvent::Closed(why) => {
                if mine {
                    inner.forget(id);
                    shared
                        .events
                        .publish("device", closed_view(id, "closed", Some(&why)));
                }
                return;
            }
            // Job starts and ends are the job's waiter's to tell (with the sender's report).
            _ => {}
        }
    }
}

/// Waits for the end of job `id` on device `device` and records it.
pub(crate) fn wait_for_end(shared: &Shared, id: u64, device: &str, handle: JobHandle) {
    let r = handle.wait();
    let mut inner = shared.lock();
    if let Some(o) = inner.open.get_mut(device).filter(|o| o.job == Some(id)) {
        o.job = None;
    }
    if let Some(j) = inner.jobs.get_mut(&id) {
        j.question = None;
        match r {
            Ok(o) => {
                j.state = JobState::Done;
                j.message = "complete".into();
                j.report = Some(report_view(&o.report));
            }
            Err(e) => {
                j.state = if j.stop_asked {
                    JobState::Stopped
                } else {
                    JobState::Failed
                };
                j.in_doubt = j.job.as_ref().and_then(|job| doubt_view(&e, job));
                j.message = e.to_string();
            }
        }
    }
    shared.publish_job(&inner, id);
    if inner.open.contains_key(device) {
        shared.publish_device(&inner, device, "idle");
    }
}

/// Waits for the end of plot `id` on device `device` and records it: done when every byte was
/// sent (and, on the embedded plotter, drawn), stopped when the operator stopped it.
pub(crate) fn wait_for_plot(shared: &Shared, id: u64, device: &str, handle: PlotHandle) {
    let r = handle.wait();
    let mut inner = shared.lock();
    if let Some(o) = inner.open.get_mut(device).filter(|o| o.job == Some(id)) {
        o.job = None;
    }
    if let Some(j) = inner.jobs.get_mut(&id) {
        match r {
            Ok(o) => {
                j.state = JobState::Done;
                j.message = "complete".into();
                j.report = Some(plot_report_view(&o.report));
            }
            Err(e) => {
                j.state = if j.stop_asked {
                    JobState::Stopped
                } else {
                    JobState::Failed
                };
                j.message = e.to_string();
            }
        }
    }
    shared.publish_job(&inner, id);
    if inner.open.contains_key(device) {
        shared.publish_device(&inner, device, "idle");
    }
}
