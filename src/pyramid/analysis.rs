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

use super::synthesis::Scratch;
use super::{Pyramid, PyramidError};
use crate::mesh::{Mesh, SlotIndex};
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

        let mut p = Pyramid {
            n_base,
            n_finest,
            passthrough: signal[n_finest..].to_vec(),
            base: Vec::new(),
            survivor: Vec::with_capacity(n_splits),
            touched_start: Vec::with_capacity(n_splits + 1),
            touched: Vec::with_capacity(7 * n_splits),
            stencil_start: Vec::with_capacity(7 * n_splits + 1),
            stencil_vertex: Vec::with_capacity(80 * n_splits),
            stencil_weight: Vec::with_capacity(80 * n_splits),
            fan_start: Vec::with_capacity(7 * n_splits + 1),
            fan: Vec::with_capacity(45 * n_splits),
            fan_open: Vec::with_capacity(7 * n_splits),
            details: Vec::with_capacity(7 * n_splits),
            relaxation: relaxation.name(),
            surface_area,
            bbox_diagonal,
        };
        p.touched_start.push(0);
        p.stencil_start.push(0);
        p.fan_start.push(0);

        let mut f = signal.to_vec();
        let mut scratch = Scratch::default();
        let mut stencil = Vec::new();
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
            // 1. Record the touched vertices (v, then its ring CCW) with weights and fans.
            let s = p.survivor.len();
            p.survivor.push(survivor);
            for j in std::iter::once(vh).chain(mesh.outgoing(vh).map(|h| mesh.to_vertex(h))) {
                p.touched.push(j.slot() as u32);
                if relaxation.stencil(mesh, geometry, j, &mut stencil) {
                    for &(u, w) in &stencil {
                        p.stencil_vertex.push(u.slot() as u32);
                        p.stencil_weight.push(w);
                    }
                }
                p.stencil_start.push(p.stencil_vertex.len() as u32);
                let mut first = None;
                for h in mesh.outgoing(j) {
                    first.get_or_insert(h);
                    p.fan.push(mesh.to_vertex(h).slot() as u32);
                }
                p.fan_start.push(p.fan.len() as u32);
                p.fan_open
                    .push(first.is_some_and(|h| mesh.is_boundary_halfedge(h)));
            }
            p.touched_start.push(p.touched.len() as u32);
            let (a, b) = (p.touched_start[s] as usize, p.touched_start[s + 1] as usize);
            if p.touched[a] as usize != v || !p.touched[a + 1..b].contains(&survivor) {
                return Err(PyramidError::Internal(format!(
                    "split {k}: vertex {v} is not adjacent to its survivor {survivor}"
                )));
            }
            // 2. Presmooth the ring from f^(n); remember f^(n) on the touched vertices.
            scratch.saved.clear();
            scratch
                .saved
                .extend(p.touched[a..b].iter().map(|&j| f[j as usize]));
            let mut smoothed = std::mem::take(&mut scratch.smoothed);
            p.presmooth_ring(s, &f, &mut smoothed);
            for (e, &x) in (a + 1..b).zip(&smoothed) {
                f[p.touched[e] as usize] = x;
            }
            // 3–4. Downsample (f[v] is no longer read: stencils never contain their own
            // vertex, and v's value is replaced by its prediction) and predict.
            p.predict_split(s, &mut f, &mut scratch);
            // 5. Details in the frames of the predicted geometry.
            for i in 0..b - a {
                let d = scratch.saved[i] - scratch.q[i];
                p.details.push(scratch.frames[i].to_local(d));
            }
            // f^(n−1): the presmoothed ring; the removed vertex is gone.
            for (e, &x) in (a + 1..b).zip(&smoothed) {
                f[p.touched[e] as usize] = x;
            }
            scratch.smoothed = smoothed;
            if !cursor.collapse() {
                return Err(PyramidError::Internal(format!(
                    "cannot collapse level {}",
                    v + 1
                )));
            }
        }
        progress.update(1.0);
        p.base = f[..n_base].to_vec();
        Ok(p)
    }
}

/// Total area and bounding-box diagonal of a mesh.
fn surface_stats(mesh: &Mesh) -> (f64, f64) {
    let area = mesh.faces().map(|f| mesh.face_area(f)).sum();
    (area, mesh.bbox_diagonal())
}
