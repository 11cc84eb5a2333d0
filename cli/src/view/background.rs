//! The editor's background work on a large scan, on its own thread and thread pool so that the
//! server keeps answering: the exact full-resolution result of the latest state the page
//! previewed (what export uses and what replaces the preview), and, while nothing else is
//! asked for, the fine octaves' displacements at the shown vertices that previews combine
//! ([`super::preview`]).

use glam::DVec3;
use meshpyr::pyramid::{Filter, LevelGains, LevelMove, Pyramid, SynthesisCache};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// How long a state must stay the latest before its exact synthesis starts: while a slider is
/// dragged, the exact results of states it passes through would only slow its previews.
const SETTLE: Duration = Duration::from_millis(150);

/// An exact result: the state's number, its moves and gains, and the finest signal (PM order).
#[derive(Clone)]
pub(crate) struct Exact {
    pub version: u64,
    pub key: StateKey,
    pub signal: Arc<Vec<DVec3>>,
}

/// What determines a result: the gains per level and the moves.
#[derive(Clone, PartialEq)]
pub(crate) struct StateKey {
    pub gains: LevelGains,
    pub moves: Vec<LevelMove>,
}

/// What the worker and the background thread share.
#[derive(Default)]
struct Work {
    /// The latest state asked for, with its number and when.
    wanted: Option<(u64, StateKey)>,
    wanted_at: Option<Instant>,
    /// The latest exact result.
    exact: Option<Exact>,
    /// Octaves `(index, lo, hi)` whose displacements are still to measure, in order.
    todo: Vec<(usize, usize, usize)>,
    /// Measured displacements the worker has not taken yet.
    done: Vec<(usize, Vec<[f32; 3]>)>,
    /// How many octaves were asked for, and measured.
    fine_total: usize,
    fine_measured: usize,
    /// What the thread is doing (`None`: waiting).
    busy: Option<&'static str>,
    stop: bool,
}

/// The handle the worker keeps; dropping it stops the thread after its current task.
pub(crate) struct Background {
    shared: Arc<(Mutex<Work>, Condvar)>,
}

impl Background {
    /// Starts the thread for `pyramid`, to measure the displacements of `octaves`
    /// (`(index, lo, hi)`) at vertices `0..shown`, on a pool of all cores but one.
    pub fn start(
        pyramid: Arc<Pyramid>,
        octaves: Vec<(usize, usize, usize)>,
        shown: usize,
    ) -> Background {
        let shared = Arc::new((
            Mutex::new(Work {
                fine_total: octaves.len(),
                todo: octaves,
                ..Work::default()
            }),
            Condvar::new(),
        ));
        let theirs = Arc::clone(&shared);
        let threads =
            std::thread::available_parallelism().map_or(1, |n| n.get().saturating_sub(1).max(1));
        std::thread::spawn(move || {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build();
            match pool {
                Ok(pool) => pool.install(|| serve(&pyramid, &theirs, shown)),
                Err(_) => serve(&pyramid, &theirs, shown),
            }
        });
        Background { shared }
    }

    fn lock(&self) -> MutexGuard<'_, Work> {
        self.shared.0.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Asks for the exact result of state `key`, numbered `version` (later numbers replace
    /// earlier ones that have not started).
    pub fn want(&self, version: u64, key: StateKey) {
        let mut work = self.lock();
        let known = work.exact.as_ref().is_some_and(|e| e.key == key);
        if known {
            if let Some(e) = work.exact.as_mut() {
                e.version = version;
            }
        } else {
            work.wanted = Some((version, key));
            work.wanted_at = Some(Instant::now());
            self.shared.1.notify_all();
        }
    }

    /// The latest exact result, if any.
    pub fn exact(&self) -> Option<Exact> {
        self.lock().exact.clone()
    }

    /// Displacements measured since the last call.
    pub fn take_measured(&self) -> Vec<(usize, Vec<[f32; 3]>)> {
        std::mem::take(&mut self.lock().done)
    }

    /// `(measured, total)` fine octaves, and what the thread is doing.
    pub fn progress(&self) -> (usize, usize, Option<&'static str>) {
        let work = self.lock();
        (work.fine_measured, work.fine_total, work.busy)
    }
}

impl Drop for Background {
    fn drop(&mut self) {
        self.lock().stop = true;
        self.shared.1.notify_all();
    }
}

/// The thread's loop: exact results first (the page waits for them), then displacements.
fn serve(pyramid: &Pyramid, shared: &(Mutex<Work>, Condvar), shown: usize) {
    let p = &pyramid.pyramid;
    let mut cache = SynthesisCache::octaves(p);
    let mut unit: Option<Vec<DVec3>> = None;
    let lock = || shared.0.lock().unwrap_or_else(|e| e.into_inner());
    loop {
        let mut work = lock();
        while !work.stop && work.wanted.is_none() && work.todo.is_empty() {
            work = shared.1.wait(work).unwrap_or_else(|e| e.into_inner());
        }
        if work.stop {
            return;
        }
        let settling = work
            .wanted_at
            .map(|at| at.elapsed())
            .filter(|&waited| waited < SETTLE);
        if let Some(waited) = settling {
            drop(shared.1.wait_timeout(work, SETTLE - waited));
            continue;
        }
        if let Some((version, key)) = work.wanted.take() {
            work.busy = Some("exact");
            drop(work);
            let signal = if key.moves.is_empty() {
                Ok(cache.synthesize(p, &key.gains).to_vec())
            } else {
                p.edit_levels(&key.moves, &key.gains)
            };
            let mut work = lock();
            work.busy = None;
            // Moves were checked before they were sent, so an error is not expected; the page
            // then keeps its preview and export reports the error itself.
            if let Ok(signal) = signal {
                work.exact = Some(Exact {
                    version,
                    key,
                    signal: Arc::new(signal),
                });
            }
            continue;
        }
        let (octave, lo, hi) = work.todo.remove(0);
        work.busy = Some("octaves");
        drop(work);
        let base =
            unit.get_or_insert_with(|| cache.synthesize(p, &LevelGains::unit())[..shown].to_vec());
        let without = Filter::new().gain(lo, hi, 0.0).resolve(p.surface_area());
        let zeroed = cache.synthesize(p, &without);
        let displacement = base
            .iter()
            .zip(zeroed)
            .map(|(&a, &b)| (a - b).to_array().map(|x| x as f32))
            .collect();
        let mut work = lock();
        work.busy = None;
        work.done.push((octave, displacement));
        work.fine_measured += 1;
    }
}
