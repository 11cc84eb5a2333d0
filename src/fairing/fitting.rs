//! Vertex fitting to a smoothed normal field (`docs/algorithms.md` §2.6):
//!
//! ```text
//! E(P) = Σ_T A(T) ‖n(T) − m(T)‖² = Σ_T (2A(T) − N_T · m(T)),   N_T = (P1 − P0) × (P2 − P0)
//! ∇_P E = Σ_{T ∋ P} (n(T) − m(T)) × (Pb − Pa)      for T = (P, Pa, Pb) counter-clockwise
//! ```
//!
//! minimised with nonlinear conjugate gradients (Polak–Ribière+, restarted on loss of descent)
//! and an Armijo backtracking line search. Each step moves no vertex further than a cap, and a
//! step that turns any face over (`N_T^new · N_T^old ≤ 0`) is rejected like one that fails the
//! Armijo test: the energy's `2A` term rewards shrinking faces whose normal is off target, and
//! a folded face would satisfy it spuriously.
//!
//! Determinism: per-face and per-vertex terms are computed independently in parallel; every
//! global sum adds fixed-size chunks sequentially in a fixed order, so results are bitwise the
//! same for any number of threads.

use super::surface::{FlatSurface, unit_normal};
use crate::progress::Progress;
use glam::DVec3;
use rayon::prelude::*;

/// Consecutive small decreases that end the fitting: a single short step (capped, or cut
/// back by the flip test) is not convergence.
pub(crate) const STALL_ITERATIONS: usize = 5;

/// Chunk length of the fixed-order parallel sums.
const CHUNK: usize = 4096;

/// Parameters of the optimiser.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct FitOptions {
    /// Most CG iterations.
    pub max_iterations: usize,
    /// Stop when [`STALL_ITERATIONS`] iterations in a row each lower the energy by less than
    /// this fraction of it.
    pub tolerance: f64,
    /// Largest move of any vertex in one step, in absolute length.
    pub step_cap: f64,
    /// Armijo sufficient-decrease constant c₁.
    pub armijo: f64,
    /// Most halvings of the step in one line search.
    pub max_halvings: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            max_iterations: 200,
            tolerance: 1e-6,
            step_cap: 0.1,
            armijo: 1e-4,
            max_halvings: 30,
        }
    }
}

/// What the optimiser did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FitReport {
    /// Iterations that moved the vertices.
    pub iterations: usize,
    /// Energy at the start.
    pub initial_energy: f64,
    /// Energy at the end (never above the start).
    pub final_energy: f64,
    /// Trial steps rejected because a face would have flipped.
    pub rejected_flips: usize,
}

/// The fitting problem: connectivity, targets and the vertex → corner incidence for gradients.
pub(crate) struct Fitting<'a> {
    surface: &'a FlatSurface,
    targets: &'a [DVec3],
    /// CSR of faces per vertex slot: `faces[starts[v]..starts[v + 1]]` are the faces with a
    /// corner at `v`, in face order (which fixes the order of every per-vertex sum). The
    /// corner itself is found again in the triangle (its three vertices differ), which
    /// costs less than storing it at the fitting's peak.
    starts: Vec<u32>,
    faces: Vec<u32>,
}

