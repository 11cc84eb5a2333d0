//! Waves of independent splits, so synthesis and analysis can run on several threads and still
//! give the bits of the sequential order.
//!
//! Split `k` reads the values of its local table and writes those of its touched vertices (the
//! first `t` entries). Two splits conflict when one writes a vertex the other reads. A split's
//! wave is one more than the latest wave of an earlier split it conflicts with (as soon as
//! possible), so within a wave no split reads what another writes: they can run in any order,
//! or at once, and every split sees exactly the values it sees in the sequential order. Waves
//! run one after the other.
//!
//! On a scan most splits of the fine levels fall in large waves; the first coarse splits form a
//! chain of waves of one.
//!
//! Within a wave the splits are stored by a spatial key (the Morton code of the new vertex), and
//! [`run_waves`] gives each thread the same stretch of every wave, so a thread keeps working on
//! one region of the surface and finds the values it reads in its own cache instead of the
//! other core's (docs/performance.md, "Detail pyramid: parallelism, speed and memory").

use glam::DVec3;
use std::ops::Range;
use std::sync::atomic::Ordering::{Acquire, Relaxed, Release};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize};

/// The splits of a pyramid grouped by wave, and where each is stored: the pyramid keeps its
/// records wave after wave (within a wave by a spatial key, see [`Waves::schedule`]), so that
/// synthesis reads them front to back.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Waves {
    /// The split stored at each slot.
    split_at: Vec<u32>,
    /// The slot of each split.
    slot_of: Vec<u32>,
    /// Wave `w` occupies slots `starts[w]..starts[w + 1]`.
    starts: Vec<u32>,
}

impl Waves {
    /// Schedules `n_splits` splits; `record(k)` gives split `k`'s local table (the vertices it
    /// reads, all below `n_values`) and how many of them, from the front, it writes. Within a
    /// wave the splits are stored by `key` (ties in split order): a spatial key puts splits
    /// near on the surface near in the wave, so a thread that runs a stretch of each wave keeps
    /// working on the same region and finds its vertices in its own cache.
    pub(crate) fn schedule<'a>(
        n_splits: usize,
        n_values: usize,
        record: impl Fn(usize) -> (&'a [u32], usize),
        key: impl Fn(usize) -> u64,
    ) -> Waves {
        // Latest wave that wrote / read each vertex (0: none yet).
        let mut last_write = vec![0u32; n_values];
        let mut last_read = vec![0u32; n_values];
        let mut wave_of = Vec::with_capacity(n_splits);
        let mut n_waves = 0;
        for k in 0..n_splits {
            let (reads, n_writes) = record(k);
            let writes = &reads[..n_writes];
            // Writes are reads too, so reading after a write and writing after a write both
            // show up in `last_write` of the reads.
            let after = reads
                .iter()
                .map(|&x| last_write[x as usize])
                .chain(writes.iter().map(|&x| last_read[x as usize]))
                .max()
                .unwrap_or(0);
            let wave = after + 1;
            for &x in reads {
                let r = &mut last_read[x as usize];
                *r = (*r).max(wave);
            }
            for &x in writes {
                last_write[x as usize] = wave;
            }
            wave_of.push(wave);
            n_waves = n_waves.max(wave as usize);
        }
        // Counting sort by wave (numbered from 1), then each wave by key.
        let mut starts = vec![0u32; n_waves + 1];
        for &w in &wave_of {
            starts[w as usize] += 1;
        }
        let mut at = 0;
        for s in &mut starts {
            let count = *s;
            *s = at;
            at += count;
        }
        // `starts[w]` is where wave w begins; renumber the waves from 0 below.
        let mut fill: Vec<u32> = starts[1..].to_vec();
        let mut split_at = vec![0u32; n_splits];
        for (k, &w) in wave_of.iter().enumerate() {
            let slot = &mut fill[w as usize - 1];
            split_at[*slot as usize] = k as u32;
            *slot += 1;
        }
        starts.remove(0);
        starts.push(n_splits as u32);
        for w in starts.windows(2) {
            split_at[w[0] as usize..w[1] as usize].sort_unstable_by_key(|&k| (key(k as usize), k));
        }
        let mut slot_of = vec![0u32; n_splits];
        for (slot, &k) in split_at.iter().enumerate() {
            slot_of[k as usize] = slot as u32;
        }
        Waves {
            split_at,
            slot_of,
            starts,
        }
    }

