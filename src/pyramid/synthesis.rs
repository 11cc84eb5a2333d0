//! Synthesis (`docs/algorithms.md` §1c): from the base signal, split by split, predict the new vertex
//! and its 1-ring with the level's relaxation weights, rebuild their frames from the prediction,
//! and add the scaled details.
//!
//! The prediction and the frames here are the ones the analysis uses too (`predict_values`,
//! `local_frames`), so both passes evaluate identical arithmetic in identical order; with unit
//! gains synthesis returns the analysed signal up to rounding.
//!
//! Each split works on its *local table* (see [`DetailPyramid`]): the values of the few dozen vertices
//! it reads are gathered once into a small contiguous buffer, predicted and framed there, and
//! only the touched vertices are written back. All per-split records are read front to back:
//! they are stored wave by wave (`waves`), and the splits of a large wave, which read nothing
//! another writes, run on rayon's threads with the bits of the sequential order.

use super::frames::{Frame, LocalIndex, frame_min_length, vertex_frame};
use super::gains::LevelGains;
use super::quantise::{Targets, dequantised, quantised};
use super::waves::{SharedSignal, run_waves};
use super::{Codes, DetailPyramid, PyramidError, SplitOffsets};
use glam::DVec3;

/// One touched entry of a split record, decoded: where its stencil indices, weights and fan
/// live in the streams.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Entry {
    /// Stencil indices: `codes[stencil..stencil + len]`, weights `weights[weight..weight + len]`.
    pub stencil: usize,
    pub len: usize,
    pub weight: usize,
    /// Fan indices: `codes[fan..fan + fan_len]`.
    pub fan: usize,
    pub fan_len: usize,
    pub open: bool,
}

/// Scratch buffers reused across splits (no allocation per split).
#[derive(Default)]
pub(crate) struct Scratch {
    /// The split's local signal (gathered values, then the predicted geometry `G`).
    pub g: Vec<DVec3>,
    pub q: Vec<DVec3>,
    pub frames: Vec<Frame>,
    pub entries: Vec<Entry>,
    pub smoothed: Vec<DVec3>,
}

/// Decodes the record of one split starting at `codes[c]` (weights at `w`) into `entries`;
/// returns the local index of the survivor.
#[inline]
pub(crate) fn decode<I: LocalIndex>(
    codes: &[I],
    c: usize,
    w: usize,
    entries: &mut Vec<Entry>,
) -> usize {
    let t = codes[c].at();
    let survivor = codes[c + 1].at();
    let (mut c, mut w) = (c + 2, w);
    entries.clear();
    for _ in 0..t {
        let len = codes[c].at();
        let fan_word = codes[c + 1].at();
        let fan_len = fan_word >> 1;
        entries.push(Entry {
            stencil: c + 2,
            len,
            weight: w,
            fan: c + 2 + len,
            fan_len,
            open: fan_word & 1 == 1,
        });
        c += 2 + len + fan_len;
        w += len;
    }
    survivor
}

/// Cache hints for the values the split stored after `slot` gathers: they are scattered over
/// `f` (PM order is not mesh order) and miss the cache on large meshes, so hinting them while
/// the split at `slot` computes overlaps the misses. Analysis and synthesis both call it.
#[inline]
pub(crate) fn prefetch_next_split(
    f: &SharedSignal,
    offsets: &[SplitOffsets],
    locals: &[u32],
    slot: usize,
) {
    if let Some(after) = offsets.get(slot + 2) {
        for &x in &locals[offsets[slot + 1].locals..after.locals] {
            f.prefetch(x as usize);
        }
    }
}

/// `Σ w g[i]` over a stencil whose weights sum to one (every relaxation's do), evaluated as
/// `a + Σ w (g[i] − a)` with `a` the stencil's first value: the first weight is implied, so
/// the weights used always sum to exactly one and their f32 rounding moves the result by a
/// fraction of the stencil's extent, not of the coordinates (a scan far from the origin
/// predicts as well as one at it). Two interleaved accumulators: the dependency chain of the
/// sum is what bounds this loop.
#[inline(always)]
fn relax_local<I: LocalIndex>(idx: &[I], w: &[f32], g: &[DVec3]) -> DVec3 {
    let anchor = g[idx[0].at()];
    let term = |k: usize| f64::from(w[k]) * (g[idx[k].at()] - anchor);
    let mut a0 = DVec3::ZERO;
    let mut a1 = DVec3::ZERO;
    let mut k = 1;
    while k + 1 < idx.len() {
        a0 += term(k);
        a1 += term(k + 1);
        k += 2;
    }
    if k < idx.len() {
        a0 += term(k);
    }
    anchor + (a0 + a1)
}

