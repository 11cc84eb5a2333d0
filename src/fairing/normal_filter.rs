//! The adaptive Gaussian filter of face normals with automatic scale selection
//! (`docs/algorithms.md` §2.3–2.4).
//!
//! For each triangle T and each σ of a grid, the smoothed normal is
//! `m_σ(T) = Σ_j w_j n_j / ‖Σ_j w_j n_j‖` with `w_j = A(T_j) K_σ(d(T, T_j))` over the dual
//! geodesic ball of T, and its spread is the weighted variance `V_σ(T)` ([`local_variance`]).
//! The scale kept is `σ_opt = argmin_σ [V_σ(T) + ε/σ²]`: small where normals vary (noise or
//! features), large where the surface is flat. One Dijkstra to the largest support serves all
//! scales, evaluated in one sweep over the distance-sorted ball. The support may be cut short
//! of the kernel's 4σ ([`ScaleGrid::reach`]): the ball's size, hence the time, goes with the
//! square of its radius, and the kernel's tail beyond 3σ holds 0.5 % of its weight.

use super::dual::{DualBall, DualGraph};
use super::kernel;
use crate::progress::Progress;
use glam::DVec3;
use rayon::prelude::*;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Most scales a grid may have (the sweep keeps its accumulators on the stack).
pub(crate) const MAX_SCALES: usize = 64;

/// Scale selection parameters in absolute units (lengths, length²).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct ScaleGrid {
    /// The candidate σ, ascending, positive; at most [`MAX_SCALES`].
    pub sigmas: Vec<f64>,
    /// ε of rule (5), in length² (the penalty ε/σ² is dimensionless like the variance).
    pub epsilon: f64,
    /// ρ of the anisotropic metric ([`super::dual::edge_weight`]); 0 for the isotropic filter.
    pub rho: f64,
    /// Where the neighbourhoods are cut, in units of σ: faces at `reach · σ` or farther get
    /// no weight at that σ. At most the kernel's support [`kernel::SUPPORT`].
    pub reach: f64,
    /// Which variance estimate the selection rule uses.
    pub variance: Variance,
    /// Per face, the factor its σ values are multiplied by (its local edge length over the
    /// mean), or empty for one scale everywhere. ε/σ² is dimensionless, so the penalty does
    /// not change: only the kernels stretch.
    pub local: Vec<f64>,
}

/// The variance estimate of rule (5); see `local_variance`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Variance {
    /// The weighted variance `Σ w ‖m − n‖² / Σ w` as reconstructed from the paper.
    Biased,
    /// The same with the reliability-weights correction `(Σw)² / ((Σw)² − Σw²)`. At small σ
    /// the ball's weight sits on the face itself, so the biased variance is near zero however
    /// noisy the normals are, and the rule then keeps noisy faces at the smallest scale; the
    /// correction estimates the spread of the normals instead, independent of σ on a noisy
    /// plane, so only real variation (features, curvature) keeps σ small.
    #[default]
    Unbiased,
}

/// The filtered normal field.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct FilteredNormals {
    /// m(T), unit length; zero for a face whose neighbourhood carries no weight at any scale
    /// (an isolated degenerate triangle), which the fitting then leaves out.
    pub normals: Vec<DVec3>,
    /// Index into [`ScaleGrid::sigmas`] of σ_opt(T); `u8::MAX` where `normals` is zero.
    pub scale: Vec<u8>,
}

/// The local variance of the normals about their weighted mean, reconstructed from §2.4:
/// `V = Σ w_j ‖m − n_j‖² / Σ w_j` with `m = S/‖S‖`, `S = Σ w_j n_j`.
///
/// Every weighted normal has unit length (degenerate faces have zero weight), so
/// `Σ w_j ‖m − n_j‖² = Σ w_j (2 − 2 m·n_j) = 2 Σw − 2‖S‖`, which lets one sweep accumulate only
/// `Σw` and `S` (and `Σw²` for the [`Variance::Unbiased`] correction). Returns `None` when
/// the mean is undefined, or for the unbiased estimate when a single face carries all the
/// weight (no spread can be estimated).
#[inline]
pub(crate) fn local_variance(
    kind: Variance,
    weight_sum: f64,
    weight_sq_sum: f64,
    weighted_normals: DVec3,
) -> Option<f64> {
    let s = weighted_normals.length();
    if !(weight_sum > 0.0 && s > 0.0 && s.is_finite()) {
        return None;
    }
    let biased = (2.0 - 2.0 * s / weight_sum).max(0.0);
    match kind {
        Variance::Biased => Some(biased),
        Variance::Unbiased => {
            let w2 = weight_sum * weight_sum;
            let effective = w2 - weight_sq_sum;
            // Fewer than about 1.01 effective samples: the correction is meaningless.
            (effective > 1e-2 * w2).then(|| biased * w2 / effective)
        }
    }
}

