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

use super::synthesis::{Scratch, decode, predict_local, presmooth_local};
use super::waves::Waves;
use super::{Codes, Pyramid, PyramidError, SplitOffsets};
use crate::mesh::{Mesh, SlotIndex, VertexId};
use crate::pm::ProgressiveMesh;
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
        let mut cursor = pm.cursor();
        let (surface_area, bbox_diagonal) = surface_stats(cursor.mesh());

        // Records are written finest split first (the order of the collapses), with wide
        // codes, then copied into storage order (wave by wave) and narrowed at the end.
        let mut offsets = Vec::with_capacity(n_splits + 1);
        let mut locals: Vec<u32> = Vec::with_capacity(32 * n_splits);
        let mut codes: Vec<u32> = Vec::with_capacity(128 * n_splits);
        let mut weights: Vec<f64> = Vec::with_capacity(72 * n_splits);
        let mut details: Vec<DVec3> = Vec::with_capacity(7 * n_splits);
        let push_offsets = |o: &mut Vec<SplitOffsets>, l: usize, c: usize, w: usize, d: usize| {
            o.push(SplitOffsets {
                locals: l,
                codes: c,
                weights: w,
                details: d,
            })
        };

        let mut f = signal.to_vec();
        let mut scratch = Scratch::default();
        let mut stencils = Vec::new();
        let mut stencil_lens = Vec::new();
        let mut touched: Vec<VertexId> = Vec::new();
        // PM vertex → its index in the current split's local table (u32::MAX: not in it).
        let mut local_of = vec![u32::MAX; geometry.len()];
        let report_every = (n_splits / 200).max(1);
        for (done, k) in (0..n_splits).rev().enumerate() {
            if done % report_every == 0 {
                progress.update(done as f64 / n_splits.max(1) as f64);
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
            push_offsets(
                &mut offsets,
                locals.len(),
                codes.len(),
                weights.len(),
                details.len(),
            );
            let (l0, c0, w0) = (locals.len(), codes.len(), weights.len());
            // 1. The touched vertices (v, then its ring CCW) open the local table; their
            //    stencils and fans (indices into the table) follow, weights alongside.
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
                local(j.slot(), &mut locals);
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
                    let x = local(u.slot(), &mut locals);
                    codes.push(x);
                    weights.push(w);
                }
                next_stencil += len;
                let mut first = None;
                let fan_at = codes.len();
                for h in mesh.outgoing(j) {
                    first.get_or_insert(h);
                    let x = local(mesh.to_vertex(h).slot(), &mut locals);
                    codes.push(x);
                }
                let open = first.is_some_and(|h| mesh.is_boundary_halfedge(h));
                codes[len_at] = (fan_at - len_at - 2) as u32;
                codes[len_at + 1] = ((codes.len() - fan_at) as u32) << 1 | open as u32;
            }
            for &u in &locals[l0..] {
                local_of[u as usize] = u32::MAX;
            }
            let t = touched.len();
            let table = &locals[l0..];
            let decoded = decode(&codes, c0, w0, &mut scratch.entries);
            debug_assert_eq!(decoded, survivor_local);
            // 2. Presmooth the ring from f^(n); remember f^(n) on the touched vertices.
            let g = &mut scratch.g;
            g.clear();
            g.extend(table.iter().map(|&x| f[x as usize]));
            scratch.saved.clear();
            scratch.saved.extend_from_slice(&g[..t]);
            presmooth_local(&codes, &weights, &scratch.entries, g, &mut scratch.smoothed);
            // 3. Downsample: f^(n−1) is the presmoothed ring; the removed vertex is gone (its
            //    value is never read again: the prediction starts it at its survivor).
            g[1..t].copy_from_slice(&scratch.smoothed);
            for (&x, &s) in table[1..t].iter().zip(&scratch.smoothed) {
                f[x as usize] = s;
            }
            // 4. Predict, 5. details in the frames of the predicted geometry.
            predict_local(
                &codes,
                &weights,
                &scratch.entries,
                survivor_local,
                g,
                &mut scratch.q,
                &mut scratch.frames,
            );
            for i in 0..t {
                let d = scratch.saved[i] - scratch.q[i];
                details.push(scratch.frames[i].to_local(d));
            }
            if !cursor.collapse() {
                return Err(PyramidError::Internal(format!(
                    "cannot collapse level {}",
                    v + 1
                )));
            }
        }
        push_offsets(
            &mut offsets,
            locals.len(),
            codes.len(),
            weights.len(),
            details.len(),
        );
        progress.update(1.0);

        // Storage order: wave by wave (see `waves`); analysis wrote split k at n_splits − 1 − k.
        let waves = Waves::schedule(n_splits, signal.len(), |k| {
            let (o, next) = (offsets[n_splits - 1 - k], offsets[n_splits - k]);
            (&locals[o.locals..next.locals], next.details - o.details)
        });
        let slotted = Records {
            offsets,
            locals,
            codes,
            weights,
            details,
        }
        .in_slot_order(&waves);
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
            details: slotted.details,
            waves,
            relaxation: relaxation.name(),
            surface_area,
            bbox_diagonal,
        })
    }
}

/// The per-split streams of a pyramid being built (codes still 32-bit).
struct Records {
    offsets: Vec<SplitOffsets>,
    locals: Vec<u32>,
    codes: Vec<u32>,
    weights: Vec<f64>,
    details: Vec<DVec3>,
}

impl Records {
    /// The records, written by the analysis finest split first, copied into the slots `waves`
    /// assigns them. Streams are copied one at a time, so the peak memory is the records plus
    /// the largest stream.
    fn in_slot_order(self, waves: &Waves) -> Records {
        let offsets = &self.offsets;
        let n_splits = offsets.len().saturating_sub(1);
        // The analysis position of the record stored at each slot.
        let position = |slot: usize| n_splits - 1 - waves.split_at(slot);
        fn gather<T: Copy>(
            from: Vec<T>,
            n_splits: usize,
            range: impl Fn(usize) -> std::ops::Range<usize>,
        ) -> Vec<T> {
            let mut to = Vec::with_capacity(from.len());
            for slot in 0..n_splits {
                to.extend_from_slice(&from[range(slot)]);
            }
            to
        }
        let field = |get: fn(&SplitOffsets) -> usize| {
            move |slot: usize| {
                let i = position(slot);
                get(&offsets[i])..get(&offsets[i + 1])
            }
        };
        let locals = gather(self.locals, n_splits, field(|o| o.locals));
        let codes = gather(self.codes, n_splits, field(|o| o.codes));
        let weights = gather(self.weights, n_splits, field(|o| o.weights));
        let details = gather(self.details, n_splits, field(|o| o.details));
        let mut at = SplitOffsets::default();
        let mut slotted = Vec::with_capacity(n_splits + 1);
        slotted.push(at);
        for slot in 0..n_splits {
            let (o, next) = (offsets[position(slot)], offsets[position(slot) + 1]);
            at.locals += next.locals - o.locals;
            at.codes += next.codes - o.codes;
            at.weights += next.weights - o.weights;
            at.details += next.details - o.details;
            slotted.push(at);
        }
        Records {
            offsets: slotted,
            locals,
            codes,
            weights,
            details,
        }
    }
}

/// Total area and bounding-box diagonal of a mesh.
fn surface_stats(mesh: &Mesh) -> (f64, f64) {
    let area = mesh.faces().map(|f| mesh.face_area(f)).sum();
    (area, mesh.bbox_diagonal())
}
