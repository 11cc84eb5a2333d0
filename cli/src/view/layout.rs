//! The rest of a staged pyramid ([`meshpyr::pyramid::Staged`]): the editor of a `.pyr` file
//! opens on the pyramid of the levels its previews synthesise, and the whole pyramid (most
//! of the opening: the relaxation weights and fans of every split) is recorded meanwhile on
//! the loader's thread and a thread pool of its own, so that the server's requests do not
//! queue behind it. The session swaps it in when it is done ([`Session`]); until then the
//! calls that need it say that it is pending.
//!
//! [`Session`]: super::session::Session

use meshpyr::progress::Progress;
use meshpyr::pyramid::{DetailPyramid, PendingLayout, Pyramid};
use std::sync::mpsc::Receiver;
use std::sync::{Arc, Mutex, MutexGuard};

/// What the recording and the session share.
#[derive(Default)]
struct Shared {
    /// The fraction recorded.
    done: f64,
    /// The whole pyramid, or why it could not be made; taken by the session.
    result: Option<Result<DetailPyramid, String>>,
}

/// The session's side: progress and, once recorded, the whole pyramid.
pub(crate) struct LayoutWait {
    shared: Arc<Mutex<Shared>>,
}

/// The loader thread's side: records the whole pyramid of `scan` from `pending`.
pub(crate) struct LayoutJob {
    scan: Arc<Pyramid>,
    pending: PendingLayout,
    shared: Arc<Mutex<Shared>>,
    hold: Option<Receiver<()>>,
}

fn lock(shared: &Mutex<Shared>) -> MutexGuard<'_, Shared> {
    // A recording that panicked while holding the lock left only numbers behind.
    shared.lock().unwrap_or_else(|e| e.into_inner())
}

/// The two sides of recording the rest of `scan`'s pyramid; with `hold`, the recording starts
/// only once it receives (or its sender is gone).
pub(crate) fn staged(
    scan: Arc<Pyramid>,
    pending: PendingLayout,
    hold: Option<Receiver<()>>,
) -> (LayoutJob, LayoutWait) {
    let shared = Arc::new(Mutex::new(Shared::default()));
    let job = LayoutJob {
        scan,
        pending,
        shared: Arc::clone(&shared),
        hold,
    };
    (job, LayoutWait { shared })
}

impl LayoutWait {
    /// The fraction recorded.
    pub fn done(&self) -> f64 {
        lock(&self.shared).done
    }

    /// The whole pyramid or why there is none, once, when the recording has ended.
    pub fn take(&self) -> Option<Result<DetailPyramid, String>> {
        lock(&self.shared).result.take()
    }
}

impl Progress for LayoutWait {
    fn update(&self, fraction: f64) {
        lock(&self.shared).done = fraction.clamp(0.0, 1.0);
    }
}

impl LayoutJob {
    /// Records the whole pyramid on a pool of as many threads as cores, then hands it to the
    /// session. The scan is let go first, so that the session holds the only reference when
    /// it swaps the pyramid in.
    pub fn run(self) {
        let LayoutJob {
            scan,
            pending,
            shared,
            hold,
        } = self;
        if let Some(hold) = hold {
            let _ = hold.recv();
        }
        let progress = LayoutWait {
            shared: Arc::clone(&shared),
        };
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        let record = || {
            pending
                .record(&scan.pm, &progress)
                .map(|(pyramid, _)| pyramid)
                .map_err(|e| e.to_string())
        };
        let recorded = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            match rayon::ThreadPoolBuilder::new().num_threads(threads).build() {
                Ok(pool) => pool.install(record),
                Err(_) => record(),
            }
        }))
        .unwrap_or_else(|_| {
            Err("internal error while recording the layout (please report)".into())
        });
        drop(pending);
        drop(scan);
        let mut shared = lock(&shared);
        shared.done = 1.0;
        shared.result = Some(recorded);
    }
}
