//! Analysis (`docs/algorithms.md` §1c): finest → coarsest, one half-edge collapse at a time.
//!
//! At level `n` (vertex `n − 1` is about to be removed, `t` is the vertex it collapses into):
//! 1. record the level's relaxation weights of the removed vertex and of its 1-ring, computed
//!    from the **original** positions and the level's connectivity, and their 1-ring fans;
//! 2. presmooth the 1-ring with those weights (Jacobi: all from `f^(n)`);
//! 3. collapse — `f^(n−1)` is the presmoothed signal without the removed vertex;
//! 4. predict the removed vertex, then its 1-ring, from `f^(n−1)` (the subdivision step `S_n`);
//! 5. store `d_j = F_j (f^(n)_j − q_j)` in the frames of the predicted geometry.
//!
//! Presmoothing only changes vertices the synthesis overwrites with `q + d`, so the pyramid
//! reconstructs exactly whatever the presmoothing does (the Burt–Adelson property).
//!
//! Steps 4 and 5 run in a second pass, coarsest split first (module `quantise`): the walk down
//! keeps each split's targets `f^(n)_j`, and the details are quantised against the
//! predictions synthesis itself makes, so that rounding does not add up across levels.
//!
//! Step 1 never reads the signal, and it is most of the work (the hinge coefficients), so it
//! runs first, for all splits, on rayon's threads: the hierarchy is cut into contiguous ranges
//! of splits, each recorded on its own thread from the very mesh the single walk would have
//! there, so the records and the pyramid do not depend on the thread count. Operators with
//! ring stencils (Guskov's) walk a [`FlatReplay`] up from the base, replaying the splits
//! before their range first: its rings are the half-edge mesh's circulations, slots included,
//! in one or two cache lines per vertex instead of linked 48-byte records, and the record
//! walk is bound by memory, not arithmetic. The others walk a half-edge cursor down from the
//! finest level. Steps 2–3 then run over the records, finest split first, and steps 4–5
//! coarsest first; like synthesis, both run the splits of a wave (see `waves`) at once.

use super::frames::LocalIndex;
use super::quantise::{detail_step, signal_diagonal};
use super::synthesis::{Scratch, decode, prefetch_next_split, presmooth_local};
use super::waves::{SharedSignal, Waves, run_waves};
use super::{CodeWidth, Codes, DetailPyramid, PyramidError, SplitOffsets};
use crate::mesh::geometry::morton_codes;
use crate::mesh::{SlotIndex, VertexId};
use crate::pm::{FlatReplay, PmCursor, ProgressiveMesh};
use crate::progress::Progress;
use crate::relax::{Relaxation, RingStencils};
use glam::DVec3;

impl DetailPyramid {
    /// Analyses the original positions of `pm` (the surface itself).
    pub fn analyze(
        pm: &ProgressiveMesh,
        relaxation: &dyn Relaxation,
        progress: &dyn Progress,
    ) -> Result<DetailPyramid, PyramidError> {
        Self::analyze_signal(pm, relaxation, pm.original_positions(), progress)
    }

    /// Analyses `signal` (PM order, one value per PM vertex including the ones without faces)
    /// on the hierarchy of `pm`. The weights always come from the original positions, so two
    /// signals on the same PM — say a scan and its filtered version — have comparable details.
    pub fn analyze_signal(
        pm: &ProgressiveMesh,
        relaxation: &dyn Relaxation,
        signal: &[DVec3],
        progress: &dyn Progress,
    ) -> Result<DetailPyramid, PyramidError> {
        let geometry = pm.original_positions();
        if signal.len() != geometry.len() {
            return Err(PyramidError::Invalid(format!(
                "signal has {} values, the progressive mesh has {} vertices",
                signal.len(),
                geometry.len()
            )));
        }
        let layout = Layout::record(pm, relaxation, progress)?;
        // Steps 2–3, finest split first: waves in reverse storage order, which, like split
        // order, runs every split after the splits it depends on.
        let mut f = signal.to_vec();
        let slotted = &layout.slotted;
        let mut targets = vec![DVec3::ZERO; slotted.offsets.last().map_or(0, |o| o.details)];
        with_codes!(&slotted.codes, c => {
            slotted.downsample(c, &layout.waves, &mut f, &mut targets, progress)
        });
        let base = f[..layout.n_base].to_vec();
        drop(f);
        // Steps 4–5 in synthesis order, quantised in the closed loop.
        let step = detail_step(signal_diagonal(signal));
        let mut pyramid = layout.into_pyramid(relaxation, signal, base, Vec::new(), step);
        let done = RECORDS_SHARE + DOWNSAMPLE_SHARE;
        pyramid.details =
            pyramid.quantise_details(targets, |x| progress.update(done + (1.0 - done) * x));
        progress.update(1.0);
        Ok(pyramid)
    }
}