    /// Number of waves.
    pub(crate) fn len(&self) -> usize {
        self.starts.len().saturating_sub(1)
    }

    /// The slot where split `k` is stored.
    #[inline]
    pub(crate) fn slot_of(&self, k: usize) -> usize {
        self.slot_of[k] as usize
    }

    /// The split stored at `slot`.
    #[inline]
    pub(crate) fn split_at(&self, slot: usize) -> usize {
        self.split_at[slot] as usize
    }

    /// The slots of wave `w`.
    pub(crate) fn wave(&self, w: usize) -> Range<usize> {
        self.starts[w] as usize..self.starts[w + 1] as usize
    }

    /// Heap memory in bytes.
    pub(crate) fn memory_bytes(&self) -> usize {
        4 * (self.split_at.len() + self.slot_of.len() + self.starts.len())
    }
}

/// Waves with fewer splits than this run on one thread, consecutive ones as a single task:
/// handing a few splits to other threads costs more than it saves.
const PARALLEL_WAVE: usize = 24;

/// A signal (one `DVec3` per vertex) that the threads running a wave share: every thread reads
/// and writes it through relaxed atomics, so a split scheduled wrongly could only compute a
/// wrong value, never race. On x86_64 and aarch64 a relaxed atomic load or store is a plain
/// load or store.
pub(crate) struct SharedSignal<'a> {
    cells: &'a [[AtomicU64; 3]],
}

impl<'a> SharedSignal<'a> {
    /// Shares `values` for as long as the view lives.
    pub(crate) fn new(values: &'a mut [DVec3]) -> Self {
        const {
            assert!(std::mem::size_of::<DVec3>() == std::mem::size_of::<[AtomicU64; 3]>());
            // Fails to compile where a u64 atomic needs more alignment than an f64 (i686).
            assert!(std::mem::align_of::<AtomicU64>() <= std::mem::align_of::<DVec3>());
        }
        // SAFETY: `DVec3` is `#[repr(C)]` of three `f64`, each the size of an `AtomicU64`, whose
        // alignment is no stricter (checked above); the exclusive borrow lasts as long as the
        // view, so nothing else reads or writes the memory meanwhile, and every access through
        // the view is atomic.
        let cells = unsafe {
            std::slice::from_raw_parts(values.as_mut_ptr().cast::<[AtomicU64; 3]>(), values.len())
        };
        SharedSignal { cells }
    }

    /// The value of vertex `i`.
    #[inline(always)]
    pub(crate) fn get(&self, i: usize) -> DVec3 {
        let c = &self.cells[i];
        DVec3::new(
            f64::from_bits(c[0].load(Relaxed)),
            f64::from_bits(c[1].load(Relaxed)),
            f64::from_bits(c[2].load(Relaxed)),
        )
    }

    /// A cache hint for vertex `i`'s value (any `i`: it is never dereferenced).
    #[inline(always)]
    pub(crate) fn prefetch(&self, i: usize) {
        crate::pm::prefetch::prefetch(self.cells.as_ptr().wrapping_add(i));
    }

    /// Sets the value of vertex `i`.
    #[inline(always)]
    pub(crate) fn set(&self, i: usize, v: DVec3) {
        let c = &self.cells[i];
        c[0].store(v.x.to_bits(), Relaxed);
        c[1].store(v.y.to_bits(), Relaxed);
        c[2].store(v.z.to_bits(), Relaxed);
    }
}

