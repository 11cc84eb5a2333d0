//! Implicit mean-curvature flow (Desbrun, Meyer, Schröder, Barr 1999): per iteration
//!
//! ```text
//! (M + dt · K) x′ = M x
//! ```
//!
//! with the lumped mass M and the cotangent stiffness K = −L of the *current* surface (both
//! rebuilt every iteration, [`crate::numerics::fem`]), i.e. one backward-Euler step of
//! ∂x/∂t = Δ_S x = −2H n. The step is unconditionally stable, so large time steps smooth in
//! few iterations.
//!
//! The time step is given relative to the squared mean edge length of the *input*:
//! `dt = time_step · L²` (fixed over the iterations, so N iterations cover time N·dt). With
//! `time_step = 1` a feature of the size of one edge is damped by roughly half per
//! iteration, while a sphere of radius R shrinks by about 2 dt/R = 2 L²/R per iteration.
//!
//! Negative edge weights (non-Delaunay edges, whose opposite angles sum to more than π) are
//! clamped to zero ([`crate::numerics::fem::clamp_negative_weights`]). Noisy scans are full of
//! needle triangles whose clamped cotangents make the plain stiffness slightly indefinite, and
//! with a large time step `M + dt K` then loses positive definiteness (the Cholesky factorisation
//! of the noisy bunny broke down at dt = L²). With the clamp the matrix is diagonally dominant,
//! hence positive definite for every dt; on a Delaunay mesh nothing changes.
//!
//! The system is solved by sparse Cholesky (faer, cargo feature `solver`), otherwise by
//! Jacobi-preconditioned CG to a 1e-7 relative residual ([`SOLVE_TOLERANCE`]) ([`crate::numerics::solvers::solve_exact`]).
//!
//! Boundaries ([`Boundary`]): `Fixed` pins the rim (Dirichlet rows, their columns moved to the
//! right-hand side so the system stays symmetric); `Smooth` uses the natural boundary
//! conditions of the finite-element Laplacian. Vertices whose triangles are all degenerate
//! (zero mass, including isolated vertices) stay where they are. Every sum runs in a fixed
//! order (the matrix work splits only by rows), so results are the same bits with any number
//! of threads.

use super::{Boundary, SmoothError};
use crate::mesh::Mesh;
use crate::numerics::fem::{clamp_negative_weights, mass_and_stiffness, mass_rhs, system_matrix};
use crate::numerics::solvers::solve_exact;
use crate::progress::Progress;
use glam::DVec3;

/// Relative residual the CG fallback (and the Cholesky check) must reach. Not tighter: after
/// many large steps the flow pinches thin parts into needle triangles whose cotangents (up to
/// 1e5) make the system so ill-conditioned that the Cholesky residual stalls around 1e-7
/// (fandisk after 19 steps of 4 L²), and CG cannot polish it further.
pub(crate) const SOLVE_TOLERANCE: f64 = 1e-7;

/// Parameters of [`implicit_mcf`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct McfOptions {
    /// Backward-Euler steps.
    pub iterations: usize,
    /// Time step in units of the input's squared mean edge length (`dt = time_step · L²`).
    pub time_step: f64,
    /// What boundary vertices do.
    pub boundary: Boundary,
}

impl Default for McfOptions {
    fn default() -> Self {
        McfOptions {
            iterations: 1,
            time_step: 1.0,
            boundary: Boundary::default(),
        }
    }
}

impl McfOptions {
    /// Checks the parameter ranges.
    pub fn validate(&self) -> Result<(), SmoothError> {
        if !(self.time_step > 0.0 && self.time_step.is_finite()) {
            return Err(SmoothError::InvalidParameter(format!(
                "time step must be a positive number, got {}",
                self.time_step
            )));
        }
        Ok(())
    }
}

/// Implicit mean-curvature flow; see the module docs. Returns the new positions in vertex slot
/// order (like [`Mesh::positions`]).
pub fn implicit_mcf(
    mesh: &Mesh,
    options: &McfOptions,
    progress: &dyn Progress,
) -> Result<Vec<DVec3>, SmoothError> {
    options.validate()?;
    // Dense arrays in slot order: `to_triangles` indexes the vertices in that order.
    let (mut x, triangles) = mesh.to_triangles();
    let l = mesh.mean_edge_length();
    let dt = options.time_step * l * l;
    let pinned: Vec<bool> = mesh
        .vertices()
        .map(|v| options.boundary == Boundary::Fixed && mesh.is_boundary_vertex(v))
        .collect();
    for it in 0..options.iterations {
        let (mass, mut stiffness) = mass_and_stiffness(&triangles, &x, None);
        clamp_negative_weights(&mut stiffness);
        let mut a = system_matrix(&mass, stiffness, dt);
        let mut b = mass_rhs(&mass, &x);
        pin_rows(&mut a, &mut b, &x, &pinned);
        let mut sol: Vec<[f64; 3]> = x.iter().map(|p| p.to_array()).collect();
        solve_exact(&a, &b, &mut sol, SOLVE_TOLERANCE).map_err(|reason| SmoothError::Solver {
            iteration: it + 1,
            reason,
        })?;
        for (p, s) in x.iter_mut().zip(&sol) {
            *p = DVec3::from_array(*s);
        }
        progress.update((it + 1) as f64 / options.iterations.max(1) as f64);
    }
    Ok(x)
}