/// The signal-independent part of a pyramid (step 1 for every split, in storage order): what
/// synthesis needs besides the base signal and the details.
pub(crate) struct Layout {
    pub(crate) n_base: usize,
    pub(crate) n_finest: usize,
    pub(crate) surface_area: f64,
    pub(crate) bbox_diagonal: f64,
    pub(crate) waves: Waves,
    slotted: Slotted,
}

impl Layout {
    /// Step 1 for every split of `pm`, then the storage order: wave by wave (see `waves`).
    /// Reports progress from 0 to [`RECORDS_SHARE`].
    pub(crate) fn record(
        pm: &ProgressiveMesh,
        relaxation: &dyn Relaxation,
        progress: &dyn Progress,
    ) -> Result<Layout, PyramidError> {
        let geometry = pm.original_positions();
        let n_base = pm.n_base_vertices();
        let n_finest = pm.n_vertices();
        let n_splits = n_finest - n_base;
        let (surface_area, bbox_diagonal) = surface_stats(&geometry[..n_finest], pm.finest_faces());
        let ranges = split_ranges(n_splits, rayon::current_num_threads());
        let cursor = relaxation.as_ring_stencils().is_none().then(|| pm.cursor());
        let mut records = record_ranges(pm, relaxation, cursor, &ranges, progress)?;
        // One code width for the pyramid: the widest range's.
        let widest = records.iter().map(|r| r.widest).max().unwrap_or(0);
        for r in &mut records {
            r.codes.widen_to(widest);
        }
        // Waves store their splits by the place of the new vertex (see `run_waves`).
        let morton = morton_codes(&geometry[n_base..n_finest]);
        let waves = Waves::schedule(
            n_splits,
            geometry.len(),
            |k| {
                let (rec, i) = record_of(&records, k);
                let (o, next) = (rec.offsets[i], rec.offsets[i + 1]);
                (&rec.locals[o.locals..next.locals], next.details - o.details)
            },
            |k| morton.as_ref().map_or(0, |m| m[k]),
        );
        let slotted = Slotted::new(records, &waves);
        Ok(Layout {
            n_base,
            n_finest,
            surface_area,
            bbox_diagonal,
            waves,
            slotted,
        })
    }

    /// How many details split `k` carries (its touched vertices: the new vertex and its ring).
    pub(crate) fn details_of_split(&self, k: usize) -> usize {
        let slot = self.waves.slot_of(k);
        self.slotted.offsets[slot + 1].details - self.slotted.offsets[slot].details
    }

    /// Where split `k`'s details start in storage order.
    pub(crate) fn details_start(&self, k: usize) -> usize {
        self.slotted.offsets[self.waves.slot_of(k)].details
    }

    /// Total number of details.
    pub(crate) fn n_details(&self) -> usize {
        self.slotted.offsets.last().map_or(0, |o| o.details)
    }

    /// The pyramid of `signal` with this layout, its `base` signal and `details` (storage
    /// order).
    pub(crate) fn into_pyramid(
        self,
        relaxation: &dyn Relaxation,
        signal: &[DVec3],
        base: Vec<DVec3>,
        details: Vec<[i32; 3]>,
        detail_step: f64,
    ) -> DetailPyramid {
        let Layout {
            n_base,
            n_finest,
            surface_area,
            bbox_diagonal,
            waves,
            slotted,
        } = self;
        DetailPyramid {
            n_base,
            n_finest,
            passthrough: signal[n_finest..].to_vec(),
            base,
            offsets: slotted.offsets,
            locals: slotted.locals,
            codes: slotted.codes,
            weights: slotted.weights,
            details,
            waves,
            relaxation: relaxation.name(),
            detail_step,
            surface_area,
            bbox_diagonal,
        }
    }
}