impl<'a> Fitting<'a> {
    /// The energy of `surface` against the target normals `targets` (one per face; a zero
    /// target leaves its face out of the energy).
    pub(crate) fn new(surface: &'a FlatSurface, targets: &'a [DVec3]) -> Fitting<'a> {
        let nv = surface.vertex_slots;
        let mut starts = vec![0u32; nv + 1];
        for t in &surface.triangles {
            for &v in t {
                starts[v as usize + 1] += 1;
            }
        }
        for i in 0..nv {
            starts[i + 1] += starts[i];
        }
        let mut fill = starts.clone();
        let mut faces = vec![0u32; starts[nv] as usize];
        for (f, t) in surface.triangles.iter().enumerate() {
            for &v in t {
                faces[fill[v as usize] as usize] = f as u32;
                fill[v as usize] += 1;
            }
        }
        Fitting {
            surface,
            targets,
            starts,
            faces,
        }
    }

    /// The faces with a corner at vertex slot `v`, in face order.
    #[inline]
    fn faces_at(&self, v: usize) -> &[u32] {
        &self.faces[self.starts[v] as usize..self.starts[v + 1] as usize]
    }

    /// `E = Σ_T (2A(T) − N_T·m(T))` over faces with a target.
    pub(crate) fn energy(&self, positions: &[DVec3]) -> f64 {
        fixed_sum(self.surface.n_faces(), |f| self.face_energy(positions, f))
    }

    #[inline]
    fn face_energy(&self, positions: &[DVec3], f: usize) -> f64 {
        let m = self.targets[f];
        if m == DVec3::ZERO {
            return 0.0;
        }
        let nt = self.surface.area_vector(positions, f);
        nt.length() - nt.dot(m)
    }

    /// The gradient of [`Fitting::energy`] into `out` (indexed by vertex slot).
    pub(crate) fn gradient(&self, positions: &[DVec3], out: &mut [DVec3]) {
        let tris = &self.surface.triangles;
        out.par_iter_mut()
            .with_min_len(1024)
            .enumerate()
            .for_each(|(v, g)| {
                let mut acc = DVec3::ZERO;
                for &f in self.faces_at(v) {
                    let f = f as usize;
                    let m = self.targets[f];
                    if m == DVec3::ZERO {
                        continue;
                    }
                    let t = tris[f];
                    let k = t.iter().position(|&u| u as usize == v).unwrap_or(0);
                    let a = positions[t[(k + 1) % 3] as usize];
                    let b = positions[t[(k + 2) % 3] as usize];
                    let (n, _) = unit_normal(self.surface.area_vector(positions, f));
                    acc += (n - m).cross(b - a);
                }
                *g = acc;
            });
    }

    /// `iterations` rounds of the local vertex update of Sun et al. (2007): every vertex moves
    /// to where, on average over its faces, it lies in the plane through the face's centroid
    /// with the target normal, `x ← x + Σ_T m(T) (m(T)·(c(T) − x)) / |T ∋ x|`. Each vertex's
    /// move is in units of its own faces, so small and large triangles converge alike, which
    /// the global energy does not do (its terms weigh with the area). Jacobi order: all moves
    /// from the same positions, so the result does not depend on the thread count.
    pub(crate) fn project(&self, positions: &mut [DVec3], iterations: usize) {
        let tris = &self.surface.triangles;
        let mut next = positions.to_vec();
        for _ in 0..iterations {
            next.par_iter_mut()
                .with_min_len(1024)
                .enumerate()
                .for_each(|(v, out)| {
                    let x = positions[v];
                    let (mut sum, mut count) = (DVec3::ZERO, 0.0);
                    for &f in self.faces_at(v) {
                        let m = self.targets[f as usize];
                        if m == DVec3::ZERO {
                            continue;
                        }
                        let c = tris[f as usize].map(|u| positions[u as usize]);
                        let centroid = (c[0] + c[1] + c[2]) / 3.0;
                        sum += m * m.dot(centroid - x);
                        count += 1.0;
                    }
                    *out = if count > 0.0 { x + sum / count } else { x };
                });
            positions.copy_from_slice(&next);
        }
    }

    /// Minimises the energy starting from `positions`, which receive the result. Vertices in
    /// no face have zero gradient and stay put. `progress` goes 0 → 1.
    pub(crate) fn minimise(
        &self,
        positions: &mut [DVec3],
        options: &FitOptions,
        progress: &dyn Progress,
    ) -> FitReport {
        let mut report = FitReport::default();
        let energy = self.energy(positions);
        report.initial_energy = energy;
        report.final_energy = energy;
        if !(energy.is_finite() && options.step_cap > 0.0) {
            return report;
        }
        let mut cg = Cg::start(self, positions, energy);
        while report.iterations < options.max_iterations && cg.grad_sq > 0.0 {
            let slope = cg.descent_slope();
            let longest = max_length(&cg.dir);
            if !(longest > 0.0 && longest.is_finite()) {
                break;
            }
            let alpha_max = options.step_cap / longest;
            self.surface_normals(positions, &mut cg.old_normals);
            let Some((new_energy, alpha)) =
                self.line_search(positions, &mut cg, alpha_max, slope, options, &mut report)
            else {
                if cg.steepest {
                    break; // not even a tiny steepest-descent step helps: converged
                }
                cg.restart_steepest();
                continue;
            };
            positions.copy_from_slice(&cg.trial);
            report.iterations += 1;
            let decrease = cg.energy - new_energy;
            cg.energy = new_energy;
            report.final_energy = new_energy;
            progress.update(report.iterations as f64 / options.max_iterations as f64);
            if cg.stalled(decrease, options.tolerance) {
                break;
            }
            cg.polak_ribiere(self, positions);
            // Let the next search start a little beyond this step.
            cg.alpha_guess = 2.0 * alpha;
        }
        progress.update(1.0);
        report
    }

    /// Armijo backtracking along `cg.dir` from a step of at most `alpha_max`, halving the
    /// step on a failed test or a flipped face; the accepted energy (its point in `cg.trial`)
    /// and step.
    fn line_search(
        &self,
        positions: &[DVec3],
        cg: &mut Cg,
        alpha_max: f64,
        slope: f64,
        options: &FitOptions,
        report: &mut FitReport,
    ) -> Option<(f64, f64)> {
        let mut alpha = cg.alpha_guess.min(alpha_max);
        for _ in 0..=options.max_halvings {
            cg.trial
                .par_iter_mut()
                .with_min_len(4096)
                .zip(positions.par_iter())
                .zip(cg.dir.par_iter())
                .for_each(|((t, p), d)| *t = *p + alpha * *d);
            match self.trial_energy(&cg.trial, &cg.old_normals) {
                Some(e) if e <= cg.energy + options.armijo * alpha * slope => {
                    return Some((e, alpha));
                }
                Some(_) => {}
                None => report.rejected_flips += 1,
            }
            alpha *= 0.5;
        }
        None
    }

    fn surface_normals(&self, positions: &[DVec3], out: &mut [DVec3]) {
        out.par_iter_mut()
            .with_min_len(4096)
            .enumerate()
            .for_each(|(f, n)| *n = self.surface.area_vector(positions, f));
    }

    /// The energy at `trial`, or `None` if a face turned over against `old_normals`.
    fn trial_energy(&self, trial: &[DVec3], old_normals: &[DVec3]) -> Option<f64> {
        let n = self.surface.n_faces();
        let chunks: Vec<Option<f64>> = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut sum = 0.0;
                let range = c * CHUNK..((c + 1) * CHUNK).min(n);
                for (f, &old) in range.clone().zip(&old_normals[range]) {
                    let nt = self.surface.area_vector(trial, f);
                    if old != DVec3::ZERO && nt.dot(old) <= 0.0 {
                        return None;
                    }
                    let m = self.targets[f];
                    if m != DVec3::ZERO {
                        sum += nt.length() - nt.dot(m);
                    }
                }
                Some(sum)
            })
            .collect();
        let mut total = 0.0;
        for c in chunks {
            total += c?;
        }
        total.is_finite().then_some(total)
    }
}

