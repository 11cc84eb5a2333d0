//! Taubin's λ|μ smoothing (Taubin 1995) with a choice of edge weights.
//!
//! One iteration is a pair of explicit umbrella steps with the same normalised weights:
//!
//! ```text
//! Δx_i = Σ_j w_ij (x_j − x_i) / Σ_j w_ij
//! x ← x + λ Δx        (λ > 0: shrinks, removes high frequencies)
//! x ← x + μ Δx        (μ < −λ: inflates back, so low frequencies survive)
//! ```
//!
//! The weights are recomputed from the current positions at the start of every iteration and
//! shared by its two half-steps, so each iteration is the linear low-pass filter
//! `(I + μK)(I + λK)` of Taubin's analysis for the geometry it starts from. `mu = 0` gives
//! plain Laplacian smoothing.
//!
//! Weights ([`Weights`]): equal, inverse edge length `1/|x_j − x_i|`, or cotangent
//! `½(cot α + cot β)`. Cotangent weights turn negative across edges opposite obtuse angles,
//! and a negative weight makes the explicit step unstable; they are clamped at zero (and each
//! cotangent at ±1e5, see [`crate::mesh::cotangent`]). Normalising by the sum then makes
//! `x + Δx` a convex combination of the neighbours, so every half-step with |λ|, |μ| ≤ 1 is
//! bounded. A vertex whose clamped weights are all zero falls back to equal weights.
//!
//! Boundary vertices follow [`Boundary`]: fixed, or smoothed along the boundary curve with
//! only their two boundary neighbours (equal weights for [`Weights::Uniform`], inverse edge
//! length otherwise, since cotangents do not exist along a curve). Isolated vertices never
//! move. Per-vertex work runs in parallel, each vertex writing only its own slot, so the
//! result is bit-for-bit the same with any number of threads.

use super::{Boundary, SmoothError};
use crate::mesh::{Mesh, VertexId, cotangent};
use crate::progress::Progress;
use glam::DVec3;
use rayon::prelude::*;
use slotmap::SecondaryMap;

/// Edge weights of the umbrella operator.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Weights {
    /// Equal weights (the original λ|μ filter; also moves vertices tangentially, which evens
    /// out the sampling).
    Uniform,
    /// `1/|x_j − x_i|` (Fujiwara weights): less tangential drift on uneven sampling.
    InverseEdgeLength,
    /// Clamped cotangent weights, a discrete Laplace–Beltrami operator (mostly normal motion).
    #[default]
    Cotangent,
}

/// Parameters of [`taubin_smoothing`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TaubinOptions {
    /// λ|μ iterations (each is two half-steps).
    pub iterations: usize,
    /// Shrinking factor λ, in (0, 1].
    pub lambda: f64,
    /// Inflating factor μ, in [−1, 0]; Taubin's condition for a pass band is μ < −λ.
    pub mu: f64,
    /// Edge weights.
    pub weights: Weights,
    /// What boundary vertices do.
    pub boundary: Boundary,
}

impl Default for TaubinOptions {
    fn default() -> Self {
        TaubinOptions {
            iterations: 10,
            lambda: 0.5,
            mu: -0.53,
            weights: Weights::default(),
            boundary: Boundary::default(),
        }
    }
}

impl TaubinOptions {
    /// Checks the parameter ranges.
    pub fn validate(&self) -> Result<(), SmoothError> {
        if !(self.lambda > 0.0 && self.lambda <= 1.0) {
            return Err(SmoothError::InvalidParameter(format!(
                "lambda must be in (0, 1], got {}",
                self.lambda
            )));
        }
        if !(self.mu >= -1.0 && self.mu <= 0.0) {
            return Err(SmoothError::InvalidParameter(format!(
                "mu must be in [-1, 0], got {}",
                self.mu
            )));
        }
        Ok(())
    }
}

const NONE: u32 = u32::MAX;

/// The umbrella stencil of every vertex in dense (slot-order) indices, CSR.
struct Stencil {
    start: Vec<u32>,
    neighbor: Vec<u32>,
    /// The vertices opposite the edge in its two faces (`NONE` where there is no face).
    opposite: Vec<[u32; 2]>,
    /// Row of each entry.
    row: Vec<u32>,
    /// Does the vertex move at all.
    moves: Vec<bool>,
    /// Is the vertex smoothed along a boundary curve (no cotangents there).
    curve: Vec<bool>,
}