/// The share of the analysis' time the records take (the progress bar's split between the
/// three phases; about two thirds with Guskov's operator).
pub(crate) const RECORDS_SHARE: f64 = 0.7;

/// The share of the walk down (presmoothing and collapsing); the closed loop takes the rest.
const DOWNSAMPLE_SHARE: f64 = 0.1;

/// Splits per range below which one thread records them all: a range's walk first reaches the
/// start of its range (a replay from the base, or a cursor collapsing from the finest level),
/// which only pays off on long ranges.
const SPLITS_PER_RANGE: usize = 1024;

/// Cuts splits `0..n_splits` into at most `threads` contiguous ranges of near-equal length,
/// coarsest first.
fn split_ranges(n_splits: usize, threads: usize) -> Vec<std::ops::Range<usize>> {
    let n = threads.clamp(1, (n_splits / SPLITS_PER_RANGE).max(1));
    (0..n)
        .map(|r| r * n_splits / n..(r + 1) * n_splits / n)
        .collect()
}

/// Step 1 for every range of splits (coarsest range first), each range on its own thread.
/// Operators with ring stencils walk a [`FlatReplay`] up from the base (each range replays
/// the splits before it first, which is cheap); the others walk a half-edge cursor down from
/// the finest level (`cursor` serves the finest range). The range a single walk would record
/// first reports progress: the coarsest on the replay, the finest on the cursor.
fn record_ranges(
    pm: &ProgressiveMesh,
    relaxation: &dyn Relaxation,
    cursor: Option<PmCursor<'_>>,
    ranges: &[std::ops::Range<usize>],
    progress: &dyn Progress,
) -> Result<Vec<Records>, PyramidError> {
    use rayon::prelude::*;
    let finest = ranges.len() - 1;
    let quiet = crate::progress::NoProgress;
    if let Some(rings) = relaxation.as_ring_stencils() {
        return ranges
            .par_iter()
            .enumerate()
            .map(|(r, range)| {
                let report: &dyn Progress = if r == 0 { progress } else { &quiet };
                record_range_on_rings(pm, rings, range.clone(), report)
            })
            .collect();
    }
    let mut cursors: Vec<Option<PmCursor<'_>>> = ranges.iter().map(|_| None).collect();
    cursors[finest] = cursor;
    cursors
        .into_par_iter()
        .zip(ranges)
        .enumerate()
        .map(|(r, (cursor, range))| {
            let mut cursor = cursor.unwrap_or_else(|| pm.cursor());
            cursor.seek(pm.n_base_vertices() + range.end);
            let report: &dyn Progress = if r == finest { progress } else { &quiet };
            record_range(pm, relaxation, cursor, range.clone(), report)
        })
        .collect()
}

/// How many splits ahead the recording walk hints the neighbourhood its stencils will read.
const STENCIL_PREFETCH_AHEAD: usize = 4;

/// Step 1 for splits `range` on a [`FlatReplay`], coarsest first: after split `k`, its new
/// vertex, its ring and their stencils and fans are those of level `n0 + k + 1`.
fn record_range_on_rings(
    pm: &ProgressiveMesh,
    rings: &dyn RingStencils,
    range: std::ops::Range<usize>,
    progress: &dyn Progress,
) -> Result<Records, PyramidError> {
    let geometry = pm.original_positions();
    let n_base = pm.n_base_vertices();
    let internal = |e: crate::pm::PmError| PyramidError::Internal(e.to_string());
    let mut replay =
        FlatReplay::new(&geometry[..n_base], &pm.base_triangles(), range.end).map_err(internal)?;
    let splits = pm.splits();
    // Hints for the splits ahead, as the `.pyr` reader gives them, and for the stencils'
    // neighbourhoods: the replay and the stencils read rings scattered over the arrays.
    let survivor = |j: usize| splits.get(j).map(|t| t.survivor);
    let hint_stencils = |replay: &FlatReplay, k: usize| {
        if let Some(s) = survivor(k + STENCIL_PREFETCH_AHEAD) {
            replay.prefetch_neighbourhood(s, geometry);
        }
    };
    for (k, s) in splits[..range.start].iter().enumerate() {
        replay.prefetch_upcoming(k, survivor);
        replay.apply(s).map_err(internal)?;
    }
    let mut recorder = Recorder::new(range.clone(), geometry.len(), false);
    let mut touched: Vec<u32> = Vec::new();
    let report_every = (range.len() / 200).max(1);
    for (done, k) in range.clone().enumerate() {
        if done % report_every == 0 {
            progress.update(RECORDS_SHARE * done as f64 / range.len().max(1) as f64);
        }
        let s = &splits[k];
        replay.prefetch_upcoming(k, survivor);
        hint_stencils(&replay, k);
        replay.apply(s).map_err(internal)?;
        let v = (n_base + k) as u32;
        touched.clear();
        touched.push(v);
        touched.extend(replay.ring_entries(v).0.iter().map(|e| e.nbr));
        recorder.stencils.clear();
        recorder.stencil_lens.clear();
        let (stencils, lens) = (&mut recorder.stencils, &mut recorder.stencil_lens);
        rings.ring_stencils(&replay, geometry, &touched, stencils, lens);
        recorder.record(k, &touched, s.survivor, |j, fan| {
            let (ring, boundary) = replay.ring_entries(j);
            fan.extend(ring.iter().map(|e| e.nbr));
            boundary && !ring.is_empty()
        })?;
    }
    Ok(recorder.finish())
}

