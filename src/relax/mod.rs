//! Relaxation operators: the linear smoothing steps the detail pyramid predicts and presmooths
//! with (`--relax`).
//!
//! Three operators, one file each:
//! - `second_difference`: [`SecondDifference`], Guskov's non-uniform second-difference
//!   operator (the default);
//! - `mean_curvature`: [`MeanCurvatureStep`], one damped Jacobi step of implicit
//!   mean-curvature motion (cotangent weights, lumped mass);
//! - `normal_adaptive`: [`NormalAdaptive`], Guskov's operator with every hinge weighted by the
//!   agreement of its triangles' normals (taken from an Ohtake-denoised guide), so that
//!   predictions stop at creases.
//!
//! `normal_average` keeps [`NormalAverage`], the 1-ring average that `--relax normal` was in
//! format 2.0 files, so those files still load as they were written.
//!
//! `spec` names them: [`RelaxKind`] is the value of `--relax`, [`RelaxationSpec`] the
//! operator with its parameters as a `.pyr` file records it.
//!
//! The contract ([`Relaxation`]): an operator is linear in the signal, its weights coming from
//! the connectivity and a parameter geometry only (for the pyramid: the original positions of
//! the level's vertices), never from the signal. So it is its stencils — per vertex,
//! `(neighbour, weight)` pairs with the relaxed value `Σ w · signal[neighbour]` — which the
//! pyramid records per level and re-filters with, without the mesh. A set of vertices is
//! relaxed Jacobi style, every new value computed from the old ones (`relax_by_stencils`).
//! Values live in flat arrays indexed by [`SlotIndex::slot`](crate::mesh::SlotIndex::slot), so
//! an operator never hashes.

use crate::mesh::{Mesh, VertexId};
use crate::pm::FlatReplay;
use glam::DVec3;

pub(crate) mod mean_curvature;
pub(crate) mod normal_adaptive;
pub(crate) mod normal_average;
pub(crate) mod second_difference;
pub(crate) mod spec;

pub use mean_curvature::{MeanCurvatureStep, StepWeights};
pub use normal_adaptive::NormalAdaptive;
pub use normal_average::NormalAverage;
pub use second_difference::SecondDifference;
pub use spec::RelaxKind;
pub use spec::RelaxationSpec;

/// An (n+1)² grid of unit squares in the plane z = 0; with `fold`, the points with x > `fold`
/// are bent up by 90° about the line x = fold (a crease along it). For the operators' tests.
#[cfg(test)]
pub(crate) fn folded_grid(n: usize, fold: Option<f64>) -> Mesh {
    let (p, t) = crate::mesh::shapes::grid(n, |i, j| {
        let (x, y) = (i as f64, j as f64);
        match fold {
            Some(f) if x > f => DVec3::new(f, y, x - f),
            _ => DVec3::new(x, y, 0.0),
        }
    });
    Mesh::from_triangles(&p, &t).expect("valid grid").mesh
}

/// One relaxation of `vertices`, Jacobi style: `out[i]` gets `Σ w · signal[j]` over the
/// stencil of `vertices[i]` (in stencil order), or keeps its value where it has none.
///
/// * `geometry[v.slot()]` — the parameter geometry the weights come from;
/// * `signal[v.slot()]` — the values being smoothed (positions or details);
/// * `out.len() == vertices.len()`.
#[cfg(test)]
pub(crate) fn relax_by_stencils<R: Relaxation + ?Sized>(
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

/// A local linear smoothing operator on mesh vertices; see the module docs.
pub trait Relaxation: Sync {
    /// Short name used on the command line (`second-difference`, `mcm`, `normal`).
    fn name(&self) -> &'static str;

    /// The operator at `vertex` as fixed linear weights, from `geometry[v.slot()]` on the
    /// connectivity of `mesh`: fills `out` with `(neighbour, w)` so that the relaxed value is
    /// `Σ w · signal[neighbour]`, and returns `true`; returns `false` with `out` empty for a
    /// vertex that keeps its value (an empty stencil with `true` is not allowed). The stencil
    /// may contain `vertex` itself (a self weight); the detail pyramid starts a vertex being
    /// predicted at its survivor's value, so a self weight reads that.
    ///
    /// Implementations must not panic on degenerate geometry (zero-area triangles, coincident
    /// vertices): where weights are undefined they fall back to a documented simpler rule.
    fn stencil(
        &self,
        mesh: &Mesh,
        geometry: &[DVec3],
        vertex: VertexId,
        out: &mut Vec<(VertexId, f64)>,
    ) -> bool;

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

    /// The operator's stencils on a [`FlatReplay`], if it computes them there (default
    /// `None`). The detail pyramid's analysis then records the weights on a replay walked up
    /// from the base mesh, which is several times lighter on memory than a half-edge mesh.
    fn as_ring_stencils(&self) -> Option<&dyn RingStencils> {
        None
    }
}

/// The stencils of a [`Relaxation`] on the rings of a [`FlatReplay`]
/// ([`Relaxation::as_ring_stencils`]).
pub trait RingStencils: Sync {
    /// [`Relaxation::stencils`] on the rings of `replay` (the mesh of its current level), with
    /// vertices and stencil entries as PM indices: the weights of the half-edge mesh the replay
    /// stands for, bit for bit when that mesh has the replay's slots.
    fn ring_stencils(
        &self,
        replay: &FlatReplay,
        geometry: &[DVec3],
        vertices: &[u32],
        out: &mut Vec<(u32, f64)>,
        lens: &mut Vec<usize>,
    );
}
