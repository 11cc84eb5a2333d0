//! Analysis (`algorithms.md` §1c): finest → coarsest, one half-edge collapse at a time.
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
//! Step 1 never reads the signal, and it is most of the work (the hinge coefficients), so it
//! runs first, for all splits, on rayon's threads: the hierarchy is cut into contiguous ranges
//! of splits, and each range is walked down by its own cursor, which starts at the finest level
//! and collapses to the top of its range — the very mesh records the single walk would have
//! there, so the records and the pyramid do not depend on the thread count. Steps 2–5 then run
//! over the records, finest split first; like synthesis, they run the splits of a wave (see
//! `waves`) at once, in reverse.

use super::frames::frame_min_length;
use super::synthesis::{Scratch, decode, predict_local, prefetch_next_split, presmooth_local};
use super::waves::{SharedSignal, Waves, run_waves};
use super::{Codes, Pyramid, PyramidError, SplitOffsets};
use crate::mesh::geometry::morton_codes;
use crate::mesh::{Mesh, SlotIndex, VertexId};
use crate::pm::{PmCursor, ProgressiveMesh};
use crate::progress::Progress;
use crate::relax::Relaxation;
use glam::DVec3;

impl Pyramid {
    /// Analyses the original positions of `pm` (the surface itself).
    pub fn analyze(
        pm: &ProgressiveMesh,
        relaxation: &dyn Relaxation,
        progress: &dyn Progress,
    ) -> Result<Pyramid, PyramidError> {
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
    ) -> Result<Pyramid, PyramidError> {
        if !relaxation.has_linear_stencils() {
            return Err(PyramidError::NonLinearRelaxation(relaxation.name()));
        }
        let geometry = pm.original_positions();
        if signal.len() != geometry.len() {
            return Err(PyramidError::Invalid(format!(
                "signal has {} values, the progressive mesh has {} vertices",
                signal.len(),
                geometry.len()
            )));
        }
        let n_base = pm.n_base_vertices();
        let n_finest = pm.n_vertices();
        let n_splits = n_finest - n_base;
        let cursor = pm.cursor();
        let (surface_area, bbox_diagonal) = surface_stats(cursor.mesh());

        // Step 1 for every split, then the storage order: wave by wave (see `waves`).
        let ranges = split_ranges(n_splits, rayon::current_num_threads());
        let records = record_ranges(pm, relaxation, cursor, &ranges, progress)?;
        let record_of = |k: usize| {
            let r = ranges.partition_point(|r| r.end <= k);
            (&records[r], ranges[r].end - 1 - k)
        };
        // Waves store their splits by the place of the new vertex (see `run_waves`).
        let morton = morton_codes(&geometry[n_base..n_finest]);
        let waves = Waves::schedule(
            n_splits,
            signal.len(),
            |k| {
                let (rec, i) = record_of(k);
                let (o, next) = (rec.offsets[i], rec.offsets[i + 1]);
                (&rec.locals[o.locals..next.locals], next.details - o.details)
            },
            |k| morton.as_ref().map_or(0, |m| m[k]),
        );
        let slotted = Records::in_slot_order(&records, &waves, record_of);
        drop(records);

        // Steps 2–5, finest split first: waves in reverse storage order, which, like split
        // order, runs every split after the splits it depends on.
        let mut f = signal.to_vec();
        let mut details = vec![DVec3::ZERO; slotted.offsets.last().map_or(0, |o| o.details)];
        let min_length = frame_min_length(bbox_diagonal);
        slotted.downsample(&waves, &mut f, &mut details, min_length, progress);
        progress.update(1.0);

        let codes = slotted.codes;
        let widest = codes.iter().copied().max().unwrap_or(0);
        let codes = if widest <= u8::MAX as u32 {
            Codes::Byte(codes.iter().map(|&c| c as u8).collect())
        } else if widest <= u16::MAX as u32 {
            Codes::Narrow(codes.iter().map(|&c| c as u16).collect())
        } else {
            Codes::Wide(codes)
        };
        Ok(Pyramid {
            n_base,
            n_finest,
            passthrough: signal[n_finest..].to_vec(),
            base: f[..n_base].to_vec(),
            offsets: slotted.offsets,
            locals: slotted.locals,
            codes,
            weights: slotted.weights,
            details,
            waves,
            relaxation: relaxation.name(),
            surface_area,
            bbox_diagonal,
        })
    }
}

/// The share of the analysis' time the records take (the progress bar's split between the
/// two phases; about two thirds with Guskov's operator).
const RECORDS_SHARE: f64 = 0.7;

/// Splits per range below which one thread records them all: a range's cursor is built at the
/// finest level and collapses to the top of its range first, which only pays off on long ranges.
const SPLITS_PER_RANGE: usize = 1024;

/// Cuts splits `0..n_splits` into at most `threads` contiguous ranges of near-equal length,
/// coarsest first.
fn split_ranges(n_splits: usize, threads: usize) -> Vec<std::ops::Range<usize>> {
    let n = threads.clamp(1, (n_splits / SPLITS_PER_RANGE).max(1));
    (0..n)
        .map(|r| r * n_splits / n..(r + 1) * n_splits / n)
        .collect()
}