impl Stencil {
    fn new(mesh: &Mesh, boundary: Boundary) -> Stencil {
        let mut index: SecondaryMap<VertexId, u32> = SecondaryMap::with_capacity(mesh.n_vertices());
        for (i, v) in mesh.vertices().enumerate() {
            index.insert(v, i as u32);
        }
        let n = mesh.n_vertices();
        let mut s = Stencil {
            start: Vec::with_capacity(n + 1),
            neighbor: Vec::with_capacity(mesh.n_halfedges()),
            opposite: Vec::with_capacity(mesh.n_halfedges()),
            row: Vec::with_capacity(mesh.n_halfedges()),
            moves: Vec::with_capacity(n),
            curve: Vec::with_capacity(n),
        };
        s.start.push(0);
        for (i, v) in mesh.vertices().enumerate() {
            let on_boundary = mesh.is_boundary_vertex(v);
            let moves = !mesh.is_isolated(v) && (!on_boundary || boundary == Boundary::Smooth);
            let curve = moves && on_boundary;
            if moves {
                for h in mesh.outgoing(v) {
                    if curve && !mesh.is_boundary_edge(h) {
                        continue;
                    }
                    let opp = |h| match mesh.face(h) {
                        Some(_) => index[mesh.to_vertex(mesh.next(h))],
                        None => NONE,
                    };
                    s.neighbor.push(index[mesh.to_vertex(h)]);
                    s.opposite.push([opp(h), opp(mesh.twin(h))]);
                    s.row.push(i as u32);
                }
            }
            s.moves.push(moves);
            s.curve.push(curve);
            s.start.push(s.neighbor.len() as u32);
        }
        s
    }

    /// Raw (unnormalised) weight of every entry for positions `x`.
    fn weights(&self, x: &[DVec3], weights: Weights, min_length: f64) -> Vec<f64> {
        (0..self.neighbor.len())
            .into_par_iter()
            .map(|k| {
                let i = self.row[k] as usize;
                let j = self.neighbor[k] as usize;
                let inverse = || 1.0 / x[i].distance(x[j]).max(min_length);
                match weights {
                    Weights::Uniform => 1.0,
                    Weights::InverseEdgeLength => inverse(),
                    Weights::Cotangent if self.curve[i] => inverse(),
                    Weights::Cotangent => {
                        let w: f64 = self.opposite[k]
                            .iter()
                            .filter(|&&o| o != NONE)
                            .map(|&o| {
                                let xo = x[o as usize];
                                0.5 * cotangent(x[i] - xo, x[j] - xo)
                            })
                            .sum();
                        w.max(0.0)
                    }
                }
            })
            .collect()
    }

    /// The normalised umbrella vector of every vertex (zero for vertices that do not move).
    fn umbrella(&self, x: &[DVec3], w: &[f64], out: &mut [DVec3]) {
        out.par_iter_mut().enumerate().for_each(|(i, d)| {
            *d = DVec3::ZERO;
            if !self.moves[i] {
                return;
            }
            let (s, e) = (self.start[i] as usize, self.start[i + 1] as usize);
            if s == e {
                return;
            }
            let mut sum_w = 0.0;
            let mut acc = DVec3::ZERO;
            for k in s..e {
                sum_w += w[k];
                acc += w[k] * (x[self.neighbor[k] as usize] - x[i]);
            }
            *d = if sum_w > 0.0 && acc.is_finite() {
                acc / sum_w
            } else {
                let mean: DVec3 = (s..e).map(|k| x[self.neighbor[k] as usize]).sum();
                mean / (e - s) as f64 - x[i]
            };
        });
    }
}

