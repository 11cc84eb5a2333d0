//! Relaxation operators: the plug-in point shared by the detail pyramid, the cascadic
//! subdivider and the smoother.
//!
//! One shape fits all of them: *relax a set of vertices, Jacobi style* — every new value is
//! computed from the old values, then the caller writes them all. Values live in flat arrays
//! indexed by [`SlotIndex::slot`](crate::mesh::SlotIndex::slot), so an operator never hashes.

use crate::mesh::{Mesh, VertexId};
use crate::pm::FlatReplay;
use glam::DVec3;

pub mod mean_curvature;
pub mod normal_adaptive;
pub mod second_difference;
pub mod spec;

pub use mean_curvature::MeanCurvatureStep;
pub use normal_adaptive::NormalAdaptive;
pub use second_difference::SecondDifference;
pub use spec::{RelaxKind, RelaxationSpec};

/// [`Relaxation::relax`] for an operator whose [`Relaxation::stencil`] describes it exactly:
/// each vertex gets `Σ w · signal[j]` over its stencil (in stencil order), or keeps its value
/// where it has none.
pub fn relax_by_stencils<R: Relaxation + ?Sized>(
    op: &R,
    mesh: &Mesh,
    geometry: &[DVec3],
    signal: &[DVec3],
    vertices: &[VertexId],
    out: &mut [DVec3],
) {
    let mut stencil = Vec::new();
    for (o, &v) in out.iter_mut().zip(vertices) {
        *o = if op.stencil(mesh, geometry, v, &mut stencil) {
            second_difference::apply_stencil(&stencil, signal)
        } else {
            signal[crate::mesh::SlotIndex::slot(v)]
        };
    }
}

/// A local smoothing operator on mesh vertices.
pub trait Relaxation: Sync {
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

    /// True when [`Relaxation::stencil`] describes the operator exactly at every vertex (the
    /// operator is linear in the signal, with weights from the mesh and the parameter geometry
    /// only). Default `false`.
    fn has_linear_stencils(&self) -> bool {
        false
    }

    /// The operator as fixed linear weights at `vertex`: fills `out` with `(neighbour, w)` so
    /// that the relaxed value is `Σ w · signal[neighbour]`, and returns `true`. Operators whose
    /// result is not such a stencil (nonlinear in the signal) keep this default, which returns
    /// `false`. An operator returning `true` for a vertex must give exactly that linear map in
    /// [`Relaxation::relax`]; an empty stencil with `true` is not allowed (return `false` for a
    /// vertex that keeps its value). The stencil may contain `vertex` itself (a self weight);
    /// the detail pyramid starts a vertex being predicted at its survivor's value, so a self
    /// weight reads that. The detail pyramid caches stencils per level with this, so
    /// re-filtering needs no mesh at all.
    fn stencil(
        &self,
        mesh: &Mesh,
        geometry: &[DVec3],
        vertex: VertexId,
        out: &mut Vec<(VertexId, f64)>,
    ) -> bool {
        let _ = (mesh, geometry, vertex);
        out.clear();
        false
    }

    /// [`Relaxation::stencil`] for several vertices at once: appends the stencil of each of
    /// `vertices` to `out` and its length to `lens` (`0` where `stencil` returns `false`).
    /// Operators whose weights share work between neighbouring vertices (an edge's hinge
    /// coefficients enter the stencils of all four of its flap vertices) override this to
    /// compute that work once; the result must be bit-identical to calling `stencil` per
    /// vertex.
    fn stencils(
        &self,
        mesh: &Mesh,
        geometry: &[DVec3],
        vertices: &[VertexId],
        out: &mut Vec<(VertexId, f64)>,
        lens: &mut Vec<usize>,
    ) {
        let mut one = Vec::new();
        for &v in vertices {
            if self.stencil(mesh, geometry, v, &mut one) {
                out.extend_from_slice(&one);
                lens.push(one.len());
            } else {
                lens.push(0);
            }
        }
    }

    /// True when [`Relaxation::ring_stencils`] computes this operator's stencils. The detail
    /// pyramid's analysis then records its weights on a [`FlatReplay`] walked up from the base
    /// mesh, which is several times lighter on memory than a half-edge mesh. Default `false`.
    fn has_ring_stencils(&self) -> bool {
        false
    }

    /// [`Relaxation::stencils`] on the rings of `replay` (the mesh of its current level), with
    /// vertices and stencil entries as PM indices: the weights of the half-edge mesh the replay
    /// stands for, bit for bit when that mesh has the replay's slots. Returns `false`, appending
    /// nothing, for an operator without this path (the default).
    fn ring_stencils(
        &self,
        replay: &FlatReplay,
        geometry: &[DVec3],
        vertices: &[u32],
        out: &mut Vec<(u32, f64)>,
        lens: &mut Vec<usize>,
    ) -> bool {
        let _ = (replay, geometry, vertices, out, lens);
        false
    }
}
