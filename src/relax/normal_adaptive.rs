//! [`NormalAdaptive`]: Guskov's second-difference operator with every hinge weighted by how well
//! the normals of its two triangles agree, so that a prediction stops at creases
//! (`--relax normal`; `docs/algorithms.md` §1d).
//!
//! Guskov's operator (`second_difference`) predicts `f_i` by minimising `Σ_e (D_e f)²` over the
//! hinges `e` whose flap contains `i`. Here each hinge counts with a weight
//!
//! ```text
//! ω_e = exp(−(1 − cos θ_e) / s²),      R f_i = argmin Σ_e ω_e (D_e f)²,
//! w_ij = −Σ_e ω_e c_{e,i} c_{e,j} / Σ_e ω_e c_{e,i}²
//! ```
//!
//! with `θ_e` the angle between the normals of the hinge's two triangles and `s` the normal
//! scale (the `1 − cos θ = ‖n₁ − n₂‖² / 2` of Ohtake's normal kernels). Scaling a hinge's four
//! coefficients by `√ω_e` does exactly that, so the operator is Guskov's code with one factor
//! per hinge.
//!
//! Why this keeps creases where a weighted 1-ring average does not:
//!
//! * every `D_e` still kills constants, so the weights sum to one, and a hinge that lies in a
//!   plane still annihilates functions linear in that plane;
//! * at a crease the hinges *across* it (their triangles on two sides) get `ω ≈ 0`, the hinges
//!   *within* each side keep `ω ≈ 1`. A vertex on a flat side is then predicted from its side
//!   alone and stays in its plane; a vertex on the crease is predicted from the hinges of both
//!   sides, whose least-squares solution lies on both planes — on the crease line; a corner
//!   lies on three planes. Guskov's operator instead bends every crease hinge flat, which
//!   rounds the crease level after level; an average has no linear precision at all and
//!   shrinks it.
//!
//! The operator stays linear in the signal: the weights come from the parameter geometry and a
//! **guide** geometry the normals are taken from, never from the signal, so the pyramid's
//! reconstruction stays exact. On a noisy scan the parameter geometry's own normals are noise
//! (at the finest levels a hinge's angle is mostly noise), so the pyramid gives the operator the
//! finest level denoised by Ohtake's normal filtering (`smooth --method auto`, which keeps
//! creases) as its guide ([`NormalAdaptive::with_guide`]); without a guide the parameter
//! geometry is used, which suits clean CAD meshes.
//!
//! Fallbacks are Guskov's: degenerate hinges are skipped, a vertex without usable hinges or
//! with weights summing past the bound keeps its value; a hinge whose guide triangles have no
//! normal counts fully (`ω = 1`).

use super::second_difference::Steering;
use super::{Relaxation, RingStencils, SecondDifference};
use crate::mesh::{Mesh, VertexId};
use crate::pm::FlatReplay;
use glam::DVec3;
use std::sync::Arc;

/// Guskov's operator steered by normals; see the module docs.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalAdaptive {
    /// Normal scale `s`: a hinge whose triangles' normals differ by `‖n₁ − n₂‖ = s` counts
    /// `e^{−1/2}`; default 0.25 (a 20° hinge then counts 0.38, a 45° one 0.01).
    pub normal_scale: f64,
    /// [`SecondDifference::degenerate_area_ratio`].
    pub degenerate_area_ratio: f64,
    /// Positions the normals come from, indexed like the parameter geometry.
    pub(crate) guide: Option<Arc<[DVec3]>>,
}

impl Default for NormalAdaptive {
    fn default() -> Self {
        NormalAdaptive {
            normal_scale: 0.25,
            degenerate_area_ratio: SecondDifference::default().degenerate_area_ratio,
            guide: None,
        }
    }
}

impl NormalAdaptive {
    /// This operator with its normals taken from `guide` (one position per vertex, indexed
    /// like the parameter geometry the stencils are asked for) instead of from the parameter
    /// geometry. The pyramid passes the finest level denoised by Ohtake's filter.
    pub fn with_guide(mut self, guide: Vec<DVec3>) -> Self {
        self.guide = Some(guide.into());
        self
    }

    /// The guide positions, if any.
    pub fn guide(&self) -> Option<&[DVec3]> {
        self.guide.as_deref()
    }

    fn guskov(&self) -> SecondDifference {
        SecondDifference {
            degenerate_area_ratio: self.degenerate_area_ratio,
        }
    }

    fn steering(&self) -> Steering<'_> {
        let s = self.normal_scale;
        Steering {
            guide: self.guide(),
            // A scale that is not a positive number steers nothing (Guskov's weights).
            half_inverse_scale2: if s > 0.0 && s.is_finite() {
                0.5 / (s * s)
            } else {
                0.0
            },
        }
    }
}

