//! Cascadic MCM subdivision (Diewald–Morigi–Rumpf 2001, `docs/algorithms.md` §3).
//!
//! One fully implicit step of mean-curvature motion of width σ = c·h_0 (diffusion
//! coefficient α = σ²/2 over unit time) is approximated by a fixed-point iteration that
//! refines the grid on every step:
//!
//! ```text
//! M_k   := Refinement(M_{k−1})                  new vertices at edge midpoints
//! (M + α L) x_k = M · I x_0                     M, L: lumped mass and cotangent stiffness
//!                                               of M_{k−1} prolonged onto the level-k grid
//! ```
//!
//! The right-hand side is always the **initial** surface x_0, interpolated by the same
//! refinement rules — never x_{k−1}, which would apply k diffusion steps and keep shrinking.
//! Each level's system is smoothed from the prolonged x_{k−1} by `m_l` steps of damped Jacobi
//! or preconditioned CG (cascadic multigrid, `m_l = ⌈m_{l_max} β^{l_max−l}⌉`: many steps on
//! the cheap coarse levels, few on the fine ones), or solved exactly.
//!
//! Local filter width (Diewald–Morigi–Rumpf §7; `docs/algorithms.md` §3.6): with a smoothed
//! grid-size function h (initially the mean length of the edges at each vertex),
//! `α_k = (c · I h_{k−1})²/2` per vertex, averaged per triangle, and h is diffused with the
//! same matrix: `(M + L^α)[x_k, h_k] = M [I x_0, I h_0]`.
//!
//! Results are bit-for-bit reproducible on any number of threads: every sum runs in a fixed
//! order, and what runs in parallel is independent work. With quadrisection, a level's
//! half-edge connectivity (needed only by the next refinement) is built on one core while the
//! level's system is assembled and solved from flat arrays on the other; the last level's is
//! never built, since the output is its triangles.

use super::fem::{
    SymmetricCsr, identity_rows, mass_of, mass_rhs, stiffness_from_weights, system_matrix,
    triangle_weights,
};
use super::halfedge_arrays::HalfedgeArrays;
use super::refine::{
    BisectionLevel, Prolongation, QuadTopology, bisect_level, initial_marking,
    quadrisect_connectivity, quadrisection_parts, quadrisection_stiffness,
};
use super::{Refinement, Solver, SubdivError, SubdivOptions, Subdivision, compact, default_beta};
use crate::mesh::{Mesh, SlotIndex};
use crate::progress::Progress;
use glam::DVec3;

/// What the solver did on one level.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelReport {
    /// Level, 1-based.
    pub level: usize,
    /// Vertices on this level.
    pub vertices: usize,
    /// Faces on this level.
    pub faces: usize,
    /// Smoothing or CG steps taken (0 for a direct solve).
    pub steps: usize,
    /// ‖A x − b‖ / ‖b‖ after the solve (largest over the coordinate columns).
    pub relative_residual: f64,
}

/// The cascadic schedule `m_l = ⌈m_{l_max}·β^{l_max−l}⌉` for `l = 1..=levels`, each capped
/// at `cap`.
pub fn schedule(levels: usize, finest_steps: usize, beta: f64, cap: usize) -> Vec<usize> {
    (1..=levels)
        .map(|l| {
            let m = finest_steps as f64 * beta.powi((levels - l) as i32);
            if m.is_finite() {
                // Forgive rounding: 2·(2√2)² must give 16, not 17.
                ((m * (1.0 - 1e-12)).ceil() as usize).min(cap)
            } else {
                cap
            }
        })
        .collect()
}

/// `steps` damped Jacobi sweeps `x ← x − ω D⁻¹ (A x − b)` on `K` columns.
pub fn jacobi<const K: usize>(
    a: &SymmetricCsr,
    b: &[[f64; K]],
    x: &mut [[f64; K]],
    steps: usize,
    omega: f64,
) {
    let mut ax = vec![[0.0; K]; x.len()];
    for _ in 0..steps {
        a.mul(x, &mut ax);
        for i in 0..x.len() {
            let s = omega / a.diagonal(i);
            for k in 0..K {
                x[i][k] -= s * (ax[i][k] - b[i][k]);
            }
        }
    }
}

