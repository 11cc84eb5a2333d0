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
//! On a hierarchy built in blocks ([`ProgressiveMesh::pins`]), a split's touched vertices are
//! its new vertex and the ring vertices that are free in its pass: the ones pinned there are
//! only read, so that each block's splits write only the block's free vertices and the
//! blocks' analyses commute (`docs/partitioned.md`, "The detail pyramid on a partitioned
//! hierarchy"). Everything downstream reads the touched set from the records.
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
use super::quantise::{Targets, detail_step, signal_diagonal};
use super::spill::{Placement, Stream, Writer};
use super::synthesis::{Scratch, decode, prefetch_next_split, presmooth_local};
use super::waves::{SharedSignal, Waves, run_waves};
use super::{
    CodeWidth, Codes, CodesWriter, DetailPyramid, PyramidError, SplitOffsets, release_records,
};
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
        Self::analyze_signal_at(pm, relaxation, signal, progress, None)
    }

    /// [`Self::analyze_signal`] with the layout at `placement` (`None`: by its size, see
    /// module `spill`).
    pub(crate) fn analyze_signal_at(
        pm: &ProgressiveMesh,
        relaxation: &dyn Relaxation,
        signal: &[DVec3],
        progress: &dyn Progress,
        placement: Option<Placement>,
    ) -> Result<DetailPyramid, PyramidError> {
        let geometry = pm.original_positions();
        if signal.len() != geometry.len() {
            return Err(PyramidError::Invalid(format!(
                "signal has {} values, the progressive mesh has {} vertices",
                signal.len(),
                geometry.len()
            )));
        }
        let layout = Layout::record(pm, relaxation, progress, placement)?;
        // Steps 2–3, finest split first: waves in reverse storage order, which, like split
        // order, runs every split after the splits it depends on.
        let mut f = signal.to_vec();
        let slotted = &layout.slotted;
        let mut targets = vec![[0; 3]; slotted.offsets.last().map_or(0, |o| o.details)];
        with_codes!(&slotted.codes, c => {
            slotted.downsample(c, &layout.waves, signal, &mut f, &mut targets, progress)
        });
        slotted.release_all();
        let base = f[..layout.n_base].to_vec();
        drop(f);
        // Steps 4–5 in synthesis order, quantised in the closed loop.
        let step = detail_step(signal_diagonal(signal));
        let mut pyramid = layout.into_pyramid(relaxation, signal, base, Vec::new(), step);
        let done = RECORDS_SHARE + DOWNSAMPLE_SHARE;
        pyramid.details = pyramid.quantise_details(signal, targets, |x| {
            progress.update(done + (1.0 - done) * x)
        });
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
    /// Step 1 for every split of `pm`, then the storage order: wave by wave (see `waves`),
    /// the streams at `placement` (`None`: by their expected size, see module `spill`).
    /// Reports progress from 0 to [`RECORDS_SHARE`].
    pub(crate) fn record(
        pm: &ProgressiveMesh,
        relaxation: &dyn Relaxation,
        progress: &dyn Progress,
        placement: Option<Placement>,
    ) -> Result<Layout, PyramidError> {
        Layout::record_prefix(pm, relaxation, progress, placement, pm.splits().len())
    }

    /// [`Self::record`] for the first `n_splits` splits only: the layout of the levels up to
    /// `n0 + n_splits`, as if the hierarchy ended there, except that the surface area and
    /// diagonal are the finest level's (they turn feature sizes into levels). Each split's
    /// records are those of the whole layout: a split's records depend only on the splits
    /// before it.
    pub(crate) fn record_prefix(
        pm: &ProgressiveMesh,
        relaxation: &dyn Relaxation,
        progress: &dyn Progress,
        placement: Option<Placement>,
        n_splits: usize,
    ) -> Result<Layout, PyramidError> {
        let geometry = pm.original_positions();
        let n_base = pm.n_base_vertices();
        let (surface_area, bbox_diagonal) =
            surface_stats(&geometry[..pm.n_vertices()], pm.finest_faces());
        let n_splits = n_splits.min(pm.splits().len());
        let n_finest = n_base + n_splits;
        let cursor = relaxation.as_ring_stencils().is_none().then(|| pm.cursor());
        // Ring stencils replay up to each range's start; the cursor's seek is not modelled.
        let prefix_cost = if cursor.is_none() {
            PREFIX_REPLAY_COST
        } else {
            0.0
        };
        let ranges = split_ranges(n_splits, rayon::current_num_threads(), prefix_cost);
        let placement = placement.unwrap_or_else(|| {
            Placement::for_layout(n_splits.saturating_mul(LAYOUT_BYTES_PER_SPLIT))
        });
        let mut records = record_ranges(pm, relaxation, cursor, &ranges, placement, progress)?;
        // One code width for the pyramid: the widest range's.
        let widest = records.iter().map(|r| r.widest).max().unwrap_or(0);
        for r in &mut records {
            let codes = std::mem::replace(&mut r.codes, Codes::Byte(Stream::default()));
            r.codes = codes.widened(widest, placement)?;
        }
        // Waves store their splits by the place of the new vertex (see `run_waves`).
        let morton = morton_codes(&geometry[n_base..n_finest]);
        let waves = Waves::schedule(
            n_splits,
            geometry.len(),
            |k| {
                // The scan reads the locals once, in split order: hand back the pages of
                // each block of splits once it is past them.
                if k % RELEASE_EVERY == 0 && k > 0 {
                    release_locals(&records, k - RELEASE_EVERY..k);
                }
                let (rec, i) = record_of(&records, k);
                let (o, next) = (rec.offsets[i], rec.offsets[i + 1]);
                (&rec.locals[o.locals..next.locals], next.details - o.details)
            },
            |k| morton.as_ref().map_or(0, |m| m[k]),
        );
        drop(morton);
        records.iter().for_each(|r| r.locals.release_all());
        let slotted = Slotted::new(records, &waves, placement)?;
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

/// About the bytes of a split's layout records on scans (75 weights, 32 local-table entries, 131
/// codes, the offsets), to decide early where the layout goes (module `spill`).
const LAYOUT_BYTES_PER_SPLIT: usize = 4 * 75 + 4 * 32 + 131 + 32;

/// The share of the analysis' time the records take (the progress bar's split between the
/// three phases; about two thirds with Guskov's operator).
pub(crate) const RECORDS_SHARE: f64 = 0.7;

/// The share of the walk down (presmoothing and collapsing); the closed loop takes the rest.
const DOWNSAMPLE_SHARE: f64 = 0.1;

/// Splits per range below which one thread records them all: a range's walk first reaches the
/// start of its range (a replay from the base, or a cursor collapsing from the finest level),
/// which only pays off on long ranges.
const SPLITS_PER_RANGE: usize = 1024;

/// What replaying a split on the way to a range's start costs against recording one (its
/// replay included), for operators with ring stencils: each range replays every split before
/// it first, so ranges of equal length leave the coarsest range's thread idle while the finer
/// ones still work (on the 6.66M scan, the finer of two equal ranges took about a fifth longer).
const PREFIX_REPLAY_COST: f64 = 0.2;

/// Cuts splits `0..n_splits` into at most `threads` contiguous ranges, coarsest first, of
/// about equal work when reaching a range's start costs `prefix_cost` per split before it
/// (relative to recording one): range `r` from `a_r` to `a_{r+1}` costs
/// `ρ·a_r + (a_{r+1} − a_r)`, and equal costs give `a_r = n·(1 − q^r)/(1 − q^m)` for `m`
/// ranges, `q = 1 − ρ` (equal lengths when `ρ = 0`). Empty ranges are dropped.
fn split_ranges(n_splits: usize, threads: usize, prefix_cost: f64) -> Vec<std::ops::Range<usize>> {
    let n = threads.clamp(1, (n_splits / SPLITS_PER_RANGE).max(1));
    let q = 1.0 - prefix_cost.clamp(0.0, 0.9);
    let cut = |r: usize| {
        if q == 1.0 {
            r * n_splits / n
        } else {
            let share = (1.0 - q.powi(r as i32)) / (1.0 - q.powi(n as i32));
            ((share * n_splits as f64).round() as usize).min(n_splits)
        }
    };
    let mut cuts: Vec<usize> = (0..=n).map(cut).collect();
    cuts[n] = n_splits;
    cuts.dedup();
    if cuts.len() == 1 {
        // No splits: one empty range.
        cuts.push(n_splits);
    }
    cuts.windows(2).map(|w| w[0]..w[1]).collect()
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
    placement: Placement,
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
                record_range_on_rings(pm, rings, range.clone(), placement, report)
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
            record_range(pm, relaxation, cursor, range.clone(), placement, report)
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
    placement: Placement,
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
    let mut recorder = Recorder::new(range.clone(), geometry.len(), false, placement)?;
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
        let pinned = pinned_at(pm, k);
        let ring = replay.ring_entries(v).0.iter().map(|e| e.nbr);
        touched.extend(ring.filter(|x| !is_pinned(pinned, *x)));
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
    recorder.finish()
}

/// Step 1 for splits `range` (walked finest first, `cursor` at level `n0 + range.end`).
fn record_range(
    pm: &ProgressiveMesh,
    relaxation: &dyn Relaxation,
    mut cursor: PmCursor<'_>,
    range: std::ops::Range<usize>,
    placement: Placement,
    progress: &dyn Progress,
) -> Result<Records, PyramidError> {
    let geometry = pm.original_positions();
    let n_base = pm.n_base_vertices();
    let n = range.len();
    let mut recorder = Recorder::new(range.clone(), geometry.len(), true, placement)?;
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
        let pinned = pinned_at(pm, k);
        let ring = mesh.outgoing(vh).map(|h| mesh.to_vertex(h));
        touched_handles.extend(ring.filter(|x| !is_pinned(pinned, x.slot() as u32)));
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
    recorder.finish()
}

/// The vertices pinned in the pass of split `k` of a partitioned hierarchy (ascending; none
/// in one piece). A split leaves its ring vertices pinned in its pass untouched: they are
/// neither presmoothed nor predicted and get no detail there, only read, so that the splits
/// of one block of a pass write only the block's free vertices and read nothing another
/// block writes (`docs/partitioned.md`, "The detail pyramid on a partitioned hierarchy").
fn pinned_at(pm: &ProgressiveMesh, k: usize) -> &[u32] {
    pm.pins().map_or(&[], |p| p.pinned_at(k))
}

fn is_pinned(pinned: &[u32], v: u32) -> bool {
    !pinned.is_empty() && pinned.binary_search(&v).is_ok()
}

/// Writes the records of one range of splits, split by split.
struct Recorder {
    offsets: Writer<SplitOffsets>,
    locals: Writer<u32>,
    codes: CodesWriter,
    weights: Writer<f32>,
    range: std::ops::Range<usize>,
    reversed: bool,
    widest: u32,
    n_touched: usize,
    /// The current split's local table.
    split_locals: Vec<u32>,
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
    fn new(
        range: std::ops::Range<usize>,
        n_vertices: usize,
        reversed: bool,
        placement: Placement,
    ) -> Result<Recorder, PyramidError> {
        let n = range.len();
        Ok(Recorder {
            offsets: Writer::new(placement, n + 1)?,
            // Reserves above the usual sizes (on scans about 32 locals, 127–135 codes and
            // 74–80 weights per split): untouched capacity costs no memory, a doubling copies
            // the stream.
            locals: Writer::new(placement, 40 * n)?,
            codes: CodesWriter::new(placement, 160 * n)?,
            weights: Writer::new(placement, 90 * n)?,
            range,
            reversed,
            widest: 0,
            n_touched: 0,
            split_locals: Vec::new(),
            stencils: Vec::new(),
            stencil_lens: Vec::new(),
            fan: Vec::new(),
            split_codes: Vec::new(),
            local_of: vec![u32::MAX; n_vertices],
        })
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
        let weights = &mut self.weights;
        self.offsets.push(SplitOffsets {
            locals: self.locals.len(),
            codes: self.codes.len(),
            weights: weights.len(),
            details: self.n_touched,
        })?;
        let codes = &mut self.split_codes;
        codes.clear();
        let locals = &mut self.split_locals;
        locals.clear();
        let local_of = &mut self.local_of;
        let mut local = |u: u32, locals: &mut Vec<u32>| {
            let x = &mut local_of[u as usize];
            if *x == u32::MAX {
                *x = locals.len() as u32;
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
                weights.push(w as f32)?;
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
        for &u in locals.iter() {
            local_of[u as usize] = u32::MAX;
        }
        self.locals.extend_from_slice(locals)?;
        self.widest = codes.iter().fold(self.widest, |m, &c| m.max(c));
        self.codes.extend_widening(codes, self.widest)?;
        self.n_touched += touched.len();
        Ok(())
    }

    fn finish(mut self) -> Result<Records, PyramidError> {
        self.offsets.push(SplitOffsets {
            locals: self.locals.len(),
            codes: self.codes.len(),
            weights: self.weights.len(),
            details: self.n_touched,
        })?;
        Ok(Records {
            offsets: self.offsets.finish()?,
            locals: self.locals.finish()?,
            codes: self.codes.finish()?,
            weights: self.weights.finish()?,
            range: self.range,
            reversed: self.reversed,
            widest: self.widest,
        })
    }
}

/// The signal-independent per-split streams of one range of splits, as recorded; the
/// `details` offsets count the touched vertices, whose details come later. Codes are recorded
/// as narrow as the range's largest code so far allows (a byte on most meshes), not as 32-bit
/// values narrowed later: the 32-bit stream would be 4 bytes × ~130 codes per split.
struct Records {
    offsets: Stream<SplitOffsets>,
    locals: Stream<u32>,
    codes: Codes,
    weights: Stream<f32>,
    /// The splits recorded, in the order given by `reversed` (finest first when set).
    range: std::ops::Range<usize>,
    reversed: bool,
    /// The largest code.
    widest: u32,
}

/// The range record holding split `k` (ranges are contiguous and in split order), and the
/// split's position in it.
fn record_of(records: &[Records], k: usize) -> (&Records, usize) {
    let (r, i) = record_index(records, k);
    (&records[r], i)
}

/// [`record_of`] as the index of the range record.
fn record_index(records: &[Records], k: usize) -> (usize, usize) {
    let r = records.partition_point(|r| r.range.end <= k);
    let rec = &records[r];
    let i = if rec.reversed {
        rec.range.end - 1 - k
    } else {
        k - rec.range.start
    };
    (r, i)
}

/// Splits whose recorded locals [`Waves::schedule`] reads before their pages are handed back.
const RELEASE_EVERY: usize = 4096;

/// Hands back the pages of the local tables and offsets of splits `splits` (see [`Stream::release`]).
fn release_locals(records: &[Records], splits: std::ops::Range<usize>) {
    for rec in records {
        let (a, b) = (
            splits.start.max(rec.range.start),
            splits.end.min(rec.range.end),
        );
        if a >= b {
            continue;
        }
        let (i0, i1) = if rec.reversed {
            (rec.range.end - b, rec.range.end - a)
        } else {
            (a - rec.range.start, b - rec.range.start)
        };
        rec.locals
            .release(rec.offsets[i0].locals..rec.offsets[i1].locals);
        rec.offsets.release(i0..i1);
    }
}

/// The records of all splits in slot order (see `waves`), codes as narrow as the widest
/// allows: the layout of the finished pyramid, which steps 2–5 already read.
struct Slotted {
    offsets: Stream<SplitOffsets>,
    locals: Stream<u32>,
    codes: Codes,
    weights: Stream<f32>,
}

impl Slotted {
    /// The records of all ranges copied into the slots `waves` assigns them (every range's
    /// codes already in one width), one stream at a time, each range stream dropped once
    /// copied; the copies are written at `placement`.
    fn new(
        mut ranges: Vec<Records>,
        waves: &Waves,
        placement: Placement,
    ) -> Result<Slotted, PyramidError> {
        let n_splits: usize = ranges.iter().map(|r| r.offsets.len() - 1).sum();
        let at = |slot: usize| record_of(&ranges, waves.split_at(slot));
        let mut next = SplitOffsets::default();
        let mut offsets = Vec::with_capacity(n_splits + 1);
        for slot in 0..n_splits {
            let (r, i) = at(slot);
            let (o, end) = (r.offsets[i], r.offsets[i + 1]);
            offsets.push(next);
            next.locals += end.locals - o.locals;
            next.codes += end.codes - o.codes;
            next.weights += end.weights - o.weights;
            next.details += end.details - o.details;
        }
        offsets.push(next);
        let locals = gather_stream(
            &ranges,
            waves,
            &offsets,
            placement,
            |r| &r.locals,
            |r, x| r.locals.release(x),
            |o| o.locals,
        )?;
        for r in &mut ranges {
            r.locals = Stream::default();
        }
        let weights = gather_stream(
            &ranges,
            waves,
            &offsets,
            placement,
            |r| &r.weights,
            |r, x| r.weights.release(x),
            |o| o.weights,
        )?;
        for r in &mut ranges {
            r.weights = Stream::default();
        }
        // Every range was widened to the widest code of all (see `Self::new`'s caller), so
        // all have the same width.
        let codes = match ranges.first().map(|r| &r.codes) {
            None | Some(Codes::Byte(_)) => {
                slotted_codes::<u8>(&ranges, waves, &offsets, placement)?
            }
            Some(Codes::Narrow(_)) => slotted_codes::<u16>(&ranges, waves, &offsets, placement)?,
            Some(Codes::Wide(_)) => slotted_codes::<u32>(&ranges, waves, &offsets, placement)?,
        };
        drop(ranges);
        let mut stored = Writer::new(placement, offsets.len())?;
        stored.extend_from_slice(&offsets)?;
        drop(offsets);
        Ok(Slotted {
            offsets: stored.finish()?,
            locals,
            codes,
            weights,
        })
    }

    /// Hands back the resident pages of every stream (see [`Stream::release`]).
    fn release_all(&self) {
        self.release_slots(0..self.offsets.len().saturating_sub(1));
    }

    /// Hands back the resident pages of the records of slots `slots`.
    fn release_slots(&self, slots: std::ops::Range<usize>) {
        release_records(
            (&self.offsets, &self.locals, &self.codes, &self.weights),
            slots,
        );
    }

    /// Steps 2–3 of the split stored at `slot`, reading `f = f^(n)`: writes the presmoothed
    /// values of its 1-ring (`f^(n−1)` there) into `f`, and the values `f^(n)` of its touched
    /// vertices, which synthesis must reach, into their places in `targets` (as displacements
    /// from the analysed `signal`).
    fn split_targets<I: LocalIndex>(
        &self,
        codes: &[I],
        slot: usize,
        signal: &[DVec3],
        f: &SharedSignal,
        targets: &Targets,
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
        for (i, (&value, &x)) in g[..t].iter().zip(table).enumerate() {
            targets.set_displacement(o.details + i, value - signal[x as usize]);
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
        signal: &[DVec3],
        f: &mut [DVec3],
        targets: &mut [[i32; 3]],
        progress: &dyn Progress,
    ) {
        let (f, targets) = (SharedSignal::new(f), Targets::new(targets));
        run_waves(
            (0..waves.len()).rev().map(|w| waves.wave(w)),
            |done| progress.update(RECORDS_SHARE + DOWNSAMPLE_SHARE * done),
            |slot, scratch: &mut Scratch| {
                self.split_targets(codes, slot, signal, &f, &targets, scratch)
            },
            |slots| self.release_slots(slots),
        );
    }
}

/// The code stream in slot order, every range's codes being `T`s (a range in another width
/// contributes nothing, which `gather`'s length check turns into a panic).
fn slotted_codes<T: CodeWidth + Send + Sync>(
    ranges: &[Records],
    waves: &Waves,
    offsets: &[SplitOffsets],
    placement: Placement,
) -> Result<Codes, PyramidError> {
    let stream = gather_stream(
        ranges,
        waves,
        offsets,
        placement,
        |r| T::of(&r.codes),
        |r, x| r.codes.release(x),
        |o| o.codes,
    )?;
    Ok(T::wrap(stream))
}

/// Elements [`gather_stream`] copies per batch: a batch is gathered in memory, then written
/// (small in unit tests, so that their meshes take several batches).
const GATHER_BATCH: usize = if cfg!(test) { 1 << 12 } else { 1 << 22 };

/// Elements of a range's stream [`gather_stream`] reads past before handing their pages back.
const GATHER_RELEASE: usize = if cfg!(test) { 1 << 8 } else { 1 << 16 };

/// One stream of the records in slot order ([`Slotted::new`]): `data` of the range record
/// holding each slot's split, its part found at `pos` of the range's offsets, copied to `pos`
/// of the slot's new `offsets`. Batch by batch: a batch's records are read in the order they
/// lie in the ranges' streams, not in slot order, and the pages behind the read are handed
/// back as it goes (`release`). Slot order scatters the reads over the whole stream, so read
/// in slot order every page a batch touches stayed resident until the batch ended (with the
/// kernel mapping the neighbours of each faulted page too, the whole stream on a scanner-class
/// mesh); read in stream order, only the pages near the read are.
fn gather_stream<T: bytemuck::Pod>(
    ranges: &[Records],
    waves: &Waves,
    offsets: &[SplitOffsets],
    placement: Placement,
    data: impl Fn(&Records) -> &[T],
    release: impl Fn(&Records, std::ops::Range<usize>),
    pos: fn(&SplitOffsets) -> usize,
) -> Result<Stream<T>, PyramidError> {
    let n_slots = offsets.len() - 1;
    let mut out = Writer::new(placement, pos(&offsets[n_slots]))?;
    let mut buffer: Vec<T> = Vec::new();
    let mut reads: Vec<(usize, usize, usize)> = Vec::new();
    let mut first = 0;
    while first < n_slots {
        // The slots whose records fit in a batch (at least one).
        let limit = pos(&offsets[first]) + GATHER_BATCH;
        let last = first + 1 + offsets[first + 1..n_slots].partition_point(|o| pos(o) <= limit);
        reads.clear();
        reads.extend((first..last).map(|slot| {
            let (r, i) = record_index(ranges, waves.split_at(slot));
            (r, i, slot)
        }));
        reads.sort_unstable();
        let base = pos(&offsets[first]);
        buffer.clear();
        buffer.resize(pos(&offsets[last]) - base, T::zeroed());
        // Per range: how far its data and offsets were handed back.
        let mut behind = (usize::MAX, 0, 0);
        for &(r, i, slot) in &reads {
            let rec = &ranges[r];
            let (a, b) = (pos(&rec.offsets[i]), pos(&rec.offsets[i + 1]));
            if behind.0 != r {
                behind = (r, a, i);
            } else if a - behind.1 >= GATHER_RELEASE {
                release(rec, behind.1..a);
                rec.offsets.release(behind.2..i);
                behind = (r, a, i);
            }
            let dst = pos(&offsets[slot]) - base;
            assert_eq!(
                b - a,
                pos(&offsets[slot + 1]) - pos(&offsets[slot]),
                "record lengths disagree with their offsets"
            );
            buffer[dst..dst + (b - a)].copy_from_slice(&data(rec)[a..b]);
        }
        out.extend_from_slice(&buffer)?;
        for r in ranges {
            release(r, 0..usize::MAX);
            r.offsets.release_all();
        }
        first = last;
    }
    Ok(out.finish()?)
}

/// Total area and bounding-box diagonal of a mesh.
pub(crate) fn surface_stats(positions: &[DVec3], faces: &[[u32; 3]]) -> (f64, f64) {
    use rayon::prelude::*;
    // Face order and formula of `Mesh::face_area` summed over a mesh built from `faces`. The
    // areas (the random reads of positions and the square roots) are computed on all cores a
    // batch at a time and added in face order, so the sum has the bits of the sequential one.
    const CHUNK: usize = 1 << 15;
    let batch = CHUNK * 4 * rayon::current_num_threads().max(1);
    let area_of = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        crate::mesh::geometry::triangle_area(a, b, c)
    };
    let mut area: f64 = std::iter::empty::<f64>().sum();
    for faces in faces.chunks(batch) {
        let areas: Vec<Vec<f64>> = faces
            .par_chunks(CHUNK)
            .map(|chunk| chunk.iter().map(area_of).collect())
            .collect();
        area = areas.iter().flatten().fold(area, |sum, &a| sum + a);
    }
    let diagonal = crate::mesh::geometry::BoundingBox::of(positions.iter().copied())
        .map_or(0.0, |b| b.diagonal());
    (area, diagonal)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lengths(ranges: &[std::ops::Range<usize>]) -> Vec<usize> {
        ranges.iter().map(|r| r.len()).collect()
    }

    #[test]
    fn the_surface_area_has_the_bits_of_the_sequential_sum_in_face_order() {
        let n = 300_000u32;
        let positions: Vec<DVec3> = (0..n)
            .map(|i| {
                let t = f64::from(i);
                DVec3::new(
                    (t * 0.37).sin() * t,
                    (t * 1.3).cos(),
                    (t * 0.011).sin() * 1e-3,
                )
            })
            .collect();
        let faces: Vec<[u32; 3]> = (0..n - 2).map(|i| [i, (i * 7 + 1) % n, i + 2]).collect();
        let sequential: f64 = faces
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| positions[i as usize]);
                crate::mesh::geometry::triangle_area(a, b, c)
            })
            .sum();
        let (area, _) = surface_stats(&positions, &faces);
        assert_eq!(area.to_bits(), sequential.to_bits());
        let empty: f64 = std::iter::empty::<f64>().sum();
        assert_eq!(surface_stats(&positions, &[]).0.to_bits(), empty.to_bits());
    }

    #[test]
    fn ranges_tile_the_splits_coarsest_first() {
        for (n_splits, threads, cost) in [
            (0, 4, 0.2),
            (1000, 4, 0.2),
            (1_000_000, 2, 0.0),
            (1_000_000, 3, 0.2),
            (5_000, 64, 0.2),
        ] {
            let ranges = split_ranges(n_splits, threads, cost);
            assert!(!ranges.is_empty() && ranges.len() <= threads);
            assert_eq!(ranges[0].start, 0);
            assert_eq!(ranges.last().unwrap().end, n_splits);
            assert!(
                ranges
                    .windows(2)
                    .all(|w| w[0].end == w[1].start && w[0].end > w[0].start)
            );
        }
    }

    #[test]
    fn without_a_prefix_cost_ranges_are_equal_and_with_one_the_coarse_ranges_are_longer() {
        assert_eq!(lengths(&split_ranges(1_000_000, 4, 0.0)), vec![250_000; 4]);
        let ranges = split_ranges(1_000_000, 2, 0.2);
        // ρ = 0.2: the coarse range takes 1/(2 − ρ) of the splits, and both cost the same.
        assert_eq!(ranges[0].end, 555_556);
        let cost = |r: &std::ops::Range<usize>| 0.2 * r.start as f64 + r.len() as f64;
        let costs: Vec<f64> = split_ranges(1_000_000, 3, 0.2).iter().map(cost).collect();
        assert!(
            costs.iter().all(|c| (c - costs[0]).abs() < 2.0),
            "{costs:?}"
        );
        assert!(
            lengths(&split_ranges(1_000_000, 3, 0.2))
                .windows(2)
                .all(|w| w[0] > w[1])
        );
    }
}
