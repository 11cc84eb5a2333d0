//! Solvers for the symmetric positive definite systems `A x = b` of the finite-element code
//! ([`SymmetricCsr`]), on `K` right-hand-side columns at once: damped Jacobi, Jacobi-
//! preconditioned conjugate gradients, and an exact solve (sparse Cholesky with the `solver`
//! feature, otherwise CG to a tolerance). Every sum runs over the rows in order, so results do
//! not depend on the thread count.

use super::fem::SymmetricCsr;

/// `steps` damped Jacobi sweeps `x ← x − ω D⁻¹ (A x − b)` on `K` columns.
pub(crate) fn jacobi<const K: usize>(
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
pub(crate) fn conjugate_gradient<const K: usize>(
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
pub(crate) fn relative_residual<const K: usize>(
    a: &SymmetricCsr,
    b: &[[f64; K]],
    x: &[[f64; K]],
) -> f64 {
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
pub(crate) fn solve_exact<const K: usize>(
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
/// collapses on oversubscribed machines.
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;
    use crate::numerics::fem::{cotangent_stiffness, lumped_mass, system_matrix};
    use glam::DVec3;

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
        let r = crate::subdiv::refine::quadrisect(&m).unwrap();
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