/// The value of entry `e` relaxed from `g`, or `fallback` when its stencil is empty.
#[inline(always)]
fn relax_entry<I: LocalIndex>(
    codes: &[I],
    weights: &[f32],
    e: &Entry,
    g: &[DVec3],
    fallback: DVec3,
) -> DVec3 {
    if e.len == 0 {
        return fallback;
    }
    relax_local(
        &codes[e.stencil..e.stencil + e.len],
        &weights[e.weight..e.weight + e.len],
        g,
    )
}

/// The relaxation `R^n` of every 1-ring entry (entries `1..`) from `g` (Jacobi), into `out`;
/// the analysis presmoothing.
pub(crate) fn presmooth_local<I: LocalIndex>(
    codes: &[I],
    weights: &[f32],
    entries: &[Entry],
    g: &[DVec3],
    out: &mut Vec<DVec3>,
) {
    out.clear();
    for (i, e) in entries.iter().enumerate().skip(1) {
        out.push(relax_entry(codes, weights, e, g, g[i]));
    }
}

/// The subdivision step `S_n` on a split's local signal `g` (entry `i` is `g[i]`; `g` holds
/// `f^(n−1)` on everything but the new vertex): the new vertex starts at its survivor's value
/// (operators with a self weight read it) and is predicted, then its 1-ring simultaneously
/// (reading the new vertex's prediction). Leaves the predictions in `q` and the predicted
/// geometry `G` in `g`, from which [`local_frames`] builds the frames.
#[inline]
pub(crate) fn predict_values<I: LocalIndex>(
    codes: &[I],
    weights: &[f32],
    entries: &[Entry],
    survivor: usize,
    g: &mut [DVec3],
    q: &mut Vec<DVec3>,
) {
    let t = entries.len();
    g[0] = g[survivor];
    let qv = relax_entry(codes, weights, &entries[0], g, g[survivor]);
    g[0] = qv;
    q.clear();
    q.push(qv);
    for (i, e) in entries.iter().enumerate().skip(1) {
        q.push(relax_entry(codes, weights, e, g, g[i]));
    }
    g[1..t].copy_from_slice(&q[1..]);
}

/// The frames of all touched entries of a split, built from the predicted geometry `G` in `g`
/// (`min_length`: see [`vertex_frame`]).
#[inline]
pub(crate) fn local_frames<I: LocalIndex>(
    codes: &[I],
    entries: &[Entry],
    survivor: usize,
    g: &[DVec3],
    frames: &mut Vec<Frame>,
    min_length: f64,
) {
    frames.clear();
    for (i, e) in entries.iter().enumerate() {
        let reference = if i == 0 { survivor } else { 0 };
        let fan = &codes[e.fan..e.fan + e.fan_len];
        frames.push(vertex_frame(g, i, fan, e.open, reference, min_length));
    }
}

impl DetailPyramid {
    /// The prediction step shared by synthesis and the analysis' closed loop: gathers the
    /// local table of the split stored at `slot` from `f = f^(n−1)`, decodes its record and
    /// predicts its touched vertices into `scratch.q` (the predicted geometry in
    /// `scratch.g`). Returns the survivor's local index, for [`Self::split_frames`].
    #[inline]
    fn predict_split<I: LocalIndex>(
        &self,
        codes: &[I],
        slot: usize,
        f: &SharedSignal,
        scratch: &mut Scratch,
    ) -> usize {
        let o = self.offsets[slot];
        let locals = &self.locals[o.locals..self.offsets[slot + 1].locals];
        prefetch_next_split(f, &self.offsets, &self.locals, slot);
        let g = &mut scratch.g;
        g.clear();
        g.extend(locals.iter().map(|&x| f.get(x as usize)));
        let survivor = decode(codes, o.codes, o.weights, &mut scratch.entries);
        predict_values(
            codes,
            &self.weights,
            &scratch.entries,
            survivor,
            g,
            &mut scratch.q,
        );
        survivor
    }