/// Jacobi-preconditioned conjugate gradients on `K` independent columns, at most `max_steps`
/// iterations; a column stops when ‖r‖ ≤ `tolerance`·‖b‖ (or on breakdown). Returns the
/// number of iterations run.
pub fn conjugate_gradient<const K: usize>(
    a: &SymmetricCsr,
    b: &[[f64; K]],
    x: &mut [[f64; K]],
    max_steps: usize,
    tolerance: f64,
) -> usize {
    // Four vectors (r, p, q and the inverse diagonal): the preconditioned residual
    // z = D⁻¹ r is recomputed where it is needed instead of stored, and the x/r update
    // also sums rᵀz and rᵀr for the next step, so an iteration reads the vectors three
    // times besides the product. Every sum runs over the rows in order, as a plain dot
    // product would, so the iterates are the textbook ones bit for bit.
    let n = x.len();
    let inv_diag: Vec<f64> = (0..n).map(|i| 1.0 / a.diagonal(i)).collect();
    let mut r = vec![[0.0; K]; n];
    a.mul(x, &mut r);
    let mut p = vec![[0.0; K]; n];
    let mut rz = [0.0; K];
    let mut rr = [0.0; K];
    for i in 0..n {
        for k in 0..K {
            let ri = b[i][k] - r[i][k];
            r[i][k] = ri;
            let zi = ri * inv_diag[i];
            p[i][k] = zi;
            rz[k] += ri * zi;
        }
    }
    for ri in &r {
        for k in 0..K {
            rr[k] += ri[k] * ri[k];
        }
    }
    let mut q = vec![[0.0; K]; n];
    let b_norm = column_dot(b, b).map(f64::sqrt);
    let mut active = [true; K];
    let mut steps = 0;
    while steps < max_steps {
        for k in 0..K {
            if rr[k].sqrt() <= tolerance * b_norm[k] || rr[k] == 0.0 {
                active[k] = false;
            }
        }
        if !active.iter().any(|&a| a) {
            break;
        }
        steps += 1;
        a.mul(&p, &mut q);
        let pq = column_dot(&p, &q);
        let mut step = [0.0; K];
        for k in 0..K {
            if active[k] && pq[k] > 0.0 && pq[k].is_finite() {
                step[k] = rz[k] / pq[k];
            } else {
                active[k] = false;
            }
        }
        let mut rz_new = [0.0; K];
        rr = [0.0; K];
        // Zipped slices rather than indices: no bounds checks in the hot passes.
        for ((xi, ri), ((pi, qi), &d)) in x
            .iter_mut()
            .zip(r.iter_mut())
            .zip(p.iter().zip(&q).zip(&inv_diag))
        {
            for k in 0..K {
                xi[k] += step[k] * pi[k];
                let rk = ri[k] - step[k] * qi[k];
                ri[k] = rk;
                rz_new[k] += rk * (rk * d);
                rr[k] += rk * rk;
            }
        }
        let mut beta = [0.0; K];
        for k in 0..K {
            if active[k] && rz[k] > 0.0 {
                beta[k] = rz_new[k] / rz[k];
            }
        }
        for ((pi, ri), &d) in p.iter_mut().zip(&r).zip(&inv_diag) {
            for k in 0..K {
                if active[k] {
                    pi[k] = ri[k] * d + beta[k] * pi[k];
                }
            }
        }
        rz = rz_new;
    }
    steps
}

fn column_dot<const K: usize>(a: &[[f64; K]], b: &[[f64; K]]) -> [f64; K] {
    let mut s = [0.0; K];
    for (x, y) in a.iter().zip(b) {
        for k in 0..K {
            s[k] += x[k] * y[k];
        }
    }
    s
}