/// Filters the face normals `normals` (unit or zero) with weights `areas` on `graph`.
///
/// Runs in parallel over faces; every face's result depends only on the inputs, so the output
/// is identical for any number of threads. `progress` goes 0 → 1.
pub(crate) fn filter_normals(
    graph: &DualGraph,
    normals: &[DVec3],
    areas: &[f64],
    grid: &ScaleGrid,
    progress: &dyn Progress,
) -> FilteredNormals {
    let n = graph.len();
    let k = grid.sigmas.len().min(MAX_SCALES);
    let sigmas = &grid.sigmas[..k];
    let reach = grid.reach.clamp(0.0, kernel::SUPPORT);
    let radius = sigmas.last().map_or(0.0, |s| reach * s);
    let inv: Vec<f64> = sigmas.iter().map(|s| 1.0 / s).collect();
    let penalty: Vec<f64> = sigmas.iter().map(|s| grid.epsilon / (s * s)).collect();
    let table = kernel::ShapeTable::new();
    let pool = Pool(Mutex::new(Vec::new()));
    let done = AtomicUsize::new(0);
    let step = (n / 200).max(1024);
    // Written in place rather than collected and split: the filter runs at the denoiser's
    // peak, where a face-sized temporary would raise it.
    let mut filtered = FilteredNormals {
        normals: vec![DVec3::ZERO; n],
        scale: vec![u8::MAX; n],
    };
    filtered
        .normals
        .par_iter_mut()
        .zip(filtered.scale.par_iter_mut())
        .enumerate()
        .with_min_len(256)
        .for_each_init(
            || pool.take(n),
            |ws, (f, (normal, scale))| {
                let ball = ws.ball.as_mut().expect("workspace present until dropped");
                let local = grid.local.get(f).copied().unwrap_or(1.0);
                ball.grow(graph, normals, grid.rho, f as u32, radius * local);
                let inv_local: [f64; MAX_SCALES] =
                    std::array::from_fn(|s| inv.get(s).map_or(0.0, |i| i / local));
                (*normal, *scale) = select_scale(
                    &ball.ball,
                    normals,
                    areas,
                    &Sweep {
                        inv_sigma: &inv_local[..k],
                        reach,
                        penalty: &penalty,
                        variance: grid.variance,
                        table: &table,
                    },
                );
                let c = done.fetch_add(1, Ordering::Relaxed) + 1;
                if c.is_multiple_of(step) {
                    progress.update(c as f64 / n as f64);
                }
            },
        );
    progress.update(1.0);
    filtered
}

/// What the sweep of one face needs besides its ball.
#[derive(Clone, Copy)]
struct Sweep<'a> {
    /// 1/σ per scale, ascending σ (the face's local factor applied).
    inv_sigma: &'a [f64],
    /// Where the neighbourhoods are cut, in units of σ ([`ScaleGrid::reach`]).
    reach: f64,
    /// ε/σ² per scale.
    penalty: &'a [f64],
    variance: Variance,
    table: &'a kernel::ShapeTable,
}

/// The sweep for one face: accumulate `Σw` and `S` for every scale over the sorted ball, then
/// pick the scale minimising `V_σ + ε/σ²` (the smallest σ on ties).
fn select_scale(
    ball: &[(f64, u32)],
    normals: &[DVec3],
    areas: &[f64],
    sweep: &Sweep,
) -> (DVec3, u8) {
    let Sweep {
        inv_sigma,
        reach,
        penalty,
        variance,
        table,
    } = *sweep;
    let k = inv_sigma.len();
    let mut w_sum = [0.0f64; MAX_SCALES];
    let mut w_sq = [0.0f64; MAX_SCALES];
    let mut s_sum = [DVec3::ZERO; MAX_SCALES];
    // Scales whose support no longer reaches the current (sorted) distance drop out for good:
    // `first` is the smallest scale still active.
    let mut first = 0;
    for &(d, j) in ball {
        let a = areas[j as usize];
        while first < k && d * inv_sigma[first] >= reach {
            first += 1;
        }
        if first == k {
            break;
        }
        if a == 0.0 {
            continue;
        }
        let nj = normals[j as usize];
        for s in first..k {
            let w = a * table.eval(d * inv_sigma[s]);
            w_sum[s] += w;
            w_sq[s] += w * w;
            s_sum[s] += w * nj;
        }
    }
    let pick = |kind: Variance| {
        let mut best: Option<(f64, usize)> = None;
        for s in 0..k {
            if let Some(v) = local_variance(kind, w_sum[s], w_sq[s], s_sum[s]) {
                let score = v + penalty[s];
                if best.is_none_or(|(b, _)| score < b) {
                    best = Some((score, s));
                }
            }
        }
        best
    };
    // A face alone in its component has no spread to estimate: fall back to the biased rule.
    match pick(variance).or_else(|| pick(Variance::Biased)) {
        Some((_, s)) => (s_sum[s].normalize(), s as u8),
        None => (DVec3::ZERO, u8::MAX),
    }
}