/// Taubin λ|μ smoothing; see the module docs. Returns the new positions in vertex slot order
/// (like [`Mesh::positions`]).
pub fn taubin_smoothing(
    mesh: &Mesh,
    options: &TaubinOptions,
    progress: &dyn Progress,
) -> Result<Vec<DVec3>, SmoothError> {
    options.validate()?;
    let stencil = Stencil::new(mesh, options.boundary);
    let mut x = mesh.positions();
    // Coincident vertices would give infinite inverse-length weights; 1e-9 of the mean edge
    // keeps them finite and still dominant.
    let mean_edge = mesh.mean_edge_length();
    let min_length = if mean_edge > 0.0 {
        1e-9 * mean_edge
    } else {
        f64::MIN_POSITIVE
    };
    let mut d = vec![DVec3::ZERO; x.len()];
    for it in 0..options.iterations {
        let w = stencil.weights(&x, options.weights, min_length);
        for factor in [options.lambda, options.mu] {
            if factor == 0.0 {
                continue;
            }
            stencil.umbrella(&x, &w, &mut d);
            x.par_iter_mut()
                .zip(&d)
                .for_each(|(xi, di)| *xi += factor * *di);
        }
        progress.update((it + 1) as f64 / options.iterations as f64);
    }
    Ok(x)
}

#[cfg(test)]
mod tests {
    use super::super::testutil::{grid, icosphere, noisy, radial_stats};
    use super::*;
    use crate::progress::NoProgress;

    fn run(mesh: &Mesh, o: TaubinOptions) -> Vec<DVec3> {
        taubin_smoothing(mesh, &o, &NoProgress).unwrap()
    }

    #[test]
    fn a_plane_stays_planar_and_a_noisy_plane_gets_flatter() {
        let plane = grid(12, 0.0);
        for weights in [
            Weights::Uniform,
            Weights::InverseEdgeLength,
            Weights::Cotangent,
        ] {
            for boundary in [Boundary::Fixed, Boundary::Smooth] {
                let o = TaubinOptions {
                    weights,
                    boundary,
                    ..Default::default()
                };
                let x = run(&plane, o);
                assert!(x.iter().all(|p| p.z == 0.0), "{weights:?}");
                let bumpy = noisy(&plane, 0.02, 3);
                let before: f64 = bumpy.positions().iter().map(|p| p.z * p.z).sum();
                let after: f64 = run(&bumpy, o).iter().map(|p| p.z * p.z).sum();
                assert!(after < 0.5 * before, "{weights:?}: {before} -> {after}");
            }
        }
    }

    #[test]
    fn fixed_boundaries_stay_and_smooth_ones_move() {
        let plane = noisy(&grid(10, 0.0), 0.02, 5);
        let x0 = plane.positions();
        let fixed = run(&plane, TaubinOptions::default());
        let smooth = run(
            &plane,
            TaubinOptions {
                boundary: Boundary::Smooth,
                ..Default::default()
            },
        );
        let mut moved = 0;
        for (i, v) in plane.vertices().enumerate() {
            if plane.is_boundary_vertex(v) {
                assert_eq!(fixed[i], x0[i]);
                moved += usize::from(smooth[i] != x0[i]);
            }
        }
        assert!(moved > 0);
    }

    #[test]
    fn taubin_keeps_a_sphere_while_laplacian_shrinks_it() {
        let sphere = icosphere(3);
        for weights in [
            Weights::Uniform,
            Weights::InverseEdgeLength,
            Weights::Cotangent,
        ] {
            let o = TaubinOptions {
                iterations: 20,
                weights,
                ..Default::default()
            };
            let (taubin, _) = radial_stats(&run(&sphere, o));
            let (laplace, _) = radial_stats(&run(&sphere, TaubinOptions { mu: 0.0, ..o }));
            assert!(taubin > 0.99, "{weights:?}: {taubin}");
            assert!(laplace < 0.97, "{weights:?}: {laplace}");
        }
    }

    #[test]
    fn noise_on_a_sphere_is_reduced_deterministically() {
        let sphere = noisy(&icosphere(3), 0.01, 9);
        let (_, before) = radial_stats(&sphere.positions());
        let a = run(&sphere, TaubinOptions::default());
        let (_, after) = radial_stats(&a);
        assert!(after < 0.5 * before, "{before} -> {after}");
        assert_eq!(a, run(&sphere, TaubinOptions::default()));
    }

    #[test]
    fn bad_parameters_are_rejected() {
        let m = grid(2, 0.0);
        for (lambda, mu) in [(0.0, -0.5), (1.5, -0.5), (f64::NAN, -0.5), (0.5, 0.1)] {
            let o = TaubinOptions {
                lambda,
                mu,
                ..Default::default()
            };
            assert!(taubin_smoothing(&m, &o, &NoProgress).is_err());
        }
    }
}