/// ‖A x − b‖ / ‖b‖, largest over the columns (0 for a zero column of b with zero residual).
pub fn relative_residual<const K: usize>(a: &SymmetricCsr, b: &[[f64; K]], x: &[[f64; K]]) -> f64 {
    // Without storing A x − b: at a million rows that vector's first touch cost more than
    // the product.
    let rr = a.residual_squares(x, b);
    let bb = column_dot(b, b);
    (0..K)
        .map(|k| {
            if bb[k] > 0.0 {
                (rr[k] / bb[k]).sqrt()
            } else {
                rr[k].sqrt()
            }
        })
        .fold(0.0, f64::max)
}

/// Solves `A x = b` to `tolerance` (relative residual): sparse Cholesky via faer with the
/// `solver` feature (polished by CG if its residual misses the tolerance), otherwise
/// preconditioned CG from the given `x`. Returns the CG steps taken.
pub fn solve_exact<const K: usize>(
    a: &SymmetricCsr,
    b: &[[f64; K]],
    x: &mut [[f64; K]],
    tolerance: f64,
) -> Result<usize, String> {
    #[cfg(feature = "solver")]
    cholesky_solve(a, b, x)?;
    // CG needs at most n steps in exact arithmetic; allow a generous multiple for rounding.
    let cap = 10 * a.n() + 100;
    let steps = if relative_residual(a, b, x) > tolerance {
        conjugate_gradient(a, b, x, cap, tolerance)
    } else {
        0
    };
    let res = relative_residual(a, b, x);
    if res.is_nan() || res > tolerance * 10.0 {
        return Err(format!(
            "residual {res:.3e} above tolerance {tolerance:.1e} after {steps} CG steps"
        ));
    }
    Ok(steps)
}

/// Sparse Cholesky (AMD ordering, simplicial or supernodal as faer decides). faer is built
/// without its `rayon` feature, so this runs sequentially (`Par::Seq`): its parallel mode
/// collapses on oversubscribed machines (crates.md).
#[cfg(feature = "solver")]
fn cholesky_solve<const K: usize>(
    a: &SymmetricCsr,
    b: &[[f64; K]],
    x: &mut [[f64; K]],
) -> Result<(), String> {
    use faer::linalg::solvers::Solve;
    use faer::sparse::{SparseColMat, Triplet};
    let n = a.n();
    let mut lower = Vec::with_capacity(a.val.len() / 2 + n);
    for i in 0..n {
        for k in a.row_start[i] as usize..a.row_start[i + 1] as usize {
            let j = a.col[k] as usize;
            if j <= i {
                lower.push(Triplet::new(i, j, a.val[k]));
            }
        }
    }
    let m = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &lower)
        .map_err(|e| format!("assembling the sparse matrix: {e:?}"))?;
    let llt = m
        .sp_cholesky(faer::Side::Lower)
        .map_err(|e| format!("sparse Cholesky: {e:?}"))?;
    let mut rhs = faer::Mat::<f64>::from_fn(n, K, |i, k| b[i][k]);
    llt.solve_in_place(rhs.as_mut());
    for (i, xi) in x.iter_mut().enumerate() {
        for (k, v) in xi.iter_mut().enumerate() {
            *v = rhs[(i, k)];
        }
    }
    Ok(())
}

/// Mean length of the edges at each vertex (0 for an isolated vertex), indexed by slot.
pub fn vertex_grid_size(mesh: &Mesh) -> Vec<f64> {
    let mut h = vec![0.0; mesh.vertices().map(|v| v.slot() + 1).max().unwrap_or(0)];
    for v in mesh.vertices() {
        let (s, n) = mesh
            .outgoing(v)
            .fold((0.0, 0usize), |(s, n), e| (s + mesh.edge_length(e), n + 1));
        h[v.slot()] = if n == 0 { 0.0 } else { s / n as f64 };
    }
    h
}

