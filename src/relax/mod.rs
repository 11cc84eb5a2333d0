//! Relaxation operators: the plug-in point shared by the detail pyramid, the cascadic
//! subdivider and the smoother.
//!
//! One shape fits all of them: *relax a set of vertices, Jacobi style* — every new value is
//! computed from the old values, then the caller writes them all. Values live in flat arrays
//! indexed by [`SlotIndex::slot`](crate::mesh::SlotIndex::slot), so an operator never hashes.

use crate::mesh::{Mesh, VertexId};
use glam::DVec3;

/// A local smoothing operator on mesh vertices.
pub trait Relaxation {
    /// Short name used on the command line (`second-difference`, `mcm`, `normal`).
    fn name(&self) -> &'static str;

    /// Computes new values for `vertices` from `signal` on the connectivity of `mesh`.
    ///
    /// * `geometry[v.slot()]` — the parameter geometry the weights come from (for the pyramid:
    ///   the original positions of the vertices present at this level);
    /// * `signal[v.slot()]` — the values being smoothed (positions or details);
    /// * `out[i]` receives the relaxed value of `vertices[i]`; `out.len() == vertices.len()`.
    ///
    /// Implementations must not panic on degenerate geometry (zero-area triangles, coincident
    /// vertices): where weights are undefined they fall back to a documented simpler rule.
    fn relax(
        &self,
        mesh: &Mesh,
        geometry: &[DVec3],
        signal: &[DVec3],
        vertices: &[VertexId],
        out: &mut [DVec3],
    );
}