    /// The frames of the touched vertices of the split [`Self::predict_split`] just predicted,
    /// into `scratch.frames`.
    #[inline]
    fn split_frames<I: LocalIndex>(&self, codes: &[I], survivor: usize, scratch: &mut Scratch) {
        local_frames(
            codes,
            &scratch.entries,
            survivor,
            &scratch.g,
            &mut scratch.frames,
            frame_min_length(self.bbox_diagonal),
        );
    }

    /// Computes the values the split stored at `slot` gives its touched vertices (the new
    /// vertex, then its 1-ring) from `f = f^(n−1)`, and writes them into `f`.
    #[inline]
    fn synthesize_split<I: LocalIndex>(
        &self,
        codes: &[I],
        slot: usize,
        f: &SharedSignal,
        gains: &LevelGains,
        scratch: &mut Scratch,
    ) {
        let (o, next) = (self.offsets[slot], self.offsets[slot + 1]);
        let locals = &self.locals[o.locals..next.locals];
        let survivor = self.predict_split(codes, slot, f, scratch);
        let level = self.level_of_split(self.waves.split_at(slot));
        let (tangential, normal) = gains.split_gain(level);
        if tangential == 0.0 && normal == 0.0 {
            // A level the filter removes (low-pass, stop-band): its details vanish, so the
            // prediction is the result and the frames, about half of a split's work, are
            // not needed.
            for (&x, &q) in locals.iter().zip(&scratch.q) {
                f.set(x as usize, q);
            }
            return;
        }
        self.split_frames(codes, survivor, scratch);
        let details = &self.details[o.details..next.details];
        // The touched vertices open the local table; there is one detail for each.
        for (((&x, &q), frame), &d) in locals
            .iter()
            .zip(&scratch.q)
            .zip(&scratch.frames)
            .zip(details)
        {
            let d = dequantised(d, self.detail_step);
            f.set(x as usize, q + frame.to_world_scaled(d, tangential, normal));
        }
    }

    /// The closed loop of the analysis (module `quantise`) for the split stored at `slot`:
    /// predicts its touched vertices from `f = f^(n−1)` as synthesis with unit gains does,
    /// replaces their targets in `targets` by the quantised details that bring them closest,
    /// and writes the values synthesis will compute from those into `f`.
    fn quantise_split<I: LocalIndex>(
        &self,
        codes: &[I],
        slot: usize,
        signal: &[DVec3],
        f: &SharedSignal,
        targets: &Targets,
        scratch: &mut Scratch,
    ) {
        let (o, next) = (self.offsets[slot], self.offsets[slot + 1]);
        let locals = &self.locals[o.locals..next.locals];
        let survivor = self.predict_split(codes, slot, f, scratch);
        self.split_frames(codes, survivor, scratch);
        let step = self.detail_step;
        for (i, ((&x, &q), frame)) in locals
            .iter()
            .zip(&scratch.q)
            .zip(&scratch.frames)
            .enumerate()
        {
            let target = signal[x as usize] + targets.displacement(o.details + i);
            let detail = quantised(frame.to_local(target - q), step);
            targets.set_detail(o.details + i, detail);
            let d = dequantised(detail, step);
            // The very expression synthesis evaluates with unit gains, so that it computes
            // these bits.
            f.set(x as usize, q + frame.to_world_scaled(d, 1.0, 1.0));
        }
    }

    /// Turns `targets` (storage order: per touched entry, the value the analysis had there
    /// before its split's presmoothing, as a displacement from `signal`; see
    /// [`Targets`]) into the pyramid's quantised details, in place, synthesising from the base
    /// with unit gains as it goes (the closed loop of module `quantise`). `progress` hears the
    /// share of splits done.
    pub(crate) fn quantise_details(
        &self,
        signal: &[DVec3],
        mut targets: Vec<[i32; 3]>,
        progress: impl Fn(f64) + Sync,
    ) -> Vec<[i32; 3]> {
        let mut f = self.base_signal();
        {
            let f = SharedSignal::new(&mut f);
            let targets = Targets::new(&mut targets);
            with_codes!(&self.codes, c => run_waves(
                (0..self.waves.len()).map(|w| self.waves.wave(w)),
                &progress,
                |slot, scratch: &mut Scratch| {
                    self.quantise_split(c, slot, signal, &f, &targets, scratch)
                },
                |slots| self.release_slots(slots),
            ));
        }
        targets
    }

