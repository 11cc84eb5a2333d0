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

use super::Relaxation;
use crate::mesh::{Mesh, SlotIndex, VertexId, cotangent};
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
                mass += crate::mesh::geometry::triangle_area(p, q, o) / 3.0;
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
        if !denom.is_finite() || denom <= 1e-12 * (mass + alpha * abs_sum) {
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

    /// The damped update as one stencil: `(1 − ω + ω·self_weight)` on the vertex itself (first
    /// entry, omitted when zero), `ω·w_j` on each neighbour. The stencil contains the vertex
    /// itself, so a caller predicting a vertex without a value must give it a starting value
    /// first (the detail pyramid starts a new vertex at its survivor). A vertex whose update is
    /// the identity returns `false`.
    fn stencil(
        &self,
        mesh: &Mesh,
        geometry: &[DVec3],
        vertex: VertexId,
        out: &mut Vec<(VertexId, f64)>,
    ) -> bool {
        out.clear();
        let w = self.weights(mesh, geometry, vertex);
        let self_weight = 1.0 - self.damping + self.damping * w.self_weight;
        if w.neighbors.is_empty() || self.damping == 0.0 {
            return false;
        }
        if self_weight != 0.0 {
            out.push((vertex, self_weight));
        }
        out.extend(w.neighbors.iter().map(|&(j, wj)| (j, self.damping * wj)));
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::relax::relax_by_stencils;

    /// The damped update as the module docs write it, `s + ω (x − s)`, for comparing the
    /// stencil with.
    fn damped_update(
        step: &MeanCurvatureStep,
        mesh: &Mesh,
        geometry: &[DVec3],
        signal: &[DVec3],
        vertices: &[VertexId],
        out: &mut [DVec3],
    ) {
        for (o, &v) in out.iter_mut().zip(vertices) {
            let s = signal[v.slot()];
            let w = step.weights(mesh, geometry, v);
            let x = w.self_weight * s
                + w.neighbors
                    .iter()
                    .map(|&(j, wj)| wj * signal[j.slot()])
                    .sum::<DVec3>();
            *o = s + step.damping * (x - s);
        }
    }

    fn plane(n: usize, jitter: f64) -> Mesh {
        let (p, t) = crate::mesh::shapes::grid(n, |i, j| {
            // Deterministic interior jitter keeps triangles valid but irregular.
            let interior = i > 0 && j > 0 && i < n && j < n;
            let d = if interior {
                jitter * (((i * 7 + j * 13) % 5) as f64 / 5.0 - 0.4)
            } else {
                0.0
            };
            DVec3::new(i as f64 + d, j as f64 - 0.5 * d, 0.0)
        });
        Mesh::from_triangles(&p, &t).unwrap().mesh
    }

    #[test]
    fn weights_sum_to_one_and_are_positive_on_a_regular_grid() {
        let m = plane(4, 0.0);
        let g = m.positions();
        let step = MeanCurvatureStep::default();
        for v in m.vertices() {
            let w = step.weights(&m, &g, v);
            let sum = w.self_weight + w.neighbors.iter().map(|x| x.1).sum::<f64>();
            assert!((sum - 1.0).abs() < 1e-14);
            assert!(w.self_weight > 0.0 && w.self_weight < 1.0);
            assert!(w.neighbors.iter().all(|x| x.1 >= 0.0));
        }
    }

    #[test]
    fn linear_signals_are_fixed_points_at_interior_vertices_of_a_plane() {
        let step = MeanCurvatureStep::default();
        let m = plane(5, 0.3);
        let g = m.positions();
        let signal: Vec<DVec3> = g
            .iter()
            .map(|p| DVec3::new(2.0 * p.x - p.y + 1.0, 0.5 * p.y, p.x + p.y))
            .collect();
        let all: Vec<_> = m.vertices().collect();
        let mut out = vec![DVec3::ZERO; all.len()];
        relax_by_stencils(&step, &m, &g, &signal, &all, &mut out);
        for (i, &v) in all.iter().enumerate() {
            if !m.is_boundary_vertex(v) {
                assert!((out[i] - signal[v.slot()]).length() < 1e-12);
            }
        }
        // Geometry relaxed on itself stays in its plane everywhere (boundary included).
        relax_by_stencils(&step, &m, &g, &g, &all, &mut out);
        assert!(out.iter().all(|p| p.z.abs() < 1e-15));
    }

    #[test]
    fn stencil_is_the_damped_update_as_weights() {
        let m = plane(4, 0.25);
        let g = m.positions();
        let bumpy: Vec<DVec3> = g
            .iter()
            .enumerate()
            .map(|(i, p)| *p + DVec3::new(0.1, -0.2, 1.0) * (((i * 7) % 5) as f64 * 0.1))
            .collect();
        let all: Vec<_> = m.vertices().collect();
        for damping in [1.0, 0.6] {
            let step = MeanCurvatureStep {
                damping,
                ..Default::default()
            };
            let mut out = vec![DVec3::ZERO; all.len()];
            damped_update(&step, &m, &g, &bumpy, &all, &mut out);
            let mut st = Vec::new();
            for (i, &v) in all.iter().enumerate() {
                assert!(step.stencil(&m, &g, v, &mut st));
                let sum: f64 = st.iter().map(|x| x.1).sum();
                assert!((sum - 1.0).abs() < 1e-13, "weights sum to {sum}");
                let x: DVec3 = st.iter().map(|&(u, w)| w * bumpy[u.slot()]).sum();
                assert!((x - out[i]).length() < 1e-13, "{x} vs {}", out[i]);
            }
        }
        // An isolated vertex keeps its value: no stencil.
        let lone = Mesh::from_triangles(&[DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z], &[[0, 1, 2]])
            .unwrap()
            .mesh;
        let iso = lone.vertices().find(|&v| lone.is_isolated(v)).unwrap();
        let mut st = vec![(iso, 1.0)];
        assert!(!MeanCurvatureStep::default().stencil(&lone, &lone.positions(), iso, &mut st));
        assert!(st.is_empty());
    }

    #[test]
    fn damping_and_scale_invariance() {
        let step = MeanCurvatureStep::default();
        let m = plane(3, 0.2);
        let g = m.positions();
        let bumpy: Vec<DVec3> = g
            .iter()
            .enumerate()
            .map(|(i, p)| *p + DVec3::Z * ((i % 3) as f64))
            .collect();
        let all: Vec<_> = m.vertices().collect();
        let mut full = vec![DVec3::ZERO; all.len()];
        let mut half = full.clone();
        relax_by_stencils(&step, &m, &g, &bumpy, &all, &mut full);
        let damped = MeanCurvatureStep {
            damping: 0.5,
            ..Default::default()
        };
        relax_by_stencils(&damped, &m, &g, &bumpy, &all, &mut half);
        for i in 0..all.len() {
            let s = bumpy[all[i].slot()];
            assert!((half[i] - (s + 0.5 * (full[i] - s))).length() < 1e-12);
        }
        // Scaling the parameter geometry leaves the weights unchanged.
        let g3: Vec<DVec3> = g.iter().map(|p| *p * 3.0).collect();
        let mut scaled = vec![DVec3::ZERO; all.len()];
        relax_by_stencils(&step, &m, &g3, &bumpy, &all, &mut scaled);
        for i in 0..all.len() {
            assert!((scaled[i] - full[i]).length() < 1e-12);
        }
    }
}