/// Cascadic MCM subdivision; see the module docs. Prefer [`super::subdivide`], which also
/// checks the output size.
pub fn subdivide_mcm(
    mesh: &Mesh,
    options: &SubdivOptions,
    progress: &dyn Progress,
) -> Result<Subdivision, SubdivError> {
    options.validate()?;
    if mesh.n_faces() == 0 {
        return Err(SubdivError::NoFaces);
    }
    super::check_output_size(mesh, options.levels, options.face_factor(), usize::MAX)?;
    let input = compact(mesh)?;
    let c = options.width;
    let h0 = input.mean_edge_length();
    let alpha = 0.5 * (c * h0) * (c * h0);
    let mut h_init = vertex_grid_size(&input);
    let mut h_cur = h_init.clone();
    // The current level: its positions and triangles, and the connectivity the next refinement
    // reads (flat half-edge arrays for quadrisection; faces, neighbours and newest vertices for
    // bisection, which keep the triangles themselves).
    let (mut positions, mut triangles) = input.to_triangles();
    let mut x0: Vec<DVec3> = positions.clone();
    let mut connectivity = Some(match options.refinement {
        Refinement::Quadrisection => Connectivity::Quad(HalfedgeArrays::from_mesh(&input)),
        Refinement::Bisection => Connectivity::Bisect(BisectionLevel::from_mesh(
            &input,
            &initial_marking(&input)?,
        )?),
    });
    let beta = options
        .beta
        .unwrap_or_else(|| default_beta(options.solver, options.refinement));
    let steps = schedule(
        options.levels,
        options.finest_steps,
        beta,
        options.max_steps_per_level,
    );
    let growth: f64 = match options.refinement {
        Refinement::Quadrisection => 4.0,
        Refinement::Bisection => 2.0,
    };
    let total: f64 = (1..=options.levels).map(|l| growth.powi(l as i32)).sum();
    let mut done = 0.0;
    let mut reports = Vec::with_capacity(options.levels);
    // One hand-over into rayon's pool for the whole schedule: the joins and parallel loops of
    // every level then start from a worker, which is far cheaper than each one waking the
    // pool from outside (measurable on small levels).
    rayon::scope(|_| -> Result<(), SubdivError> {
        for level in 1..=options.levels {
            let with_level = |e: SubdivError| match e {
                SubdivError::NotManifold { .. } => SubdivError::NotManifold { level },
                e => e,
            };
            let m_l = steps[level - 1];
            // The level's solve needs only flat arrays: triangles, prolongation and positions.
            let mut solve_level = |triangles: &[[u32; 3]],
                                   mut positions: Vec<DVec3>,
                                   prolongation: &Prolongation,
                                   quad: Option<(&HalfedgeArrays, &QuadTopology)>|
             -> Result<(usize, f64, Vec<DVec3>), String> {
                x0 = prolongation.apply(&x0);
                // Mass and stiffness from one pass over the triangles; a quadrisection reads its
                // sparsity off the coarse mesh (the same bits as the general assembly).
                let mass_and_stiffness = |positions: &[DVec3], coef: Option<&[f64]>| {
                    let tri_weights = triangle_weights(triangles, positions, coef);
                    let mass = mass_of(triangles, &tri_weights, positions.len());
                    let stiffness = quad
                        .and_then(|(coarse, topo)| {
                            quadrisection_stiffness(coarse, topo, &tri_weights)
                        })
                        .unwrap_or_else(|| {
                            stiffness_from_weights(triangles, positions.len(), &tri_weights)
                        });
                    (mass, stiffness)
                };
                if options.local_width {
                    h_init = prolongation.apply(&h_init);
                    h_cur = prolongation.apply(&h_cur);
                    let alpha_v: Vec<f64> = h_cur.iter().map(|h| 0.5 * (c * h) * (c * h)).collect();
                    let coef: Vec<f64> = triangles
                        .iter()
                        .map(|t| t.iter().map(|&v| alpha_v[v as usize]).sum::<f64>() / 3.0)
                        .collect();
                    let (mass, stiffness) = mass_and_stiffness(&positions, Some(&coef));
                    let pinned = identity_rows(&mass);
                    let a = system_matrix(&mass, stiffness, 1.0);
                    let b: Vec<[f64; 4]> = (0..positions.len())
                        .map(|i| {
                            let w = if pinned[i] { 1.0 } else { mass[i] };
                            let p = x0[i] * w;
                            [p.x, p.y, p.z, h_init[i] * w]
                        })
                        .collect();
                    let mut x: Vec<[f64; 4]> = positions
                        .iter()
                        .zip(&h_cur)
                        .map(|(p, &h)| [p.x, p.y, p.z, h])
                        .collect();
                    let taken = run_solver(options, &a, &b, &mut x, m_l)?;
                    let residual = relative_residual(&a, &b, &x);
                    h_cur = x.iter().map(|v| v[3]).collect();
                    Ok((
                        taken,
                        residual,
                        x.iter().map(|v| DVec3::new(v[0], v[1], v[2])).collect(),
                    ))
                } else {
                    let (mass, stiffness) = mass_and_stiffness(&positions, None);
                    let a = system_matrix(&mass, stiffness, alpha);
                    let b = mass_rhs(&mass, &x0);
                    // Solved in place: the prolonged positions are the start, and the
                    // solution is the level's positions (a DVec3 is three f64).
                    let x: &mut [[f64; 3]] = bytemuck::cast_slice_mut(&mut positions);
                    let taken = run_solver(options, &a, &b, x, m_l)?;
                    let residual = relative_residual(&a, &b, x);
                    Ok((taken, residual, positions))
                }
            };
            let last = level == options.levels;
            // Only the last quadrisection level leaves no connectivity behind.
            let Some(current) = connectivity.take() else {
                break;
            };
            let (next, fine_triangles, faces, solution) = match current {
                Connectivity::Quad(coarse) => {
                    let (topo, prolongation, fine_positions) =
                        quadrisection_parts(&coarse, &positions);
                    // The next refinement's connectivity is built on another core while this
                    // level solves; the last level needs none.
                    let (fine, solution) = rayon::join(
                        || (!last).then(|| quadrisect_connectivity(&coarse, &topo)),
                        || {
                            solve_level(
                                &topo.triangles,
                                fine_positions,
                                &prolongation,
                                Some((&coarse, &topo)),
                            )
                        },
                    );
                    let faces = topo.triangles.len();
                    (
                        fine.map(Connectivity::Quad),
                        Some(topo.triangles),
                        faces,
                        solution,
                    )
                }
                Connectivity::Bisect(coarse) => {
                    let (fine, prolongation) =
                        bisect_level(&coarse, positions.len()).map_err(with_level)?;
                    drop(coarse);
                    let fine_positions = prolongation.apply(&positions);
                    let solution =
                        solve_level(&fine.triangles, fine_positions, &prolongation, None);
                    // The triangles stay with the level, which the next bisection reads.
                    let faces = fine.triangles.len();
                    (Some(Connectivity::Bisect(fine)), None, faces, solution)
                }
            };
            let fail = |why: String| SubdivError::SolverFailed { level, why };
            let (taken, residual, solved) = solution.map_err(fail)?;
            if solved.iter().any(|p| !p.is_finite()) {
                return Err(fail("non-finite positions".to_string()));
            }
            connectivity = next;
            positions = solved;
            if let Some(fine) = fine_triangles {
                triangles = fine;
            }
            reports.push(LevelReport {
                level,
                vertices: positions.len(),
                faces,
                steps: taken,
                relative_residual: residual,
            });
            done += growth.powi(level as i32);
            progress.update(done / total);
        }
        Ok(())
    })?;
    if let Some(Connectivity::Bisect(level)) = connectivity {
        triangles = level.triangles;
    }
    Ok(Subdivision {
        positions,
        triangles,
        levels: reports,
    })
}