impl Relaxation for NormalAdaptive {
    fn name(&self) -> &'static str {
        "normal"
    }

    fn as_ring_stencils(&self) -> Option<&dyn RingStencils> {
        Some(self)
    }

    fn stencil(
        &self,
        mesh: &Mesh,
        geometry: &[DVec3],
        vertex: VertexId,
        out: &mut Vec<(VertexId, f64)>,
    ) -> bool {
        self.guskov()
            .vec_stencil(mesh, geometry, vertex, out, Some(&self.steering()))
    }

    fn stencils(
        &self,
        mesh: &Mesh,
        geometry: &[DVec3],
        vertices: &[VertexId],
        out: &mut Vec<(VertexId, f64)>,
        lens: &mut Vec<usize>,
    ) {
        self.guskov()
            .batch_stencils(mesh, geometry, vertices, out, lens, Some(&self.steering()))
    }
}

impl RingStencils for NormalAdaptive {
    fn ring_stencils(
        &self,
        replay: &FlatReplay,
        geometry: &[DVec3],
        vertices: &[u32],
        out: &mut Vec<(u32, f64)>,
        lens: &mut Vec<usize>,
    ) {
        self.guskov().steered_ring_stencils(
            replay,
            geometry,
            vertices,
            out,
            lens,
            Some(&self.steering()),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::SlotIndex;
    use crate::relax::folded_grid as grid;
    use crate::relax::relax_by_stencils;

    /// The relaxed positions `R(p)` of every vertex.
    fn relaxed_positions(op: &dyn Relaxation, m: &Mesh) -> Vec<DVec3> {
        let g = m.positions();
        let verts: Vec<VertexId> = m.vertices().collect();
        let mut out = vec![DVec3::ZERO; verts.len()];
        relax_by_stencils(op, m, &g, &g, &verts, &mut out);
        out
    }

    #[test]
    fn on_a_plane_it_is_guskovs_operator() {
        let m = grid(6, None);
        let g = m.positions();
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for v in m.vertices() {
            let ok = NormalAdaptive::default().stencil(&m, &g, v, &mut a);
            assert_eq!(
                ok,
                Relaxation::stencil(&SecondDifference::default(), &m, &g, v, &mut b)
            );
            assert_eq!(a.len(), b.len());
            for (x, y) in a.iter().zip(&b) {
                assert_eq!(x.0, y.0);
                assert!((x.1 - y.1).abs() <= 1e-12 * y.1.abs().max(1.0));
            }
        }
    }

    #[test]
    fn weights_sum_to_one_and_the_batch_equals_single_stencils() {
        let m = grid(6, Some(3.0));
        let g = m.positions();
        let op = NormalAdaptive::default();
        let verts: Vec<VertexId> = m.vertices().collect();
        let (mut all, mut lens, mut one) = (Vec::new(), Vec::new(), Vec::new());
        op.stencils(&m, &g, &verts, &mut all, &mut lens);
        let mut at = 0;
        for (&v, &len) in verts.iter().zip(&lens) {
            let ok = op.stencil(&m, &g, v, &mut one);
            assert_eq!(ok, len > 0);
            assert_eq!(&all[at..at + len], &one[..]);
            at += len;
            if ok {
                let sum: f64 = one.iter().map(|x| x.1).sum();
                assert!((sum - 1.0).abs() < 1e-12, "{sum}");
            }
        }
    }

    #[test]
    fn crease_vertices_are_predicted_on_the_crease_where_guskov_rounds_it() {
        let m = grid(8, Some(4.0));
        let g = m.positions();
        let steered = relaxed_positions(&NormalAdaptive::default(), &m);
        let guskov = relaxed_positions(&SecondDifference::default(), &m);
        // Interior crease vertices: x = 4 on the flat part, y away from the border.
        let crease: Vec<usize> = m
            .vertices()
            .map(|v| v.slot())
            .filter(|&i| g[i].x == 4.0 && g[i].z == 0.0 && (2.0..=6.0).contains(&g[i].y))
            .collect();
        assert!(!crease.is_empty());
        let off = |r: &[DVec3]| {
            crease
                .iter()
                .map(|&i| r[i].distance(g[i]))
                .fold(0.0, f64::max)
        };
        let (ours, theirs) = (off(&steered), off(&guskov));
        assert!(
            theirs > 0.05,
            "Guskov's operator rounds the crease: {theirs}"
        );
        assert!(ours < 0.05 * theirs, "{ours} vs {theirs}");
    }

    #[test]
    fn the_guide_decides_where_the_creases_are() {
        // Parameter geometry flat, guide folded: the stencils are the folded grid's steering
        // applied to the flat grid's coefficients, so they differ from Guskov's on the plane.
        let flat = grid(6, None);
        let folded = grid(6, Some(3.0));
        let g = flat.positions();
        let op = NormalAdaptive::default().with_guide(folded.positions());
        let (mut a, mut b) = (Vec::new(), Vec::new());
        let differs = flat.vertices().any(|v| {
            op.stencil(&flat, &g, v, &mut a);
            Relaxation::stencil(&SecondDifference::default(), &flat, &g, v, &mut b);
            a.iter().zip(&b).any(|(x, y)| (x.1 - y.1).abs() > 1e-3)
        });
        assert!(differs);
        // A guide equal to the geometry is the same as no guide.
        let same = NormalAdaptive::default().with_guide(g.clone());
        for v in flat.vertices() {
            same.stencil(&flat, &g, v, &mut a);
            NormalAdaptive::default().stencil(&flat, &g, v, &mut b);
            assert_eq!(a, b);
        }
    }
}
