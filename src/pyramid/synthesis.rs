//! Synthesis (`algorithms.md` §1c): from the base signal, split by split, predict the new vertex
//! and its 1-ring with the level's relaxation weights, rebuild their frames from the prediction,
//! and add the scaled details.
//!
//! The prediction step here is the one the analysis uses too ([`Pyramid::predict_split`]), so
//! both passes evaluate identical arithmetic in identical order; with unit gains synthesis
//! returns the analysed signal up to rounding.

use super::frames::{Frame, vertex_frame};
use super::gains::LevelGains;
use super::{Pyramid, PyramidError};
use glam::DVec3;

/// Scratch buffers reused across splits (no allocation per split).
#[derive(Default)]
pub(crate) struct Scratch {
    pub q: Vec<DVec3>,
    pub frames: Vec<Frame>,
    pub saved: Vec<DVec3>,
    pub smoothed: Vec<DVec3>,
}

impl Pyramid {
    /// `Σ w f` over the stencil of touched entry `e`, or `fallback` when the stencil is empty.
    #[inline]
    fn relax_entry(&self, e: usize, f: &[DVec3], fallback: DVec3) -> DVec3 {
        let r = self.stencil_start[e] as usize..self.stencil_start[e + 1] as usize;
        if r.is_empty() {
            return fallback;
        }
        let mut acc = DVec3::ZERO;
        for (&v, &w) in self.stencil_vertex[r.clone()]
            .iter()
            .zip(&self.stencil_weight[r])
        {
            acc += w * f[v as usize];
        }
        acc
    }

    /// The relaxation `R^n` of every 1-ring vertex of storage slot `s` from `f` (Jacobi), into
    /// `out`; the analysis presmoothing.
    pub(crate) fn presmooth_ring(&self, s: usize, f: &[DVec3], out: &mut Vec<DVec3>) {
        out.clear();
        let (a, b) = (
            self.touched_start[s] as usize,
            self.touched_start[s + 1] as usize,
        );
        for e in a + 1..b {
            let j = self.touched[e] as usize;
            out.push(self.relax_entry(e, f, f[j]));
        }
    }

    /// The subdivision step `S_n` of storage slot `s`: predicts the new vertex from the coarser
    /// signal, then its 1-ring (simultaneously, reading the new vertex's prediction), writes the
    /// predictions into `f` (which then holds the predicted geometry `G`) and into `q`, and
    /// builds the frames of all touched vertices from `G`.
    pub(crate) fn predict_split(&self, s: usize, f: &mut [DVec3], scratch: &mut Scratch) {
        let (a, b) = (
            self.touched_start[s] as usize,
            self.touched_start[s + 1] as usize,
        );
        let v = self.touched[a] as usize;
        let survivor = self.survivor[s];
        // A new vertex without weights starts where it was collapsed to.
        let qv = self.relax_entry(a, f, f[survivor as usize]);
        f[v] = qv;
        let q = &mut scratch.q;
        q.clear();
        q.push(qv);
        for e in a + 1..b {
            let j = self.touched[e] as usize;
            q.push(self.relax_entry(e, f, f[j]));
        }
        for (e, &qj) in (a + 1..b).zip(&q[1..]) {
            f[self.touched[e] as usize] = qj;
        }
        let frames = &mut scratch.frames;
        frames.clear();
        for e in a..b {
            let j = self.touched[e];
            let fan = &self.fan[self.fan_start[e] as usize..self.fan_start[e + 1] as usize];
            let reference = if e == a { survivor } else { v as u32 };
            frames.push(vertex_frame(f, j, fan, self.fan_open[e], reference));
        }
    }

    /// Synthesis of split storage slot `s` on top of `f = f^(n−1)`, leaving `f^(n)`.
    #[inline]
    fn synthesize_split(
        &self,
        k: usize,
        f: &mut [DVec3],
        gains: &LevelGains,
        scratch: &mut Scratch,
    ) {
        let s = self.split_slot(k);
        self.predict_split(s, f, scratch);
        let (tangential, normal) = gains.split_gain(self.level_of_split(k));
        let a = self.touched_start[s] as usize;
        for (i, (&q, frame)) in scratch.q.iter().zip(&scratch.frames).enumerate() {
            let e = a + i;
            let d = self.details[e];
            f[self.touched[e] as usize] = q + frame.to_world_scaled(d, tangential, normal);
        }
    }

    /// The finest signal (positions, PM order, [`Pyramid::signal_len`] long) with the details
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
        let mut scratch = Scratch::default();
        for k in from - self.n_base..to - self.n_base {
            self.synthesize_split(k, f, gains, &mut scratch);
        }
    }

    /// [`Pyramid::synthesize_range`] from `from` to the finest level, checking that `f` fits.
    pub fn resynthesize_from(
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