/// What the next refinement reads.
enum Connectivity {
    /// Quadrisection: the flat half-edge arrays.
    Quad(HalfedgeArrays),
    /// Bisection: the faces, their neighbours across each edge and their newest vertices.
    Bisect(BisectionLevel),
}

fn run_solver<const K: usize>(
    options: &SubdivOptions,
    a: &SymmetricCsr,
    b: &[[f64; K]],
    x: &mut [[f64; K]],
    m_l: usize,
) -> Result<usize, String> {
    match options.solver {
        Solver::Jacobi => {
            jacobi(a, b, x, m_l, options.jacobi_damping);
            Ok(m_l)
        }
        Solver::Cg => Ok(conjugate_gradient(a, b, x, m_l, options.cg_tolerance)),
        Solver::Exact => solve_exact(a, b, x, options.exact_tolerance),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::subdiv::fem::{cotangent_stiffness, lumped_mass, system_matrix};

    #[test]
    fn schedule_follows_the_geometric_law() {
        let s = schedule(4, 2, 2.0 * std::f64::consts::SQRT_2, 10_000);
        // ⌈2·(2√2)^3⌉ = ⌈45.25⌉, ⌈2·8⌉, ⌈2·2.83⌉, 2.
        assert_eq!(s, vec![46, 16, 6, 2]);
        assert_eq!(schedule(3, 1, 4.0, 10), vec![10, 4, 1]);
    }

    fn system() -> (SymmetricCsr, Vec<[f64; 3]>) {
        // An irregular closed surface: a quadrisected, jittered octahedron.
        let p = [
            [1.0, 0.1, 0.0],
            [-1.0, 0.0, 0.2],
            [0.1, 1.2, 0.0],
            [0.0, -1.0, 0.1],
            [0.2, 0.0, 1.5],
            [0.0, 0.1, -1.0],
        ]
        .map(DVec3::from_array);
        let f = [
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ];
        let m = Mesh::from_triangles(&p, &f).unwrap().mesh;
        let r = super::super::refine::quadrisect(&m).unwrap();
        let pos = r.mesh.positions();
        let mass = lumped_mass(&r.triangles, &pos);
        let a = system_matrix(&mass, cotangent_stiffness(&r.triangles, &pos, None), 0.3);
        let b = pos
            .iter()
            .zip(&mass)
            .map(|(q, w)| (*q * *w).to_array())
            .collect();
        (a, b)
    }

    #[test]
    fn cg_jacobi_and_exact_agree_and_converge() {
        let (a, b) = system();
        let n = a.n();
        let mut exact = vec![[0.0; 3]; n];
        solve_exact(&a, &b, &mut exact, 1e-12).unwrap();
        assert!(relative_residual(&a, &b, &exact) < 1e-11);
        let mut cg = vec![[0.0; 3]; n];
        let steps = conjugate_gradient(&a, &b, &mut cg, 1000, 1e-13);
        assert!(steps <= n + 5);
        let mut jac = vec![[0.0; 3]; n];
        jacobi(&a, &b, &mut jac, 400, 2.0 / 3.0);
        for i in 0..n {
            for k in 0..3 {
                assert!((cg[i][k] - exact[i][k]).abs() < 1e-9);
                assert!((jac[i][k] - exact[i][k]).abs() < 1e-6);
            }
        }
        // Fewer CG steps: the residual decreases monotonically in the energy sense; at least
        // it must be smaller after 5 steps than after 1.
        let mut one = vec![[0.0; 3]; n];
        conjugate_gradient(&a, &b, &mut one, 1, 0.0f64.max(1e-300));
        let mut five = vec![[0.0; 3]; n];
        conjugate_gradient(&a, &b, &mut five, 5, 1e-300);
        assert!(relative_residual(&a, &b, &five) < relative_residual(&a, &b, &one));
    }

    #[test]
    fn cg_stops_on_an_exact_start_without_dividing_by_zero() {
        let (a, b) = system();
        let mut x = vec![[0.0; 3]; a.n()];
        solve_exact(&a, &b, &mut x, 1e-13).unwrap();
        let before = x.clone();
        let steps = conjugate_gradient(&a, &b, &mut x, 50, 1e-6);
        assert_eq!(steps, 0);
        assert_eq!(x, before);
    }
}