/// Step 1 for splits `range` (walked finest first, `cursor` at level `n0 + range.end`).
fn record_range(
    pm: &ProgressiveMesh,
    relaxation: &dyn Relaxation,
    mut cursor: PmCursor<'_>,
    range: std::ops::Range<usize>,
    progress: &dyn Progress,
) -> Result<Records, PyramidError> {
    let geometry = pm.original_positions();
    let n_base = pm.n_base_vertices();
    let n = range.len();
    let mut recorder = Recorder::new(range.clone(), geometry.len(), true);
    let mut stencils = Vec::new();
    let mut touched_handles: Vec<VertexId> = Vec::new();
    let mut touched: Vec<u32> = Vec::new();
    let report_every = (n / 200).max(1);
    for (done, k) in range.rev().enumerate() {
        if done % report_every == 0 {
            progress.update(RECORDS_SHARE * done as f64 / n.max(1) as f64);
        }
        let v = n_base + k;
        if cursor.level() != v + 1 {
            return Err(PyramidError::Internal(format!(
                "cursor at level {} while analysing level {}",
                cursor.level(),
                v + 1
            )));
        }
        let mesh = cursor.mesh();
        let vh = cursor.vertex(v);
        if vh.slot() != v {
            return Err(PyramidError::Internal(format!(
                "split {k}: vertex {v} has PM slot {}",
                vh.slot()
            )));
        }
        touched_handles.clear();
        touched_handles.push(vh);
        touched_handles.extend(mesh.outgoing(vh).map(|h| mesh.to_vertex(h)));
        touched.clear();
        touched.extend(touched_handles.iter().map(|j| j.slot() as u32));
        stencils.clear();
        recorder.stencil_lens.clear();
        relaxation.stencils(
            mesh,
            geometry,
            &touched_handles,
            &mut stencils,
            &mut recorder.stencil_lens,
        );
        recorder.stencils.clear();
        recorder
            .stencils
            .extend(stencils.iter().map(|&(u, w)| (u.slot() as u32, w)));
        recorder.record(k, &touched, pm.splits()[k].survivor, |j, fan| {
            let mut first = None;
            for h in mesh.outgoing(cursor.vertex(j as usize)) {
                first.get_or_insert(h);
                fan.push(mesh.to_vertex(h).slot() as u32);
            }
            first.is_some_and(|h| mesh.is_boundary_halfedge(h))
        })?;
        if !cursor.collapse() {
            return Err(PyramidError::Internal(format!(
                "cannot collapse level {}",
                v + 1
            )));
        }
    }
    Ok(recorder.finish())
}

/// Writes the records of one range of splits, split by split.
struct Recorder {
    rec: Records,
    n_touched: usize,
    /// The current split's stencils (PM indices) and their lengths, filled by the walk.
    stencils: Vec<(u32, f64)>,
    stencil_lens: Vec<usize>,
    fan: Vec<u32>,
    /// The current split's codes, appended to the range's stream (in its current width) once
    /// complete.
    split_codes: Vec<u32>,
    /// PM vertex → its index in the current split's local table (u32::MAX: not in it).
    local_of: Vec<u32>,
}