/// The conjugate-gradient iteration's state besides the positions.
struct Cg {
    energy: f64,
    grad: Vec<DVec3>,
    /// The previous iteration's gradient, for Polak–Ribière (buffers swap each iteration).
    prev_grad: Vec<DVec3>,
    dir: Vec<DVec3>,
    /// The point a line search tries.
    trial: Vec<DVec3>,
    /// The faces' area vectors before the step, for the flip test.
    old_normals: Vec<DVec3>,
    grad_sq: f64,
    alpha_guess: f64,
    /// `dir` is the steepest descent.
    steepest: bool,
    /// Consecutive iterations with a small decrease.
    stalled: usize,
}

impl Cg {
    /// Starts along the steepest descent at `positions`, whose energy is `energy`.
    fn start(fitting: &Fitting, positions: &[DVec3], energy: f64) -> Cg {
        let nv = positions.len();
        let old_normals: Vec<DVec3> = vec![DVec3::ZERO; fitting.surface.n_faces()];
        let mut grad = vec![DVec3::ZERO; nv];
        let prev_grad = vec![DVec3::ZERO; nv];
        let mut dir = vec![DVec3::ZERO; nv];
        let trial = positions.to_vec();
        fitting.gradient(positions, &mut grad);
        for (d, g) in dir.iter_mut().zip(&grad) {
            *d = -*g;
        }
        let grad_sq = dot(&grad, &grad);
        Cg {
            energy,
            grad,
            prev_grad,
            dir,
            trial,
            old_normals,
            grad_sq,
            alpha_guess: f64::INFINITY,
            steepest: true,
            stalled: 0,
        }
    }