/// Runs the splits of `waves` (slot ranges, in the order given) with the bits of running them
/// one at a time in that order. `run(slot, scratch)` computes one split and writes its results
/// (through [`SharedSignal`]s it holds); each thread has its own `scratch`. `progress` hears the
/// share of splits done, from the calling thread only, so it never goes backwards.
///
/// A wave of [`PARALLEL_WAVE`] splits or more is cut into [`BLOCKS_PER_THREAD`] blocks per
/// thread; consecutive smaller waves form one block, which the calling thread runs. Every
/// thread walks the waves in order: it claims and runs the unclaimed blocks of a wave, its own
/// stretch first (thread `t` of `n` owns the `t`-th `n`-th of the blocks: the same region of
/// the surface wave after wave, since waves are stored by a spatial key), then any other, and
/// waits until all blocks of the wave are done before the next. A split thus sees exactly
/// what it sees in the sequential order, as no split of its wave writes what it reads or reads
/// what it writes. A thread that the pool lends late, or never, only leaves its stretch to the
/// others: nobody waits for a block that nobody runs.
pub(crate) fn run_waves<B: Default + Send>(
    waves: impl Iterator<Item = Range<usize>>,
    progress: impl Fn(f64) + Sync,
    run: impl Fn(usize, &mut B) + Sync,
    release: impl Fn(Range<usize>) + Sync,
) {
    let threads = rayon::current_num_threads();
    // Blocks (slot ranges), and the stages that group them: a large wave's blocks, or the
    // ranges of a run of small waves.
    let mut blocks: Vec<Range<usize>> = Vec::new();
    let mut stages: Vec<Stage> = Vec::new();
    let mut splits = 0;
    for slots in waves.filter(|w| !w.is_empty()) {
        splits += slots.len();
        let small = threads == 1 || slots.len() < PARALLEL_WAVE;
        match stages.last_mut() {
            Some(last) if small && last.serial => last.blocks.end += 1,
            _ => stages.push(Stage {
                serial: small,
                blocks: blocks.len()..blocks.len() + usize::from(small),
                splits_after: 0,
            }),
        }
        let stage = stages.last_mut().expect("just pushed or extended");
        stage.splits_after = splits;
        if small {
            blocks.push(slots);
            continue;
        }
        let per_block = slots.len().div_ceil(BLOCKS_PER_THREAD * threads);
        let mut start = slots.start;
        while start < slots.end {
            let end = (start + per_block).min(slots.end);
            blocks.push(start..end);
            start = end;
        }
        stage.blocks.end = blocks.len();
    }
    let claimed: Vec<AtomicBool> = (0..blocks.len()).map(|_| AtomicBool::new(false)).collect();
    let done = AtomicUsize::new(0);
    // Set when a thread panics: its blocks will never be done, so the others stop waiting
    // and the panic reaches the caller (through `rayon::scope`) instead of a hang.
    let poisoned = AtomicBool::new(false);
    let total = splits.max(1) as f64;
    let work = |thread: usize| {
        let _poison = PoisonOnUnwind(&poisoned);
        let mut scratch = B::default();
        for stage in &stages {
            let ids = stage.blocks.clone();
            if stage.serial {
                // Small waves stay on the calling thread: their splits depend on each other.
                if thread == 0 {
                    for slots in &blocks[ids.clone()] {
                        run_block(slots.clone(), &run, &release, &mut scratch);
                    }
                    done.fetch_add(ids.len(), Release);
                }
            } else {
                let own = ids.start + ids.len() * thread / threads;
                for i in (own..ids.end).chain(ids.start..own) {
                    if !claimed[i].swap(true, Relaxed) {
                        run_block(blocks[i].clone(), &run, &release, &mut scratch);
                        // Release: whoever sees the count sees the block's writes.
                        done.fetch_add(1, Release);
                    }
                }
            }
            if !wait_until_done(&done, ids.end, &poisoned) {
                return;
            }
            if thread == 0 {
                progress(stage.splits_after as f64 / total);
            }
        }
    };
    if threads == 1 || stages.iter().all(|s| s.serial) {
        work(0);
    } else {
        rayon::scope(|s| {
            for thread in 1..threads {
                s.spawn(move |_| work(thread));
            }
            work(0);
        });
    }
}

/// Splits [`run_block`] runs before it hands their records back.
const RELEASE_EVERY: usize = 1 << 12;

/// Runs the splits `slots` of one block, telling `release` after every [`RELEASE_EVERY`] of
/// them that their records are done with (a layout in a file then keeps only the pages in use
/// resident).
fn run_block<B>(
    slots: Range<usize>,
    run: &impl Fn(usize, &mut B),
    release: &impl Fn(Range<usize>),
    scratch: &mut B,
) {
    let mut start = slots.start;
    while start < slots.end {
        let end = (start + RELEASE_EVERY).min(slots.end);
        (start..end).for_each(|slot| run(slot, scratch));
        release(start..end);
        start = end;
    }
}

/// A wave, or a run of consecutive small waves, of [`run_waves`].
struct Stage {
    /// Run by the calling thread alone, block after block.
    serial: bool,
    /// Its blocks.
    blocks: Range<usize>,
    /// Splits in this and all earlier stages.
    splits_after: usize,
}