impl Recorder {
    fn new(range: std::ops::Range<usize>, n_vertices: usize, reversed: bool) -> Recorder {
        let n = range.len();
        Recorder {
            rec: Records {
                offsets: Vec::with_capacity(n + 1),
                // Reserves above the usual sizes (on scans about 32 locals, 127–135 codes
                // and 74–80 weights per split): untouched capacity costs no memory, a
                // doubling copies the stream.
                locals: Vec::with_capacity(40 * n),
                codes: Codes::Byte(Vec::with_capacity(160 * n)),
                weights: Chunked::default(),
                range,
                reversed,
                widest: 0,
            },
            n_touched: 0,
            stencils: Vec::new(),
            stencil_lens: Vec::new(),
            fan: Vec::new(),
            split_codes: Vec::new(),
            local_of: vec![u32::MAX; n_vertices],
        }
    }

    /// Records split `k` at its level: the touched vertices (the new vertex, then its ring
    /// counter-clockwise) open the local table; their stencils (from `self.stencils`) and fans
    /// (`fan(j, out)` lists `j`'s ring and says whether it starts at a boundary out-edge)
    /// follow as indices into the table, weights alongside.
    fn record(
        &mut self,
        k: usize,
        touched: &[u32],
        survivor: u32,
        mut fan: impl FnMut(u32, &mut Vec<u32>) -> bool,
    ) -> Result<(), PyramidError> {
        let rec = &mut self.rec;
        let (locals, weights) = (&mut rec.locals, &mut rec.weights);
        rec.offsets.push(SplitOffsets {
            locals: locals.len(),
            codes: rec.codes.len(),
            weights: weights.len(),
            details: self.n_touched,
        });
        let codes = &mut self.split_codes;
        codes.clear();
        let l0 = locals.len();
        let local_of = &mut self.local_of;
        let mut local = |u: u32, locals: &mut Vec<u32>| {
            let x = &mut local_of[u as usize];
            if *x == u32::MAX {
                *x = (locals.len() - l0) as u32;
                locals.push(u);
            }
            *x
        };
        for &j in touched {
            local(j, locals);
        }
        let Some(survivor_local) = touched.iter().position(|&j| j == survivor) else {
            return Err(PyramidError::Internal(format!(
                "split {k}: vertex {} is not adjacent to its survivor {survivor}",
                touched[0]
            )));
        };
        if survivor_local == 0 {
            return Err(PyramidError::Internal(format!(
                "split {k}: vertex {survivor} is its own survivor"
            )));
        }
        codes.push(touched.len() as u32);
        codes.push(survivor_local as u32);
        let mut next_stencil = 0;
        for (&j, &len) in touched.iter().zip(&self.stencil_lens) {
            let len_at = codes.len();
            codes.extend([0, 0]);
            for &(u, w) in &self.stencils[next_stencil..next_stencil + len] {
                codes.push(local(u, locals));
                // f32 is enough: synthesis anchors every stencil at its first vertex (see
                // `relax_local`), so rounding a weight moves a prediction by a fraction 1e-7 of
                // the local edge length, wherever the scan sits.
                weights.push(w as f32);
            }
            next_stencil += len;
            self.fan.clear();
            let open = fan(j, &mut self.fan);
            let fan_at = codes.len();
            for &u in &self.fan {
                codes.push(local(u, locals));
            }
            codes[len_at] = (fan_at - len_at - 2) as u32;
            codes[len_at + 1] = ((codes.len() - fan_at) as u32) << 1 | open as u32;
        }
        for &u in &locals[l0..] {
            local_of[u as usize] = u32::MAX;
        }
        rec.widest = codes.iter().fold(rec.widest, |m, &c| m.max(c));
        rec.codes.extend_widening(codes, rec.widest);
        self.n_touched += touched.len();
        Ok(())
    }

    fn finish(mut self) -> Records {
        self.rec.offsets.push(SplitOffsets {
            locals: self.rec.locals.len(),
            codes: self.rec.codes.len(),
            weights: self.rec.weights.len(),
            details: self.n_touched,
        });
        self.rec
    }
}