    /// The slope along `dir`, which turns to the steepest descent when it is no descent.
    fn descent_slope(&mut self) -> f64 {
        let slope = dot(&self.grad, &self.dir);
        if slope.is_nan() || slope >= 0.0 {
            self.set_steepest_dir();
            self.steepest = true;
            return -self.grad_sq;
        }
        slope
    }

    fn set_steepest_dir(&mut self) {
        for (d, g) in self.dir.iter_mut().zip(&self.grad) {
            *d = -*g;
        }
    }

    /// Retries the iteration along the steepest descent.
    fn restart_steepest(&mut self) {
        self.steepest = true;
        self.set_steepest_dir();
        self.alpha_guess = f64::INFINITY;
    }

    /// Counts a decrease of less than `tolerance` times the energy; true after
    /// [`STALL_ITERATIONS`] in a row.
    fn stalled(&mut self, decrease: f64, tolerance: f64) -> bool {
        if decrease <= tolerance * self.energy.abs() {
            self.stalled += 1;
            self.stalled >= STALL_ITERATIONS
        } else {
            self.stalled = 0;
            false
        }
    }

    /// The next direction at the new `positions`, Polak–Ribière+:
    /// β = max(0, g⁺·(g⁺ − g)/‖g‖²).
    fn polak_ribiere(&mut self, fitting: &Fitting, positions: &[DVec3]) {
        std::mem::swap(&mut self.grad, &mut self.prev_grad);
        fitting.gradient(positions, &mut self.grad);
        let new_sq = dot(&self.grad, &self.grad);
        let cross = dot(&self.grad, &self.prev_grad);
        let beta = ((new_sq - cross) / self.grad_sq).max(0.0);
        let beta = if beta.is_finite() { beta } else { 0.0 };
        for (d, g) in self.dir.iter_mut().zip(&self.grad) {
            *d = beta * *d - *g;
        }
        self.steepest = beta == 0.0;
        self.grad_sq = new_sq;
    }
}

/// `Σ_{i<n} term(i)`, summed in fixed chunks (parallel) whose partial sums are then added in
/// order, so the result does not depend on the number of threads.
fn fixed_sum(n: usize, term: impl Fn(usize) -> f64 + Sync) -> f64 {
    let partial: Vec<f64> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| (c * CHUNK..((c + 1) * CHUNK).min(n)).map(&term).sum())
        .collect();
    partial.iter().sum()
}

fn dot(a: &[DVec3], b: &[DVec3]) -> f64 {
    fixed_sum(a.len(), |i| a[i].dot(b[i]))
}