/// Step 1 for every range of splits (coarsest range first), each range on its own thread
/// with its own cursor; `cursor` (at the finest level) serves the finest range. Progress is
/// reported by the finest range's walk.
fn record_ranges(
    pm: &ProgressiveMesh,
    relaxation: &dyn Relaxation,
    cursor: PmCursor<'_>,
    ranges: &[std::ops::Range<usize>],
    progress: &dyn Progress,
) -> Result<Vec<Records>, PyramidError> {
    use rayon::prelude::*;
    let finest = ranges.len() - 1;
    let mut cursors: Vec<Option<PmCursor<'_>>> = ranges.iter().map(|_| None).collect();
    cursors[finest] = Some(cursor);
    cursors
        .into_par_iter()
        .zip(ranges)
        .enumerate()
        .map(|(r, (cursor, range))| {
            let mut cursor = cursor.unwrap_or_else(|| pm.cursor());
            cursor.seek(pm.n_base_vertices() + range.end);
            let quiet = crate::progress::NoProgress;
            let report: &dyn Progress = if r == finest { progress } else { &quiet };
            record_range(pm, relaxation, cursor, range.clone(), report)
        })
        .collect()
}

/// Step 1 for splits `range` (walked finest first, `cursor` at level `n0 + range.end`): the
/// local tables, codes and weights of each split, in that order, with `details` offsets
/// counting the touched vertices.
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
    let mut rec = Records {
        offsets: Vec::with_capacity(n + 1),
        locals: Vec::with_capacity(32 * n),
        codes: Vec::with_capacity(128 * n),
        weights: Vec::with_capacity(72 * n),
    };
    let mut stencils = Vec::new();
    let mut stencil_lens = Vec::new();
    let mut touched: Vec<VertexId> = Vec::new();
    let mut n_touched = 0;
    // PM vertex → its index in the current split's local table (u32::MAX: not in it).
    let mut local_of = vec![u32::MAX; geometry.len()];
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
        let survivor = pm.splits()[k].survivor;
        let mesh = cursor.mesh();
        let vh = cursor.vertex(v);
        let (locals, codes, weights) = (&mut rec.locals, &mut rec.codes, &mut rec.weights);
        rec.offsets.push(SplitOffsets {
            locals: locals.len(),
            codes: codes.len(),
            weights: weights.len(),
            details: n_touched,
        });
        let l0 = locals.len();
        // The touched vertices (v, then its ring CCW) open the local table; their stencils
        // and fans (indices into the table) follow, weights alongside.
        touched.clear();
        touched.push(vh);
        touched.extend(mesh.outgoing(vh).map(|h| mesh.to_vertex(h)));
        let mut local = |u: usize, locals: &mut Vec<u32>| {
            if local_of[u] == u32::MAX {
                local_of[u] = (locals.len() - l0) as u32;
                locals.push(u as u32);
            }
            local_of[u]
        };
        for &j in &touched {
            local(j.slot(), locals);
        }
        let Some(survivor_local) = touched.iter().position(|j| j.slot() == survivor as usize)
        else {
            return Err(PyramidError::Internal(format!(
                "split {k}: vertex {v} is not adjacent to its survivor {survivor}"
            )));
        };
        if vh.slot() != v || survivor_local == 0 {
            return Err(PyramidError::Internal(format!(
                "split {k}: vertex {v} has PM slot {}",
                vh.slot()
            )));
        }
        codes.push(touched.len() as u32);
        codes.push(survivor_local as u32);
        stencils.clear();
        stencil_lens.clear();
        relaxation.stencils(mesh, geometry, &touched, &mut stencils, &mut stencil_lens);
        let mut next_stencil = 0;
        for (&j, &len) in touched.iter().zip(&stencil_lens) {
            let len_at = codes.len();
            codes.extend([0, 0]);
            for &(u, w) in &stencils[next_stencil..next_stencil + len] {
                let x = local(u.slot(), locals);
                codes.push(x);
                weights.push(w);
            }
            next_stencil += len;
            let mut first = None;
            let fan_at = codes.len();
            for h in mesh.outgoing(j) {
                first.get_or_insert(h);
                let x = local(mesh.to_vertex(h).slot(), locals);
                codes.push(x);
            }
            let open = first.is_some_and(|h| mesh.is_boundary_halfedge(h));
            codes[len_at] = (fan_at - len_at - 2) as u32;
            codes[len_at + 1] = ((codes.len() - fan_at) as u32) << 1 | open as u32;
        }
        for &u in &locals[l0..] {
            local_of[u as usize] = u32::MAX;
        }
        n_touched += touched.len();
        if !cursor.collapse() {
            return Err(PyramidError::Internal(format!(
                "cannot collapse level {}",
                v + 1
            )));
        }
    }
    rec.offsets.push(SplitOffsets {
        locals: rec.locals.len(),
        codes: rec.codes.len(),
        weights: rec.weights.len(),
        details: n_touched,
    });
    Ok(rec)
}

