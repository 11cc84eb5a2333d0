//! [`NormalAverage`]: a 1-ring average whose weights shrink with the vertex-normal difference.
//! It was the `--relax normal` operator of format 2.0 files; those files still load with it,
//! but it is no longer selectable: as a predictor it rounds creases (an average has no linear
//! precision) and on noisy scans its raw normals steer it at random. The normal-adaptive
//! operator (`normal_adaptive`) replaced it.
//!
//! At vertex i with neighbours j, from the parameter geometry only,
//!
//! ```text
//! w_j = exp(−‖n_i − n_j‖² / (2 s²)) / Σ_k exp(−‖n_i − n_k‖² / (2 s²)),   R(x)_i = Σ_j w_j x_j
//! ```
//!
//! with `n` the angle-weighted vertex normals and `s` the normal scale. The operator is linear in
//! the signal (weights depend on the geometry alone), so the pyramid can cache it as a stencil.
//!
//! Why vertex normals and not the dihedral angle of each edge: for a vertex *on* a crease, the
//! edges along the crease are the ones with the largest dihedral angle, so weighting by it
//! would pull crease vertices off the crease into the flat sides. Comparing vertex normals
//! keeps crease vertices averaging along the crease (their normals agree) and flat-side
//! vertices averaging within their side (a crease vertex's normal is halfway between the
//! sides), which is the bilateral behaviour Ohtake's anisotropic filter has on faces.
//!
//! Fallbacks: a neighbour without a defined normal (a zero-area fan) gets weight 1; if every
//! weight underflows, the uniform average is used. An isolated vertex keeps its value.

use crate::mesh::{Mesh, SlotIndex, VertexId};
use crate::relax::Relaxation;
use glam::DVec3;
use smallvec::SmallVec;

/// Normal-adaptive 1-ring averaging; see the module docs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalAverage {
    /// Normal scale s: the normal difference ‖n_i − n_j‖ at which a neighbour's weight falls to
    /// e^{−1/2} (default 0.25; a 45° difference, ‖Δn‖ ≈ 0.77, then weighs about 0.01).
    pub normal_scale: f64,
}

impl Default for NormalAverage {
    fn default() -> Self {
        NormalAverage { normal_scale: 0.25 }
    }
}

/// Angle-weighted unit normal of `v` from `geometry` (Thürmer–Wüthrich), or zero when its fan
/// has no area. Angle weights make a crease vertex's normal the exact bisector of the two sides
/// whatever the triangulation, which area weights do not.
fn vertex_normal(mesh: &Mesh, geometry: &[DVec3], v: VertexId) -> DVec3 {
    let p = geometry[v.slot()];
    let mut sum = DVec3::ZERO;
    for h in mesh.outgoing(v) {
        if mesh.is_boundary_halfedge(h) {
            continue;
        }
        let a = geometry[mesh.to_vertex(h).slot()] - p;
        let b = geometry[mesh.to_vertex(mesh.next(h)).slot()] - p;
        let n = a.cross(b);
        let len = n.length();
        if len > f64::MIN_POSITIVE && len.is_finite() {
            sum += a.angle_between(b) * (n / len);
        }
    }
    let len = sum.length();
    if len > f64::MIN_POSITIVE && len.is_finite() {
        sum / len
    } else {
        DVec3::ZERO
    }
}

impl NormalAverage {
    /// The normalised weights of the neighbours of `v` (circulation order); empty for an
    /// isolated vertex. They are positive and sum to 1.
    pub fn weights(
        &self,
        mesh: &Mesh,
        geometry: &[DVec3],
        v: VertexId,
    ) -> SmallVec<[(VertexId, f64); 8]> {
        let ni = vertex_normal(mesh, geometry, v);
        let scale = if self.normal_scale > 0.0 && self.normal_scale.is_finite() {
            self.normal_scale
        } else {
            f64::INFINITY // a degenerate scale means no attenuation: uniform weights
        };
        let mut out: SmallVec<[(VertexId, f64); 8]> = mesh
            .outgoing(v)
            .map(|h| {
                let j = mesh.to_vertex(h);
                let nj = vertex_normal(mesh, geometry, j);
                let w = if ni == DVec3::ZERO || nj == DVec3::ZERO {
                    1.0
                } else {
                    let t = (ni - nj).length() / scale;
                    (-0.5 * t * t).exp()
                };
                (j, w)
            })
            .collect();
        let sum: f64 = out.iter().map(|x| x.1).sum();
        if sum > 0.0 && sum.is_finite() {
            for x in out.iter_mut() {
                x.1 /= sum;
            }
        } else {
            let u = 1.0 / out.len().max(1) as f64;
            for x in out.iter_mut() {
                x.1 = u;
            }
        }
        out
    }
}