fn max_length(a: &[DVec3]) -> f64 {
    // max is order-independent, so a plain parallel reduction is deterministic.
    a.par_iter()
        .map(|d| d.length_squared())
        .reduce(|| 0.0, f64::max)
        .sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;
    use crate::progress::NoProgress;

    fn noisy_sphere() -> (FlatSurface, Vec<DVec3>) {
        // A UV sphere with deterministic radial jitter.
        let (p, t) = crate::mesh::shapes::uv_sphere(16, 10, |_, i, j| {
            1.0 + 0.05 * ((i * 7 + j * 13) as f64).sin()
        });
        let built = Mesh::from_triangles(&p, &t).expect("valid sphere");
        (FlatSurface::new(&built.mesh), built.mesh.positions())
    }

    fn targets(s: &FlatSurface, p: &[DVec3]) -> Vec<DVec3> {
        // Radial directions at the centroids: the normals of the clean sphere.
        (0..s.n_faces())
            .map(|f| s.centroid(p, f).normalize())
            .collect()
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let (s, p) = noisy_sphere();
        let mut m = targets(&s, &p);
        // Perturb the targets so the gradient is far from zero.
        for (i, x) in m.iter_mut().enumerate() {
            *x = (*x + 0.3 * DVec3::new((i as f64).sin(), (i as f64 * 1.7).cos(), 0.2)).normalize();
        }
        let fit = Fitting::new(&s, &m);
        let mut g = vec![DVec3::ZERO; p.len()];
        fit.gradient(&p, &mut g);
        let h = 1e-6;
        let mut worst = 0.0f64;
        for v in [0usize, 5, 17, 40, 100] {
            for c in 0..3 {
                let mut pp = p.clone();
                let mut pm = p.clone();
                pp[v][c] += h;
                pm[v][c] -= h;
                let fd = (fit.energy(&pp) - fit.energy(&pm)) / (2.0 * h);
                worst = worst.max((fd - g[v][c]).abs());
            }
        }
        assert!(worst < 1e-7, "{worst}");
    }

    #[test]
    fn fitting_lowers_the_energy_without_flips() {
        let (s, p) = noisy_sphere();
        let m = targets(&s, &p);
        let fit = Fitting::new(&s, &m);
        let mut x = p.clone();
        let options = FitOptions {
            step_cap: 0.02,
            ..FitOptions::default()
        };
        let r = fit.minimise(&mut x, &options, &NoProgress);
        assert!(r.iterations > 0);
        assert!(r.final_energy < 0.5 * r.initial_energy, "{r:?}");
        assert!((fit.energy(&x) - r.final_energy).abs() < 1e-12);
        for f in 0..s.n_faces() {
            assert!(
                s.area_vector(&x, f).dot(s.area_vector(&p, f)) > 0.0,
                "face {f} flipped"
            );
        }
        // The fitted sphere is rounder: radii vary less than the jitter.
        let radii: Vec<f64> = x[2..].iter().map(|q| q.length()).collect();
        let spread = |r: &[f64]| {
            let mean = r.iter().sum::<f64>() / r.len() as f64;
            r.iter().map(|x| (x - mean).powi(2)).sum::<f64>()
        };
        let before: Vec<f64> = p[2..].iter().map(|q| q.length()).collect();
        assert!(
            spread(&radii) < 0.5 * spread(&before),
            "{} vs {}",
            spread(&radii),
            spread(&before)
        );
    }

    #[test]
    fn zero_targets_and_isolated_vertices_stay_out() {
        let (s, p) = noisy_sphere();
        let m = vec![DVec3::ZERO; s.n_faces()];
        let fit = Fitting::new(&s, &m);
        assert_eq!(fit.energy(&p), 0.0);
        let mut x = p.clone();
        let r = fit.minimise(&mut x, &FitOptions::default(), &NoProgress);
        assert_eq!(r.iterations, 0);
        assert_eq!(x, p);
    }

    /// A noisy plane with the plane's normal as every face's target.
    fn noisy_plane(scale: f64) -> (FlatSurface, Vec<DVec3>) {
        let mesh =
            crate::fairing::testutil::noisy(&crate::fairing::testutil::grid(12, 0.0), 0.02, 7);
        let p: Vec<DVec3> = mesh.positions().iter().map(|&x| x * scale).collect();
        (FlatSurface::new(&mesh), p)
    }

    fn height_spread(p: &[DVec3], scale: f64) -> f64 {
        let mean = p.iter().map(|x| x.z).sum::<f64>() / p.len() as f64;
        (p.iter().map(|x| (x.z - mean).powi(2)).sum::<f64>() / p.len() as f64).sqrt() / scale
    }

    #[test]
    fn vertex_updates_flatten_a_noisy_plane_at_any_scale() {
        let mut spreads = Vec::new();
        for scale in [1.0, 1e-3] {
            let (s, mut p) = noisy_plane(scale);
            let m = vec![DVec3::Z; s.n_faces()];
            let before = height_spread(&p, scale);
            Fitting::new(&s, &m).project(&mut p, 10);
            let after = height_spread(&p, scale);
            assert!(after < 0.2 * before, "{after} vs {before}");
            spreads.push(after);
        }
        // The update is in units of each vertex's own faces: a thousandfold smaller copy
        // converges exactly as far (which the area-weighted energy does not).
        assert!(
            (spreads[0] - spreads[1]).abs() < 1e-9 * spreads[0],
            "{spreads:?}"
        );
    }

    #[test]
    fn vertex_updates_leave_faces_without_a_target_and_lone_vertices_alone() {
        let (s, p) = noisy_plane(1.0);
        let mut q = p.clone();
        Fitting::new(&s, &vec![DVec3::ZERO; s.n_faces()]).project(&mut q, 5);
        assert_eq!(p, q);
    }
}