/// Blocks per thread of a large wave: several, so a thread that finishes its stretch early
/// can take over part of a slower one's.
const BLOCKS_PER_THREAD: usize = 4;

/// Sets its flag when dropped during a panic.
struct PoisonOnUnwind<'a>(&'a AtomicBool);

impl Drop for PoisonOnUnwind<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.store(true, Release);
        }
    }
}

/// Waits until `done` reaches `target` (`true`) or another thread panicked (`false`):
/// spinning first (a wave's blocks take microseconds), then yielding the core, which matters
/// when threads outnumber free cores.
#[inline]
fn wait_until_done(done: &AtomicUsize, target: usize, poisoned: &AtomicBool) -> bool {
    let mut spins = 0u32;
    while done.load(Acquire) < target {
        if poisoned.load(Acquire) {
            return false;
        }
        if spins < 2000 {
            std::hint::spin_loop();
            spins += 1;
        } else {
            std::thread::yield_now();
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Schedules records given as (local table, number written), in split order within waves.
    fn schedule(records: &[(&[u32], usize)], n_values: usize) -> Waves {
        Waves::schedule(records.len(), n_values, |k| records[k], |_| 0)
    }

    /// The splits of wave `wave` that lie in `range`, in storage order.
    fn splits_of(w: &Waves, wave: usize, range: Range<usize>) -> Vec<usize> {
        w.wave(wave)
            .map(|s| w.split_at(s))
            .filter(|k| range.contains(k))
            .collect()
    }

    #[test]
    fn conflicting_splits_go_to_later_waves() {
        // Split 0 writes 0 (reads 0, 1); split 1 writes 2 (reads 2, 3): independent.
        // Split 2 writes 1 (read by split 0): must follow split 0. Split 3 reads 0 (written by
        // split 0) and writes 4. Split 4 writes 5, reads 6: independent of all.
        let w = schedule(
            &[
                (&[0, 1], 1),
                (&[2, 3], 1),
                (&[1], 1),
                (&[4, 0], 1),
                (&[5, 6], 1),
            ],
            7,
        );
        assert_eq!(w.len(), 2);
        assert_eq!(splits_of(&w, 0, 0..5), [0, 1, 4]);
        assert_eq!(splits_of(&w, 1, 0..5), [2, 3]);
        assert_eq!(splits_of(&w, 0, 1..4), [1]);
        assert_eq!(splits_of(&w, 1, 1..4), [2, 3]);
        assert_eq!(splits_of(&w, 1, 3..3), Vec::<usize>::new());
        for k in 0..5 {
            assert_eq!(w.split_at(w.slot_of(k)), k);
        }
        assert_eq!(w.memory_bytes(), 4 * (5 + 5 + 3));
    }

    #[test]
    fn a_wave_stores_its_splits_by_key() {
        // Four independent splits, keyed in reverse, and a fifth after split 0, keyed lowest.
        let records: [(&[u32], usize); 5] = [(&[0], 1), (&[1], 1), (&[2], 1), (&[3], 1), (&[0], 1)];
        let keys = [4, 3, 3, 1, 0];
        let w = Waves::schedule(5, 4, |k| records[k], |k| keys[k]);
        assert_eq!(w.len(), 2);
        // Equal keys keep split order.
        assert_eq!(splits_of(&w, 0, 0..5), [3, 1, 2, 0]);
        assert_eq!(splits_of(&w, 1, 0..5), [4]);
        for k in 0..5 {
            assert_eq!(w.split_at(w.slot_of(k)), k);
        }
    }

    #[test]
    fn a_write_after_a_read_waits_for_the_reader() {
        // Split 0 writes 0 and reads 1; split 1 writes 1. Split 1 may not overwrite 1 before
        // split 0 has read it.
        let w = schedule(&[(&[0, 1], 1), (&[1], 1)], 2);
        assert_eq!(w.len(), 2);
        assert_eq!(splits_of(&w, 1, 0..2), [1]);
    }

    #[test]
    fn no_splits_no_waves() {
        let w = schedule(&[], 0);
        assert_eq!(w.len(), 0);
        assert_eq!(w.memory_bytes(), 4);
    }

    /// Splits over `n` values: split `k` reads three scattered values and writes the first,
    /// with a mix that depends on the order of every conflicting pair. The first hundred form
    /// a chain, so waves big and small alternate.
    fn ring_records(n: usize, n_splits: usize) -> Vec<[u32; 3]> {
        let scatter = |k: usize, i: u64| {
            let h = (k as u64 * 3 + i).wrapping_mul(0x9e37_79b9_7f4a_7c15) >> 40;
            h as usize % n
        };
        (0..n_splits)
            .map(|k| {
                if k < 100 {
                    [k % n, (k + 1) % n, (k + 2) % n].map(|x| x as u32)
                } else {
                    [scatter(k, 0), scatter(k, 1), scatter(k, 2)].map(|x| x as u32)
                }
            })
            .collect()
    }

    fn run_ring(records: &[[u32; 3]], n: usize, waves: &Waves, threads: usize) -> Vec<DVec3> {
        let mut f: Vec<DVec3> = (0..n).map(|i| DVec3::splat(i as f64)).collect();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a thread pool");
        let reported = std::sync::Mutex::new(Vec::new());
        let released = std::sync::Mutex::new(Vec::new());
        pool.install(|| {
            let shared = SharedSignal::new(&mut f);
            run_waves(
                (0..waves.len()).map(|w| waves.wave(w)),
                |p| reported.lock().expect("not poisoned").push(p),
                |slot, scratch: &mut Vec<DVec3>| {
                    let r = records[waves.split_at(slot)];
                    scratch.clear();
                    scratch.extend(r.iter().map(|&x| shared.get(x as usize)));
                    let v = scratch[0] * 0.5 + scratch[1].cross(DVec3::X) + scratch[2] * 0.25;
                    shared.set(r[0] as usize, v + DVec3::ONE);
                },
                |slots| released.lock().expect("not poisoned").push(slots),
            );
        });
        // Every split's records are handed back once, after it ran.
        let mut released = released.into_inner().expect("not poisoned");
        released.sort_by_key(|r| r.start);
        assert!(released.windows(2).all(|r| r[0].end == r[1].start));
        assert_eq!(
            released.first().map(|r| r.start)..released.last().map(|r| r.end),
            Some(0)..Some(records.len())
        );
        let reported = reported.into_inner().expect("not poisoned");
        assert!(
            reported.windows(2).all(|p| p[0] <= p[1]),
            "progress never goes back"
        );
        assert_eq!(reported.last().copied(), Some(1.0));
        f
    }

    #[test]
    fn waves_on_any_number_of_threads_give_the_sequential_bits() {
        let n = 2000;
        let records = ring_records(n, 9000);
        // Keys that scatter each wave, so blocks do not follow split order.
        let waves = Waves::schedule(
            records.len(),
            n,
            |k| (&records[k][..], 1),
            |k| (k as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15),
        );
        let sizes: Vec<usize> = (0..waves.len()).map(|w| waves.wave(w).len()).collect();
        assert!(sizes.iter().any(|&s| s >= 4 * PARALLEL_WAVE), "{sizes:?}");
        assert!(
            sizes.iter().filter(|&&s| s < PARALLEL_WAVE).count() >= 10,
            "{sizes:?}"
        );
        // The sequential order, without waves.
        let mut expected: Vec<DVec3> = (0..n).map(|i| DVec3::splat(i as f64)).collect();
        for r in &records {
            let [a, b, c] = r.map(|x| expected[x as usize]);
            expected[r[0] as usize] = a * 0.5 + b.cross(DVec3::X) + c * 0.25 + DVec3::ONE;
        }
        for threads in [1, 2, 3, 8] {
            assert_eq!(
                run_ring(&records, n, &waves, threads),
                expected,
                "{threads} threads"
            );
        }
    }

    #[test]
    fn a_panicking_split_reaches_the_caller_instead_of_hanging() {
        let n = 2000;
        let records = ring_records(n, 9000);
        let waves = Waves::schedule(records.len(), n, |k| (&records[k][..], 1), |_| 0);
        let bad = (0..waves.len())
            .map(|w| waves.wave(w))
            .find(|w| w.len() >= 4 * PARALLEL_WAVE)
            .expect("a large wave")
            .start;
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a thread pool");
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                pool.install(|| {
                    run_waves(
                        (0..waves.len()).map(|w| waves.wave(w)),
                        |_| {},
                        |slot, _: &mut ()| assert_ne!(slot, bad, "split at slot {slot} fails"),
                        |_| {},
                    )
                })
            }));
            assert!(result.is_err(), "{threads} threads: the panic is lost");
        }
    }
}