/// Turns the rows of pinned vertices into identity rows with their positions on the right,
/// and moves their columns to the right-hand side of the other rows (keeps A symmetric).
fn pin_rows(
    a: &mut crate::numerics::fem::SymmetricCsr,
    b: &mut [[f64; 3]],
    x: &[DVec3],
    pinned: &[bool],
) {
    if !pinned.iter().any(|&p| p) {
        return;
    }
    for i in 0..a.n() {
        let (s, e) = (a.row_start[i] as usize, a.row_start[i + 1] as usize);
        if pinned[i] {
            a.val[s] = 1.0;
            a.val[s + 1..e].iter_mut().for_each(|v| *v = 0.0);
            b[i] = x[i].to_array();
            continue;
        }
        for k in s + 1..e {
            let j = a.col[k] as usize;
            if pinned[j] {
                let xj = x[j].to_array();
                for (bc, xc) in b[i].iter_mut().zip(xj) {
                    *bc -= a.val[k] * xc;
                }
                a.val[k] = 0.0;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::testutil::{grid, icosphere, noisy, radial_stats};
    use super::*;
    use crate::progress::NoProgress;

    fn run(mesh: &Mesh, o: McfOptions) -> Vec<DVec3> {
        implicit_mcf(mesh, &o, &NoProgress).unwrap()
    }

    #[test]
    fn a_plane_stays_planar_and_a_noisy_plane_gets_flatter() {
        let plane = grid(10, 0.0);
        for boundary in [Boundary::Fixed, Boundary::Smooth] {
            let o = McfOptions {
                iterations: 2,
                boundary,
                ..Default::default()
            };
            let x = run(&plane, o);
            assert!(x.iter().all(|p| p.z.abs() < 1e-14), "{boundary:?}");
            let bumpy = noisy(&plane, 0.02, 3);
            let before: f64 = bumpy.positions().iter().map(|p| p.z * p.z).sum();
            let after: f64 = run(&bumpy, o).iter().map(|p| p.z * p.z).sum();
            assert!(after < 0.5 * before, "{boundary:?}: {before} -> {after}");
        }
    }

    #[test]
    fn fixed_boundaries_stay_and_natural_ones_move() {
        let plane = noisy(&grid(8, 0.0), 0.02, 4);
        let x0 = plane.positions();
        let fixed = run(&plane, McfOptions::default());
        let free = run(
            &plane,
            McfOptions {
                boundary: Boundary::Smooth,
                ..Default::default()
            },
        );
        let mut moved = 0;
        for (i, v) in plane.vertices().enumerate() {
            if plane.is_boundary_vertex(v) {
                assert_eq!(fixed[i], x0[i]);
                moved += usize::from(free[i] != x0[i]);
            } else {
                assert_ne!(fixed[i], x0[i]);
            }
        }
        assert!(moved > 0);
    }

    #[test]
    fn noise_on_a_sphere_is_reduced_and_the_sphere_shrinks_as_predicted() {
        let clean = icosphere(3);
        let sphere = noisy(&clean, 0.01, 9);
        let (_, before) = radial_stats(&sphere.positions());
        let o = McfOptions {
            iterations: 3,
            ..Default::default()
        };
        let x = run(&sphere, o);
        let (_, after) = radial_stats(&x);
        assert!(after < 0.3 * before, "{before} -> {after}");
        assert_eq!(x, run(&sphere, o));
        // Clean sphere: dR/dt = −2/R, so three steps of dt = L² shrink R = 1 by about 6 L².
        let l = clean.mean_edge_length();
        let (r, _) = radial_stats(&run(&clean, o));
        let expect = 1.0 - 6.0 * l * l;
        assert!((r - expect).abs() < 0.1 * (1.0 - expect), "{r} vs {expect}");
    }

    #[test]
    fn bad_time_steps_are_rejected() {
        let m = grid(2, 0.0);
        for time_step in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let o = McfOptions {
                time_step,
                ..Default::default()
            };
            assert!(implicit_mcf(&m, &o, &NoProgress).is_err());
        }
    }
}
