//! [`MeanCurvatureStep`]: one Jacobi update of the implicit mean-curvature-motion system as a
//! [`Relaxation`], so the detail pyramid can predict with it (`--relax mcm`).
//!
//! At vertex i, with lumped mass `M_ii`, cotangent weights `w_ij = ½(cot θ_ij + cot θ'_ij)`
//! (boundary edges: one term — natural boundary conditions) and `α_i = (c·h_i)²/2` where
//! `h_i` is the mean length of the edges at i, the implicit system `(M + αL) x = M s` with the
//! current signal `s` as both data and initial guess gives the Jacobi update
//!
//! ```text
//! x_i = (M_ii s_i + α_i Σ_j w_ij s_j) / (M_ii + α_i Σ_j w_ij)
//! ```
//!
//! an affine combination (weights sum to 1), followed by damping
//! `out = s_i + ω (x_i − s_i)`. All weights come from `geometry`, so they do not depend on
//! the signal. Since `α_i` scales with `h_i²` like `M_ii`, the weights are scale invariant.
//! On a planar mesh the cotangent Laplacian annihilates linear functions at interior
//! vertices, so those are fixed points there.

use crate::mesh::{Mesh, SlotIndex, VertexId, cotangent};
use crate::relax::Relaxation;
use glam::DVec3;
use smallvec::SmallVec;

/// Jacobi update of the implicit MCM system; see the module docs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeanCurvatureStep {
    /// Filter-width constant c: σ_i = c·h_i with h_i the mean edge length at the vertex
    /// (default 1.0, "σ ∼ h" of the paper at the level being relaxed; the self weight of a
    /// regular interior vertex is then about 1/3).
    pub width: f64,
    /// Damping ω of the update (default 1.0: the plain Jacobi step).
    pub damping: f64,
}

impl Default for MeanCurvatureStep {
    fn default() -> Self {
        MeanCurvatureStep {
            width: 1.0,
            damping: 1.0,
        }
    }
}

/// The affine weights of one vertex's update: `x_i = self_weight·s_i + Σ w·s_j`.
#[derive(Clone, Debug, PartialEq)]
pub struct StepWeights {
    /// Weight of the vertex's own value.
    pub self_weight: f64,
    /// Neighbours (circulation order) and their weights.
    pub neighbors: SmallVec<[(VertexId, f64); 8]>,
}

impl MeanCurvatureStep {
    /// The weights of the undamped update at `v`, from `geometry[slot]`. They sum to 1. An
    /// isolated vertex, or one whose system row degenerates (zero-area fan, weights cancelling),
    /// gets the identity (`self_weight = 1`, no neighbours).
    pub fn weights(&self, mesh: &Mesh, geometry: &[DVec3], v: VertexId) -> StepWeights {
        let identity = StepWeights {
            self_weight: 1.0,
            neighbors: SmallVec::new(),
        };
        let p = geometry[v.slot()];
        let mut mass = 0.0;
        let mut edge_sum = 0.0;
        let mut neighbors: SmallVec<[(VertexId, f64); 8]> = SmallVec::new();
        for h in mesh.outgoing(v) {
            let j = mesh.to_vertex(h);
            let q = geometry[j.slot()];
            edge_sum += (q - p).length();
            let mut w = 0.0;
            // Angle opposite edge (v, j) in the face left of h and in the face left of twin.
            for g in [h, mesh.twin(h)] {
                if mesh.is_boundary_halfedge(g) {
                    continue;
                }
                let o = geometry[mesh.to_vertex(mesh.next(g)).slot()];
                let a = geometry[mesh.from_vertex(g).slot()];
                let b = geometry[mesh.to_vertex(g).slot()];
                w += 0.5 * cotangent(a - o, b - o);
            }
            if !mesh.is_boundary_halfedge(h) {
                let o = geometry[mesh.to_vertex(mesh.next(h)).slot()];
                mass += 0.5 * (q - p).cross(o - p).length() / 3.0;
            }
            neighbors.push((j, w));
        }
        if neighbors.is_empty() {
            return identity;
        }
        let h_i = edge_sum / neighbors.len() as f64;
        let alpha = 0.5 * (self.width * h_i).powi(2);
        let w_sum: f64 = neighbors.iter().map(|(_, w)| w).sum();
        let abs_sum: f64 = neighbors.iter().map(|(_, w)| w.abs()).sum();
        let denom = mass + alpha * w_sum;
        // Guard: the row must stay clearly positive relative to its own entries.
        if !(denom > 1e-12 * (mass + alpha * abs_sum)) || !denom.is_finite() {
            return identity;
        }
        for (_, w) in neighbors.iter_mut() {
            *w *= alpha / denom;
        }
        StepWeights {
            self_weight: mass / denom,
            neighbors,
        }
    }
}

impl Relaxation for MeanCurvatureStep {
    fn name(&self) -> &'static str {
        "mcm"
    }

    fn relax(
        &self,
        mesh: &Mesh,
        geometry: &[DVec3],
        signal: &[DVec3],
        vertices: &[VertexId],
        out: &mut [DVec3],
    ) {
        for (o, &v) in out.iter_mut().zip(vertices) {
            let s = signal[v.slot()];
            let w = self.weights(mesh, geometry, v);
            let x = w.self_weight * s
                + w.neighbors
                    .iter()
                    .map(|&(j, wj)| wj * signal[j.slot()])
                    .sum::<DVec3>();
            *o = s + self.damping * (x - s);
        }
    }
}