/// The signal-independent per-split streams of a pyramid being built (codes still 32-bit);
/// the `details` offsets count the touched vertices, whose details come later.
struct Records {
    offsets: Vec<SplitOffsets>,
    locals: Vec<u32>,
    codes: Vec<u32>,
    weights: Vec<f64>,
}

impl Records {
    /// The records of all ranges copied into the slots `waves` assigns them; `record_of(k)`
    /// names the range record holding split `k` and its position there. Streams are copied
    /// one at a time, so the peak memory is the records plus the largest stream; each is
    /// copied by all threads at once (the reads are scattered, so one thread would mostly
    /// wait for memory).
    fn in_slot_order<'a>(
        ranges: &[Records],
        waves: &Waves,
        record_of: impl Fn(usize) -> (&'a Records, usize) + Sync,
    ) -> Records {
        let n_splits: usize = ranges.iter().map(|r| r.offsets.len() - 1).sum();
        let at = |slot: usize| record_of(waves.split_at(slot));
        let mut next = SplitOffsets::default();
        let mut offsets = Vec::with_capacity(n_splits + 1);
        offsets.push(next);
        for slot in 0..n_splits {
            let (r, i) = at(slot);
            let (o, end) = (r.offsets[i], r.offsets[i + 1]);
            next.locals += end.locals - o.locals;
            next.codes += end.codes - o.codes;
            next.weights += end.weights - o.weights;
            next.details += end.details - o.details;
            offsets.push(next);
        }
        let chunks = 4 * rayon::current_num_threads();
        let cuts: Vec<usize> = (0..=chunks).map(|c| n_splits * c / chunks).collect();
        let locals = stream(&cuts, &offsets, &at, |r| &r.locals, |o| o.locals);
        let codes = stream(&cuts, &offsets, &at, |r| &r.codes, |o| o.codes);
        let weights = stream(&cuts, &offsets, &at, |r| &r.weights, |o| o.weights);
        Records {
            offsets,
            locals,
            codes,
            weights,
        }
    }

    /// Steps 2–5 of the split stored at `slot`, reading `f = f^(n)`: writes the presmoothed
    /// values of its 1-ring (`f^(n−1)` there) into `f` and its details into their places in
    /// `details` (`min_length`: see [`vertex_frame`](super::frames::vertex_frame)).
    fn split_details(
        &self,
        slot: usize,
        f: &SharedSignal,
        details: &SharedSignal,
        min_length: f64,
        scratch: &mut Scratch,
    ) {
        let (o, next) = (self.offsets[slot], self.offsets[slot + 1]);
        let table = &self.locals[o.locals..next.locals];
        let t = next.details - o.details;
        let survivor = decode(&self.codes, o.codes, o.weights, &mut scratch.entries);
        prefetch_next_split(f, &self.offsets, &self.locals, slot);
        // 2. Presmooth the ring from f^(n); remember f^(n) on the touched vertices.
        let g = &mut scratch.g;
        g.clear();
        g.extend(table.iter().map(|&x| f.get(x as usize)));
        scratch.saved.clear();
        scratch.saved.extend_from_slice(&g[..t]);
        presmooth_local(
            &self.codes,
            &self.weights,
            &scratch.entries,
            g,
            &mut scratch.smoothed,
        );
        // 3. Downsample: f^(n−1) is the presmoothed ring; the removed vertex is gone (its
        //    value is never read again: the prediction starts it at its survivor).
        g[1..t].copy_from_slice(&scratch.smoothed);
        for (&x, &s) in table[1..t].iter().zip(&scratch.smoothed) {
            f.set(x as usize, s);
        }
        // 4. Predict, 5. details in the frames of the predicted geometry.
        predict_local(
            &self.codes,
            &self.weights,
            &scratch.entries,
            survivor,
            g,
            &mut scratch.q,
            &mut scratch.frames,
            min_length,
        );
        for i in 0..t {
            let d = scratch.frames[i].to_local(scratch.saved[i] - scratch.q[i]);
            details.set(o.details + i, d);
        }
    }

    /// Steps 2–5 for every split, turning `f = f^(finest)` into the base signal (on the base
    /// vertices) and filling `details`: waves from the last to the first, large waves on
    /// rayon's threads (see [`run_waves`]).
    fn downsample(
        &self,
        waves: &Waves,
        f: &mut [DVec3],
        details: &mut [DVec3],
        min_length: f64,
        progress: &dyn Progress,
    ) {
        let (f, details) = (SharedSignal::new(f), SharedSignal::new(details));
        run_waves(
            (0..waves.len()).rev().map(|w| waves.wave(w)),
            |done| progress.update(RECORDS_SHARE + (1.0 - RECORDS_SHARE) * done),
            |slot, scratch: &mut Scratch| {
                self.split_details(slot, &f, &details, min_length, scratch)
            },
        );
    }
}

/// One stream of the records in slot order ([`Records::in_slot_order`]): `data` of the range
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
fn surface_stats(mesh: &Mesh) -> (f64, f64) {
    let area = mesh.faces().map(|f| mesh.face_area(f)).sum();
    (area, mesh.bbox_diagonal())
}