/// The signal-independent per-split streams of a pyramid being built; the `details` offsets
/// count the touched vertices, whose details come later. Codes are recorded as narrow as the
/// range's largest code so far allows (a byte on most meshes), not as 32-bit values narrowed
/// later: the 32-bit stream would be 4 bytes × ~130 codes per split at the analysis' peak.
struct Records {
    offsets: Vec<SplitOffsets>,
    locals: Vec<u32>,
    codes: Codes,
    /// In chunks, so that joining the ranges' weights frees them as it goes.
    weights: Chunked,
    /// The splits recorded, in the order given by `reversed` (finest first when set).
    range: std::ops::Range<usize>,
    reversed: bool,
    /// The largest code.
    widest: u32,
}

/// Weights in chunks of [`Chunked::CHUNK`] entries: the largest stream (about 300 bytes per split), so
/// that turning the ranges' streams into the pyramid's one holds a chunk twice, not a range.
#[derive(Default)]
struct Chunked {
    chunks: Vec<Vec<f32>>,
    len: usize,
    /// Chunks freed by [`Chunked::free_before`].
    freed: usize,
}

impl Chunked {
    /// 64 MiB chunks: small against a large scan's weights, and above glibc's largest mmap
    /// threshold (32 MiB), so that a freed chunk goes back to the system instead of staying in
    /// the allocator's heap, where the joined stream could not reuse it (it is mapped anew).
    /// An untouched chunk costs address space only.
    const CHUNK: usize = 1 << 24;

    fn push(&mut self, w: f32) {
        match self.chunks.last_mut() {
            Some(last) if last.len() < Self::CHUNK => last.push(w),
            _ => {
                let mut chunk = Vec::with_capacity(Self::CHUNK);
                chunk.push(w);
                self.chunks.push(chunk);
            }
        }
        self.len += 1;
    }

    fn len(&self) -> usize {
        self.len
    }

    /// Appends entries `from..to` to `out`.
    fn copy_to(&self, from: usize, to: usize, out: &mut Vec<f32>) {
        let mut at = from;
        while at < to {
            let (c, i) = (at / Self::CHUNK, at % Self::CHUNK);
            let n = (Self::CHUNK - i).min(to - at);
            out.extend_from_slice(&self.chunks[c][i..i + n]);
            at += n;
        }
    }

    /// Frees the chunks wholly at or after entry `from` (a walk back to front).
    fn free_from(&mut self, from: usize) {
        while self.chunks.len() > from.div_ceil(Self::CHUNK) {
            self.chunks.pop();
        }
    }

    /// Frees the chunks wholly before entry `to` (a walk front to back).
    fn free_before(&mut self, to: usize) {
        while self.freed < to / Self::CHUNK {
            self.chunks[self.freed] = Vec::new();
            self.freed += 1;
        }
    }
}

/// The weights of all splits in split order (a range recorded finest first is read back to
/// front), each chunk of the ranges' streams freed once copied; and where each split's
/// weights start.
fn join_weights(ranges: &mut [Records]) -> (Vec<f32>, Vec<usize>) {
    let total = ranges.iter().map(|r| r.weights.len()).sum();
    let n_splits: usize = ranges.iter().map(|r| r.offsets.len() - 1).sum();
    let mut weights = Vec::with_capacity(total);
    let mut starts = Vec::with_capacity(n_splits);
    for r in ranges {
        let n = r.offsets.len() - 1;
        for j in 0..n {
            let i = if r.reversed { n - 1 - j } else { j };
            let (from, to) = (r.offsets[i].weights, r.offsets[i + 1].weights);
            starts.push(weights.len());
            r.weights.copy_to(from, to, &mut weights);
            if r.reversed {
                r.weights.free_from(from);
            } else {
                r.weights.free_before(to);
            }
        }
        r.weights = Chunked::default();
    }
    (weights, starts)
}

/// The range record holding split `k` (ranges are contiguous and in split order), and the
/// split's position in it.
fn record_of(records: &[Records], k: usize) -> (&Records, usize) {
    let r = records.partition_point(|r| r.range.end <= k);
    let rec = &records[r];
    let i = if rec.reversed {
        rec.range.end - 1 - k
    } else {
        k - rec.range.start
    };
    (rec, i)
}