    /// Synthesis of the splits `splits` on `f`: wave after wave, in storage order, large waves
    /// on rayon's threads (see [`run_waves`]).
    fn synthesize_splits<I: LocalIndex>(
        &self,
        codes: &[I],
        f: &mut [DVec3],
        splits: std::ops::Range<usize>,
        gains: &LevelGains,
    ) {
        let f = SharedSignal::new(f);
        // Part of the hierarchy: a wave stores its splits by place, not by number, so list the
        // slots of the splits asked for. Waves occupy consecutive slots, so in increasing
        // order the slots fall wave by wave.
        let listed: Option<Vec<u32>> =
            (splits.start != 0 || splits.end != self.n_splits()).then(|| {
                let mut slots: Vec<u32> = splits.map(|k| self.waves.slot_of(k) as u32).collect();
                slots.sort_unstable();
                slots
            });
        let waves = (0..self.waves.len()).map(|w| {
            let wave = self.waves.wave(w);
            match &listed {
                None => wave,
                Some(slots) => {
                    slots.partition_point(|&s| (s as usize) < wave.start)
                        ..slots.partition_point(|&s| (s as usize) < wave.end)
                }
            }
        });
        run_waves(
            waves,
            |_| {},
            |i, scratch: &mut Scratch| {
                let slot = listed.as_ref().map_or(i, |slots| slots[i] as usize);
                self.synthesize_split(codes, slot, &f, gains, scratch)
            },
            |run: std::ops::Range<usize>| match &listed {
                None => self.release_slots(run),
                // The listed slots are increasing: these runs span the slots between.
                Some(slots) => {
                    self.release_slots(slots[run.start] as usize..slots[run.end - 1] as usize + 1)
                }
            },
        );
    }
}

impl DetailPyramid {
    /// The finest signal (positions, PM order, [`DetailPyramid::signal_len`] long) with the details
    /// of every level `n` scaled by `gains` — the filtered surface. Unit gains reproduce the
    /// analysed signal to rounding.
    pub fn synthesize(&self, gains: &LevelGains) -> Vec<DVec3> {
        let mut f = self.base_signal();
        self.synthesize_range(&mut f, self.n_base, self.n_finest, gains);
        f
    }

    /// A signal array holding the base signal on `0..n0` and the pass-through values of the
    /// vertices without faces; entries in between are zero until synthesis sets them.
    pub fn base_signal(&self) -> Vec<DVec3> {
        let mut f = vec![DVec3::ZERO; self.signal_len()];
        f[..self.n_base].copy_from_slice(&self.base);
        f[self.n_finest..].copy_from_slice(&self.passthrough);
        f
    }

    /// The signal `f^(level)` of a coarser level (unit gains below it): vertices `0..level` hold
    /// the level's values. `level` is clamped to `[n0, n_vertices()]`.
    pub fn signal_at_level(&self, level: usize) -> Vec<DVec3> {
        let level = level.clamp(self.n_base, self.n_finest);
        let mut f = self.base_signal();
        self.synthesize_range(&mut f, self.n_base, level, &LevelGains::unit());
        f
    }

    /// Continues synthesis on `f` (a full-length signal holding `f^(from)` on `0..from`) up to
    /// level `to`, scaling the details of each level by `gains`.
    pub fn synthesize_range(&self, f: &mut [DVec3], from: usize, to: usize, gains: &LevelGains) {
        let from = from.clamp(self.n_base, self.n_finest);
        let to = to.clamp(from, self.n_finest);
        let splits = from - self.n_base..to - self.n_base;
        with_codes!(&self.codes, c => self.synthesize_splits(c, f, splits, gains))
    }

    /// [`DetailPyramid::synthesize_range`] from `from` to the finest level, checking that `f` fits.
    pub(crate) fn resynthesize_from(
        &self,
        mut f: Vec<DVec3>,
        from: usize,
        gains: &LevelGains,
    ) -> Result<Vec<DVec3>, PyramidError> {
        if f.len() != self.signal_len() {
            return Err(PyramidError::Invalid(format!(
                "signal has {} values, the pyramid needs {}",
                f.len(),
                self.signal_len()
            )));
        }
        if from < self.n_base || from > self.n_finest {
            return Err(PyramidError::Invalid(format!(
                "level {from} is outside the pyramid's levels {}..={}",
                self.n_base, self.n_finest
            )));
        }
        self.synthesize_range(&mut f, from, self.n_finest, gains);
        Ok(f)
    }
}