/// Dijkstra workspaces shared by rayon jobs: a job takes one (or makes one) and puts it back
/// when it ends, so the face-sized arrays are allocated about once per thread, not per job.
struct Pool(Mutex<Vec<DualBall>>);

struct Lease<'a> {
    pool: &'a Pool,
    ball: Option<DualBall>,
}

impl Pool {
    fn take(&self, n: usize) -> Lease<'_> {
        let ball = self
            .0
            .lock()
            .ok()
            .and_then(|mut v| v.pop())
            .unwrap_or_else(|| DualBall::new(n));
        Lease {
            pool: self,
            ball: Some(ball),
        }
    }
}

impl Drop for Lease<'_> {
    fn drop(&mut self) {
        if let (Some(b), Ok(mut v)) = (self.ball.take(), self.pool.0.lock()) {
            v.push(b);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fairing::surface::FlatSurface;
    use crate::mesh::Mesh;
    use crate::progress::NoProgress;

    fn grid_mesh(n: usize, height: impl Fn(f64, f64) -> f64) -> Mesh {
        let (p, t) = crate::mesh::shapes::grid(n, |i, j| {
            let (x, y) = (i as f64, j as f64);
            DVec3::new(x, y, height(x, y))
        });
        Mesh::from_triangles(&p, &t).expect("valid grid").mesh
    }

    fn run(mesh: &Mesh, grid: &ScaleGrid) -> (FilteredNormals, Vec<DVec3>) {
        let s = FlatSurface::new(mesh);
        let pos = mesh.positions();
        let fr = s.face_frames(&pos);
        let g = DualGraph::new(&s, &pos);
        (
            filter_normals(&g, &fr.normals, &fr.areas, grid, &NoProgress),
            fr.normals,
        )
    }

    fn iso_grid() -> ScaleGrid {
        ScaleGrid {
            sigmas: (1..=10).map(|i| 0.2 * i as f64).collect(),
            epsilon: 0.01,
            rho: 0.0,
            reach: kernel::SUPPORT,
            variance: Variance::Biased,
            local: Vec::new(),
        }
    }

    #[test]
    fn variance_of_agreeing_and_opposing_normals() {
        use Variance::*;
        assert_eq!(
            local_variance(Biased, 2.0, 2.0, DVec3::new(0.0, 0.0, 2.0)),
            Some(0.0)
        );
        // Two orthogonal unit normals with equal weight: ‖m − n‖² = 2 − √2 for both.
        let v = local_variance(Biased, 2.0, 2.0, DVec3::new(1.0, 1.0, 0.0)).unwrap_or(-1.0);
        assert!((v - (2.0 - 2f64.sqrt())).abs() < 1e-15);
        // Unbiased: two equal weights → factor 4 / (4 − 2) = 2.
        let u = local_variance(Unbiased, 2.0, 2.0, DVec3::new(1.0, 1.0, 0.0)).unwrap_or(-1.0);
        assert!((u - 2.0 * (2.0 - 2f64.sqrt())).abs() < 1e-15);
        // One face: no spread to estimate.
        assert_eq!(local_variance(Unbiased, 1.0, 1.0, DVec3::Z), None);
        assert_eq!(local_variance(Biased, 0.0, 0.0, DVec3::ZERO), None);
        assert_eq!(local_variance(Biased, 1.0, 1.0, DVec3::ZERO), None);
    }

    #[test]
    fn faces_at_the_reach_or_beyond_get_no_weight() {
        let normals = [DVec3::Z, DVec3::X, DVec3::Y];
        let areas = [1.0, 1.0, 1.0];
        let table = kernel::ShapeTable::new();
        let sweep = |ball: &[(f64, u32)], reach: f64| {
            let sweep = Sweep {
                inv_sigma: &[1.0],
                reach,
                penalty: &[0.0],
                variance: Variance::Biased,
                table: &table,
            };
            select_scale(ball, &normals, &areas, &sweep)
        };
        let near = [(0.0, 0), (1.0, 1)];
        let far = [(0.0, 0), (1.0, 1), (3.5, 2)];
        // Within the support, 3.5σ still counts; cut at 3σ it does not.
        assert_ne!(sweep(&far, 4.0), sweep(&near, 4.0));
        assert_eq!(sweep(&far, 3.0), sweep(&near, 3.0));
        assert_ne!(sweep(&near, 1.0), sweep(&near, 3.0));
    }

    #[test]
    fn a_plane_keeps_its_normal_and_picks_the_largest_scale() {
        let mesh = grid_mesh(12, |_, _| 0.0);
        let (m, _) = run(&mesh, &iso_grid());
        for (i, n) in m.normals.iter().enumerate() {
            assert!((*n - DVec3::Z).length() < 1e-14, "{n}");
            assert_eq!(m.scale[i], 9);
        }
    }

    #[test]
    fn noise_is_smoothed_and_the_scale_adapts() {
        // Deterministic pseudo-random heights on a plane.
        let hash = |x: f64, y: f64| ((x * 12.9898 + y * 78.233).sin() * 43758.5453).fract() - 0.5;
        let mesh = grid_mesh(20, |x, y| 0.15 * hash(x, y));
        let (m, n) = run(&mesh, &iso_grid());
        let err = |v: &[DVec3]| {
            v.iter()
                .map(|q| (*q - DVec3::Z).length_squared())
                .sum::<f64>()
        };
        assert!(
            err(&m.normals) < 0.2 * err(&n),
            "{} vs {}",
            err(&m.normals),
            err(&n)
        );
        // A plane with mild noise prefers large scales; a larger ε pushes them larger still.
        let mean = |f: &FilteredNormals| {
            f.scale.iter().map(|&s| s as f64).sum::<f64>() / f.scale.len() as f64
        };
        let small_eps = mean(&m);
        let (m2, _) = run(
            &mesh,
            &ScaleGrid {
                epsilon: 0.0005,
                ..iso_grid()
            },
        );
        assert!(mean(&m2) < small_eps, "{} vs {}", mean(&m2), small_eps);
    }

    #[test]
    fn degenerate_and_isolated_faces_do_not_produce_nan() {
        // A lone zero-area triangle and a normal pair.
        let p = [
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(5.0, 0.0, 0.0),
            DVec3::new(6.0, 0.0, 0.0),
            DVec3::new(5.0, 1.0, 0.0),
        ];
        let mesh = Mesh::from_triangles(&p, &[[0, 1, 2], [3, 4, 5]])
            .expect("valid")
            .mesh;
        let (m, _) = run(&mesh, &iso_grid());
        assert_eq!(m.normals[0], DVec3::ZERO);
        assert_eq!(m.scale[0], u8::MAX);
        assert_eq!(m.normals[1], DVec3::Z);
    }

    #[test]
    fn local_factors_make_the_scale_choice_follow_the_sampling() {
        let hash = |x: f64, y: f64| ((x * 12.9898 + y * 78.233).sin() * 43758.5453).fract() - 0.5;
        let mesh = grid_mesh(16, |x, y| 0.15 * hash(x, y));
        let (at_unit_size, _) = run(&mesh, &iso_grid());
        // The same surface an eighth the size (a power of two: exact): with the same absolute
        // σ the kernels are eight times too wide, with local factors of 1/8 they fit again.
        let (p, t) = crate::mesh::shapes::grid(16, |i, j| {
            let (x, y) = (i as f64, j as f64);
            DVec3::new(x, y, 0.15 * hash(x, y)) * 0.125
        });
        let small = Mesh::from_triangles(&p, &t).expect("valid grid").mesh;
        let faces = small.n_faces();
        let (global, _) = run(&small, &iso_grid());
        let local = ScaleGrid {
            local: vec![0.125; faces],
            ..iso_grid()
        };
        let (local, _) = run(&small, &local);
        assert_eq!(local, at_unit_size);
        assert_ne!(global.scale, at_unit_size.scale);
    }
}