/// The records of all splits in slot order (see `waves`), codes as narrow as the widest
/// allows: the layout of the finished pyramid, which steps 2–5 already read.
struct Slotted {
    offsets: Vec<SplitOffsets>,
    locals: Vec<u32>,
    codes: Codes,
    weights: Vec<f32>,
}

impl Slotted {
    /// The records of all ranges copied into the slots `waves` assigns them (every range's
    /// codes already in one width), but for the weights: they are only ever read from a
    /// split's start, so they stay in split order, joined chunk by chunk, which never holds
    /// the largest stream twice. The other streams are copied one at a time and each range
    /// stream is freed once copied. Each is copied by all threads at once (the reads are
    /// scattered, so one thread would mostly wait for memory).
    fn new(mut ranges: Vec<Records>, waves: &Waves) -> Slotted {
        let n_splits: usize = ranges.iter().map(|r| r.offsets.len() - 1).sum();
        let (weights, weights_start) = join_weights(&mut ranges);
        let at = |slot: usize| record_of(&ranges, waves.split_at(slot));
        let mut next = SplitOffsets::default();
        let mut offsets = Vec::with_capacity(n_splits + 1);
        for slot in 0..n_splits {
            let (r, i) = at(slot);
            let (o, end) = (r.offsets[i], r.offsets[i + 1]);
            next.weights = weights_start[waves.split_at(slot)];
            offsets.push(next);
            next.locals += end.locals - o.locals;
            next.codes += end.codes - o.codes;
            next.details += end.details - o.details;
        }
        drop(weights_start);
        next.weights = weights.len();
        offsets.push(next);
        let chunks = 4 * rayon::current_num_threads();
        let cuts: Vec<usize> = (0..=chunks).map(|c| n_splits * c / chunks).collect();
        let locals = stream(&cuts, &offsets, &at, |r| &r.locals, |o| o.locals);
        for r in &mut ranges {
            r.locals = Vec::new();
        }
        let at = |slot: usize| record_of(&ranges, waves.split_at(slot));
        // Every range was widened to the widest code of all (see `Self::new`'s caller), so
        // all have the same width.
        let codes = match ranges.first().map(|r| &r.codes) {
            None | Some(Codes::Byte(_)) => slotted_codes::<u8>(&cuts, &offsets, &at),
            Some(Codes::Narrow(_)) => slotted_codes::<u16>(&cuts, &offsets, &at),
            Some(Codes::Wide(_)) => slotted_codes::<u32>(&cuts, &offsets, &at),
        };
        for r in &mut ranges {
            r.codes = Codes::Byte(Vec::new());
        }
        Slotted {
            offsets,
            locals,
            codes,
            weights,
        }
    }

    /// Steps 2–3 of the split stored at `slot`, reading `f = f^(n)`: writes the presmoothed
    /// values of its 1-ring (`f^(n−1)` there) into `f`, and the values `f^(n)` of its touched
    /// vertices, which synthesis must reach, into their places in `targets`.
    fn split_targets<I: LocalIndex>(
        &self,
        codes: &[I],
        slot: usize,
        f: &SharedSignal,
        targets: &SharedSignal,
        scratch: &mut Scratch,
    ) {
        let (o, next) = (self.offsets[slot], self.offsets[slot + 1]);
        let table = &self.locals[o.locals..next.locals];
        let t = next.details - o.details;
        decode(codes, o.codes, o.weights, &mut scratch.entries);
        prefetch_next_split(f, &self.offsets, &self.locals, slot);
        let g = &mut scratch.g;
        g.clear();
        g.extend(table.iter().map(|&x| f.get(x as usize)));
        for (i, &value) in g[..t].iter().enumerate() {
            targets.set(o.details + i, value);
        }
        presmooth_local(
            codes,
            &self.weights,
            &scratch.entries,
            g,
            &mut scratch.smoothed,
        );
        // Downsample: f^(n−1) is the presmoothed ring; the removed vertex is gone (its value is
        // never read again: the prediction starts it at its survivor).
        for (&x, &s) in table[1..t].iter().zip(&scratch.smoothed) {
            f.set(x as usize, s);
        }
    }