impl Relaxation for NormalAverage {
    fn name(&self) -> &'static str {
        "normal-average"
    }

    /// The neighbour weights (no self weight); `false` for an isolated vertex, which keeps its
    /// value.
    fn stencil(
        &self,
        mesh: &Mesh,
        geometry: &[DVec3],
        vertex: VertexId,
        out: &mut Vec<(VertexId, f64)>,
    ) -> bool {
        out.clear();
        out.extend(self.weights(mesh, geometry, vertex));
        !out.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::relax::folded_grid as grid;
    use crate::relax::relax_by_stencils;

    #[test]
    fn weights_sum_to_one_and_constants_are_kept() {
        for m in [grid(6, None), grid(6, Some(3.0))] {
            let g = m.positions();
            let op = NormalAverage::default();
            let verts: Vec<VertexId> = m.vertices().collect();
            for &v in &verts {
                let w = op.weights(&m, &g, v);
                let sum: f64 = w.iter().map(|x| x.1).sum();
                assert!((sum - 1.0).abs() < 1e-14 && w.iter().all(|x| x.1 > 0.0));
            }
            let c = vec![DVec3::new(1.5, -2.0, 0.25); g.len()];
            let mut out = vec![DVec3::ZERO; verts.len()];
            relax_by_stencils(&op, &m, &g, &c, &verts, &mut out);
            assert!(out.iter().all(|x| (*x - c[0]).length() < 1e-14));
            // The relaxation is the stencil exactly.
            let signal: Vec<DVec3> = g
                .iter()
                .map(|q| *q * 1.7 + DVec3::splat(q.x * q.y))
                .collect();
            relax_by_stencils(&op, &m, &g, &signal, &verts, &mut out);
            let mut st = Vec::new();
            for (i, &v) in verts.iter().enumerate() {
                assert!(op.stencil(&m, &g, v, &mut st));
                let x: DVec3 = st.iter().map(|&(j, w)| w * signal[j.slot()]).sum();
                assert_eq!(x, out[i]);
            }
        }
    }

    #[test]
    fn a_plane_gets_the_uniform_average() {
        let m = grid(4, None);
        let g = m.positions();
        for v in m.vertices() {
            let w = NormalAverage::default().weights(&m, &g, v);
            let u = 1.0 / w.len() as f64;
            assert!(w.iter().all(|x| (x.1 - u).abs() < 1e-14));
        }
    }

    #[test]
    fn cross_crease_weights_are_much_smaller_than_uniform() {
        // Fold at x = 3: vertices with x = 3 lie on the crease.
        let m = grid(6, Some(3.0));
        let g = m.positions();
        let op = NormalAverage::default();
        let on_crease = |q: DVec3| q.x == 3.0;
        let mut checked = 0;
        for v in m.vertices() {
            let p = g[v.slot()];
            // A flat-side vertex next to the crease (interior in y).
            if p.x != 2.0 || p.z != 0.0 || p.y < 1.0 || p.y > 5.0 {
                continue;
            }
            let w = op.weights(&m, &g, v);
            let uniform = 1.0 / w.len() as f64;
            for &(j, wj) in &w {
                if on_crease(g[j.slot()]) {
                    assert!(wj < 0.05 * uniform, "{wj} vs {uniform}");
                    checked += 1;
                }
            }
        }
        assert!(checked > 0);
        // A crease vertex averages along the crease.
        for v in m.vertices() {
            let p = g[v.slot()];
            if !on_crease(p) || p.y < 1.0 || p.y > 5.0 {
                continue;
            }
            let along: f64 = op
                .weights(&m, &g, v)
                .iter()
                .filter(|x| on_crease(g[x.0.slot()]))
                .map(|x| x.1)
                .sum();
            assert!(along > 0.9, "{along}");
        }
    }

    #[test]
    fn degenerate_geometry_falls_back_to_uniform() {
        let m = grid(2, None);
        let g = vec![DVec3::ZERO; m.n_vertices()];
        for v in m.vertices() {
            let w = NormalAverage::default().weights(&m, &g, v);
            let u = 1.0 / w.len() as f64;
            assert!(w.iter().all(|x| x.1 == u));
        }
    }
}
