//! Two pieces of work side by side: one on a thread of its own, the other on this thread.

/// Runs `apart` on a thread of its own while `here` runs on this thread, and returns both
/// results. On one of rayon's worker threads both run here instead, one after the other: a
/// worker blocked joining a thread that itself waits for rayon's pool (a parallel iterator in
/// `apart`) waits forever once every worker is so blocked, as the split's candidate maps,
/// flattened on rayon's workers at once, all were. There the pool already keeps the cores busy.
pub(crate) fn beside<A: Send, H>(
    apart: impl FnOnce() -> A + Send,
    here: impl FnOnce() -> H,
) -> (A, H) {
    if rayon::current_thread_index().is_some() {
        let h = here();
        return (apart(), h);
    }
    std::thread::scope(|s| {
        let a = s.spawn(apart);
        let h = here();
        // A panic there is a bug, carried on here as if it were this thread's.
        let a = a.join().unwrap_or_else(|e| std::panic::resume_unwind(e));
        (a, h)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;
    use std::sync::mpsc;
    use std::time::Duration;

    /// Runs `f` on a thread of its own and gives its result, or `None` if it has not finished
    /// within a minute (a deadlock, which would otherwise hang the test run).
    pub(crate) fn within_a_minute<T: Send + 'static>(
        f: impl FnOnce() -> T + Send + 'static,
    ) -> Option<T> {
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            let _ = tx.send(f());
        });
        rx.recv_timeout(Duration::from_secs(60)).ok()
    }

    #[test]
    fn work_beside_that_uses_rayon_finishes_on_the_only_worker_of_a_pool() {
        let got = within_a_minute(|| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .unwrap();
            pool.install(|| beside(|| (0..10_000u64).into_par_iter().sum::<u64>(), || 7))
        });
        assert_eq!(got, Some((49_995_000, 7)));
    }

    #[test]
    fn work_beside_runs_on_another_thread_off_rayon() {
        let here = std::thread::current().id();
        let (apart, same) = beside(|| std::thread::current().id(), || 1);
        assert_ne!(apart, here);
        assert_eq!(same, 1);
    }
}