    /// Steps 2–3 for every split, turning `f = f^(finest)` into the base signal (on the base
    /// vertices) and filling `targets`: waves from the last to the first, large waves on
    /// rayon's threads (see [`run_waves`]).
    fn downsample<I: LocalIndex>(
        &self,
        codes: &[I],
        waves: &Waves,
        f: &mut [DVec3],
        targets: &mut [DVec3],
        progress: &dyn Progress,
    ) {
        let (f, targets) = (SharedSignal::new(f), SharedSignal::new(targets));
        run_waves(
            (0..waves.len()).rev().map(|w| waves.wave(w)),
            |done| progress.update(RECORDS_SHARE + DOWNSAMPLE_SHARE * done),
            |slot, scratch: &mut Scratch| self.split_targets(codes, slot, &f, &targets, scratch),
        );
    }
}

/// The code stream in slot order, every range's codes being `T`s (a range in another width
/// contributes nothing, which `gather`'s length check turns into a panic).
fn slotted_codes<'a, T: CodeWidth + Send + Sync + 'a>(
    cuts: &[usize],
    offsets: &[SplitOffsets],
    at: &(dyn Fn(usize) -> (&'a Records, usize) + Sync),
) -> Codes {
    T::wrap(stream(cuts, offsets, at, |r| T::of(&r.codes), |o| o.codes))
}

/// One stream of the records in slot order ([`Slotted::new`]): `data` of the range
/// record `at(slot)` names, each split's part found at `pos` of its offsets, copied with
/// [`gather`] to `pos` of the slot's new `offsets`.
fn stream<'a, T: Copy + Send + Sync + 'a>(
    cuts: &[usize],
    offsets: &[SplitOffsets],
    at: &(dyn Fn(usize) -> (&'a Records, usize) + Sync),
    data: fn(&'a Records) -> &'a [T],
    pos: fn(&SplitOffsets) -> usize,
) -> Vec<T> {
    gather(
        cuts,
        |slot| pos(&offsets[slot]),
        |slot| {
            let (r, i) = at(slot);
            &data(r)[pos(&r.offsets[i])..pos(&r.offsets[i + 1])]
        },
    )
}

/// The slices `record(slot)` of all slots `cuts[0]..cuts[last]`, concatenated; slot `s` lands
/// at `start(s)` (`start(cuts[last])` is the total length). The chunks `cuts[c]..cuts[c + 1]`
/// are copied on rayon's threads, each into its own part of the output.
fn gather<'r, T: Copy + Send + Sync + 'r>(
    cuts: &[usize],
    start: impl Fn(usize) -> usize,
    record: impl Fn(usize) -> &'r [T] + Sync,
) -> Vec<T> {
    use rayon::prelude::*;
    let (first, last) = (cuts[0], cuts[cuts.len() - 1]);
    let total = start(last) - start(first);
    let mut to: Vec<T> = Vec::with_capacity(total);
    let mut rest = &mut to.spare_capacity_mut()[..total];
    let mut parts = Vec::with_capacity(cuts.len());
    for w in cuts.windows(2) {
        let (part, tail) = rest.split_at_mut(start(w[1]) - start(w[0]));
        parts.push((w[0]..w[1], part));
        rest = tail;
    }
    parts.into_par_iter().for_each(|(slots, part)| {
        let mut at = 0;
        for slot in slots {
            let src = record(slot);
            for (d, &x) in part[at..at + src.len()].iter_mut().zip(src) {
                d.write(x);
            }
            at += src.len();
        }
        assert_eq!(at, part.len(), "record lengths disagree with their offsets");
    });
    // SAFETY: the parts tile `to`'s first `total` elements, and each part was written in full
    // (asserted above; a failed assertion unwinds before this line and drops `to` empty).
    unsafe { to.set_len(total) };
    to
}

/// Total area and bounding-box diagonal of a mesh.
pub(crate) fn surface_stats(positions: &[DVec3], faces: &[[u32; 3]]) -> (f64, f64) {
    // Face order and formula of `Mesh::face_area` summed over a mesh built from `faces`.
    let area = faces
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            crate::mesh::geometry::triangle_area(a, b, c)
        })
        .sum();
    let diagonal = crate::mesh::geometry::BoundingBox::of(positions.iter().copied())
        .map_or(0.0, |b| b.diagonal());
    (area, diagonal)
}
