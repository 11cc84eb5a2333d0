//! Linear finite elements on a triangle mesh given as flat arrays (positions, triangles
//! indexing them): lumped mass and cotangent stiffness, assembled into CSR arrays.
//!
//! With the angles θ, θ' opposite edge ij:
//!
//! ```text
//! M_ii = Σ_{T∋i} A(T)/3                       (lumped, diagonal)
//! L_ij = −½ Σ_{T∋ij} a_T cot θ_T   (i ≠ j),   L_ii = −Σ_{j≠i} L_ij
//! ```
//!
//! `a_T` is an optional per-face diffusion coefficient (1 when absent). L is positive
//! semi-definite; boundary edges have one cotangent term (natural boundary conditions).
//! Triangles with area below `1e-12·(longest edge)²` contribute nothing: their cotangents are
//! meaningless and would make the element matrix indefinite.

use glam::DVec3;

/// Relative area below which a triangle is skipped (area < ε·ℓ_max²).
pub(crate) const DEGENERATE_AREA: f64 = 1e-12;

/// Below this many rows the matrix work stays on one thread (rayon's overhead would dominate).
const PARALLEL_ROWS: usize = 8192;
/// Rows per parallel task.
const ROW_CHUNK: usize = 4096;

/// A symmetric sparse matrix in CSR form with the diagonal entry stored first in every row.
#[derive(Clone, Debug, PartialEq)]
pub struct SymmetricCsr {
    /// `row_start[i]..row_start[i+1]` are row `i`'s entries; length n + 1.
    pub row_start: Vec<u32>,
    /// Column of each entry (the first of a row is the row itself).
    pub col: Vec<u32>,
    /// Value of each entry.
    pub val: Vec<f64>,
}

impl SymmetricCsr {
    /// Number of rows.
    pub fn n(&self) -> usize {
        self.row_start.len().saturating_sub(1)
    }

    /// The diagonal entry of row `i`.
    #[inline]
    pub fn diagonal(&self, i: usize) -> f64 {
        self.val[self.row_start[i] as usize]
    }

    /// Row `i` of `A x`, summed in column order.
    #[inline]
    pub(crate) fn row_times<const K: usize>(&self, i: usize, x: &[[f64; K]]) -> [f64; K] {
        let (s, e) = (self.row_start[i] as usize, self.row_start[i + 1] as usize);
        let mut acc = [0.0; K];
        for (&c, &v) in self.col[s..e].iter().zip(&self.val[s..e]) {
            for (a, xc) in acc.iter_mut().zip(&x[c as usize]) {
                *a += v * xc;
            }
        }
        acc
    }

    /// `Σ_i ((A x)_i − b_i)²` per column, without storing the residual. Summed per block of
    /// rows, then over the blocks in order, so the bits do not depend on the thread count.
    pub(crate) fn residual_squares<const K: usize>(
        &self,
        x: &[[f64; K]],
        b: &[[f64; K]],
    ) -> [f64; K] {
        let block = |first: usize, b: &[[f64; K]]| {
            let mut rr = [0.0; K];
            for (i, bi) in (first..).zip(b) {
                let ax = self.row_times(i, x);
                for k in 0..K {
                    let r = ax[k] - bi[k];
                    rr[k] += r * r;
                }
            }
            rr
        };
        let b = &b[..x.len().min(b.len())];
        let sums: Vec<[f64; K]> = if b.len() < PARALLEL_ROWS {
            b.chunks(ROW_CHUNK)
                .enumerate()
                .map(|(c, chunk)| block(c * ROW_CHUNK, chunk))
                .collect()
        } else {
            use rayon::prelude::*;
            b.par_chunks(ROW_CHUNK)
                .enumerate()
                .map(|(c, chunk)| block(c * ROW_CHUNK, chunk))
                .collect()
        };
        sums.iter().fold([0.0; K], |mut acc, s| {
            for k in 0..K {
                acc[k] += s[k];
            }
            acc
        })
    }

    /// `y = A x` for `K` right-hand sides stored row-major.
    pub fn mul<const K: usize>(&self, x: &[[f64; K]], y: &mut [[f64; K]]) {
        // Rows are independent and each is summed in column order, so splitting the rows
        // over threads gives the same bits as one thread.
        let rows = |first: usize, y: &mut [[f64; K]]| {
            for (i, yi) in (first..).zip(y.iter_mut()) {
                *yi = self.row_times(i, x);
            }
        };
        if y.len() < PARALLEL_ROWS {
            rows(0, y);
        } else {
            use rayon::prelude::*;
            y.par_chunks_mut(ROW_CHUNK)
                .enumerate()
                .for_each(|(c, chunk)| rows(c * ROW_CHUNK, chunk));
        }
    }
}

/// Lumped (barycentric) mass `M_ii = Σ A(T)/3` for `triangles` indexing `positions`.
/// Degenerate triangles contribute zero.
pub fn lumped_mass(triangles: &[[u32; 3]], positions: &[DVec3]) -> Vec<f64> {
    let mut m = vec![0.0; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let area = crate::mesh::geometry::triangle_area(a, b, c);
        if is_degenerate(a, b, c, area) {
            continue;
        }
        for &i in t {
            m[i as usize] += area / 3.0;
        }
    }
    m
}

#[inline]
fn is_degenerate(a: DVec3, b: DVec3, c: DVec3, area: f64) -> bool {
    let l2 = (b - a)
        .length_squared()
        .max((c - b).length_squared())
        .max((a - c).length_squared());
    // NaN coordinates count as degenerate.
    area.is_nan() || area <= DEGENERATE_AREA * l2
}

/// `½·a·cot` of the angle opposite each edge `(j, j+1)` of triangle `v`, and the triangle's
/// area; both zero for a degenerate triangle, which counts for neither stiffness nor mass.
///
/// The three corners share `|a × b| = 2·area`, so one cross product and one square root give
/// all three cotangents (`cot = a·b / 2A`), where calling [`cotangent`] per corner would take
/// four of each; the clamp at ±1e5 is the same as [`cotangent`]'s.
#[inline]
fn half_cotangents(v: [DVec3; 3], coef: f64) -> ([f64; 3], f64) {
    const MAX_COT: f64 = 1e5;
    let (e0, e1, e2) = (v[1] - v[0], v[2] - v[1], v[0] - v[2]);
    let twice_area = e0.cross(v[2] - v[0]).length();
    let area = 0.5 * twice_area;
    if is_degenerate(v[0], v[1], v[2], area) {
        return ([0.0; 3], 0.0);
    }
    // Cosine terms at the corner opposite edge j: corner 2 for (0,1), 0 for (1,2), 1 for (2,0).
    let cos = [-e2.dot(e1), -e0.dot(e2), -e1.dot(e0)];
    let half = 0.5 * coef;
    let w = cos.map(|c| {
        let cot = if twice_area <= c.abs() / MAX_COT {
            if c >= 0.0 { MAX_COT } else { -MAX_COT }
        } else {
            c / twice_area
        };
        half * cot
    });
    (w, area)
}

/// Cotangent stiffness matrix L (positive semi-definite, rows sum to zero) of `triangles`
/// indexing `positions`, with optional per-triangle coefficients. Rows are sorted by column
/// after the diagonal.
///
/// Assembly is a counting sort of the directed edge terms into rows, then a sort of each
/// (short) row: linear, and every entry sums its triangles' terms in triangle order. On big
/// meshes each stage runs on all cores — each chunk of triangles counts into its own
/// histogram, which fixes where the chunk writes — and the result is the same bits on any
/// number of threads.
pub fn cotangent_stiffness(
    triangles: &[[u32; 3]],
    positions: &[DVec3],
    face_coefficient: Option<&[f64]>,
) -> SymmetricCsr {
    let tri_weights = triangle_weights(triangles, positions, face_coefficient);
    stiffness_from_weights(triangles, positions.len(), &tri_weights)
}

/// [`lumped_mass`] and [`cotangent_stiffness`] together, the same bits as calling both, from
/// one pass over the triangles' geometry instead of two.
pub(crate) fn mass_and_stiffness(
    triangles: &[[u32; 3]],
    positions: &[DVec3],
    face_coefficient: Option<&[f64]>,
) -> (Vec<f64>, SymmetricCsr) {
    let tri_weights = triangle_weights(triangles, positions, face_coefficient);
    (
        mass_of(triangles, &tri_weights, positions.len()),
        stiffness_from_weights(triangles, positions.len(), &tri_weights),
    )
}

/// Per triangle: `w[j]`, ½·a_T·cot of the angle at corner j+2 (opposite edge (j, j+1)), and
/// the area in `w[3]` (all zero for a degenerate triangle).
pub(crate) fn triangle_weights(
    triangles: &[[u32; 3]],
    positions: &[DVec3],
    face_coefficient: Option<&[f64]>,
) -> Vec<[f64; 4]> {
    use rayon::prelude::*;
    let weights_of = |ti: usize| {
        let coef = face_coefficient.map_or(1.0, |c| c[ti]);
        let (w, area) = half_cotangents(triangles[ti].map(|i| positions[i as usize]), coef);
        [w[0], w[1], w[2], area]
    };
    (0..triangles.len())
        .into_par_iter()
        .with_min_len(PARALLEL_ROWS)
        .map(weights_of)
        .collect()
}

/// The lumped mass from [`triangle_weights`]' areas, summed in triangle order as
/// [`lumped_mass`] does (degenerate triangles add a zero area), so the bits are the same.
pub(crate) fn mass_of(triangles: &[[u32; 3]], tri_weights: &[[f64; 4]], n: usize) -> Vec<f64> {
    let mut mass = vec![0.0; n];
    for (t, w) in triangles.iter().zip(tri_weights) {
        for &i in t {
            mass[i as usize] += w[3] / 3.0;
        }
    }
    mass
}

/// The stiffness of any triangle list from its [`triangle_weights`]: see
/// [`cotangent_stiffness`].
pub(crate) fn stiffness_from_weights(
    triangles: &[[u32; 3]],
    n: usize,
    tri_weights: &[[f64; 4]],
) -> SymmetricCsr {
    let chunk = triangles
        .len()
        .div_ceil(rayon::current_num_threads().max(1))
        .max(PARALLEL_ROWS);
    let mut cursors = count_chunk_rows(triangles, n, chunk);
    let fill = place_chunk_cursors(&mut cursors, n);
    let mut keys = scatter_edge_keys(triangles, chunk, cursors, fill[n]);
    let row_len = sort_rows(&fill, &mut keys);
    let row_start = prefix_row_starts(&row_len);
    drop(row_len);
    let (col, val) = sum_rows(&keys, &fill, &row_start, tri_weights);
    SymmetricCsr {
        row_start,
        col,
        val,
    }
}

// Every directed entry is the key `col << 32 | 3t + j`: its column and the corner whose
// weight it takes, so sorting a row orders it by column and, within a column, by
// triangle — the order the terms are summed in.

/// The column of an edge key.
#[inline]
fn key_column(key: u64) -> u32 {
    (key >> 32) as u32
}

/// The weight of the corner an edge key takes its term from.
#[inline]
fn key_weight(tri_weights: &[[f64; 4]], key: u64) -> f64 {
    let corner = (key & 0xffff_ffff) as usize;
    tri_weights[corner / 3][corner % 3]
}

/// Per chunk of `chunk` triangles, how many directed entries each row receives from it.
fn count_chunk_rows(triangles: &[[u32; 3]], n: usize, chunk: usize) -> Vec<Vec<u32>> {
    use rayon::prelude::*;
    triangles
        .par_chunks(chunk)
        .map(|ch| {
            let mut h = vec![0u32; n];
            for t in ch {
                for &i in t {
                    h[i as usize] += 2;
                }
            }
            h
        })
        .collect()
}

/// Turns the chunks' counts into the slot each chunk writes its next entry of a row to
/// (rows in order, chunks in order within a row), and returns every row's first slot, with
/// the total at `[n]`.
fn place_chunk_cursors(cursors: &mut [Vec<u32>], n: usize) -> Vec<u32> {
    let mut fill = vec![0u32; n + 1];
    let mut at = 0u32;
    for i in 0..n {
        fill[i] = at;
        for h in cursors.iter_mut() {
            let count = h[i];
            h[i] = at;
            at += count;
        }
    }
    fill[n] = at;
    fill
}

/// Writes both directed keys of every triangle edge at the chunks' cursors.
fn scatter_edge_keys(
    triangles: &[[u32; 3]],
    chunk: usize,
    mut cursors: Vec<Vec<u32>>,
    total: u32,
) -> Vec<u64> {
    use rayon::prelude::*;
    use std::sync::atomic::{AtomicU64, Ordering};
    let keys: Vec<AtomicU64> = (0..total as usize)
        .into_par_iter()
        .with_min_len(PARALLEL_ROWS)
        .map(|_| AtomicU64::new(0))
        .collect();
    triangles
        .par_chunks(chunk)
        .zip(cursors.par_iter_mut())
        .enumerate()
        .for_each(|(k, (ch, cursor))| {
            for (i, t) in ch.iter().enumerate() {
                let ti = k * chunk + i;
                for j in 0..3 {
                    let (a, b) = (t[j], t[(j + 1) % 3]);
                    let corner = (3 * ti + j) as u64;
                    for (row, col) in [(a, b), (b, a)] {
                        let c = &mut cursor[row as usize];
                        // Chunks write interleaved slots: relaxed atomic stores are plain
                        // stores and keep this free of `unsafe`.
                        keys[*c as usize].store((col as u64) << 32 | corner, Ordering::Relaxed);
                        *c += 1;
                    }
                }
            }
        });
    drop(cursors);
    keys.into_iter().map(AtomicU64::into_inner).collect()
}

/// Sorts every row's keys and returns its length in the matrix (the diagonal and one entry
/// per distinct column), whole rows per task.
fn sort_rows(fill: &[u32], keys: &mut [u64]) -> Vec<u32> {
    use rayon::prelude::*;
    split_rows(fill, keys)
        .into_par_iter()
        .flat_map_iter(|(first, last, piece)| {
            let base = fill[first] as usize;
            (first..last).map(move |i| {
                let row = &mut piece[fill[i] as usize - base..fill[i + 1] as usize - base];
                row.sort_unstable();
                1 + row
                    .chunk_by(|a, b| key_column(*a) == key_column(*b))
                    .count() as u32
            })
        })
        .collect()
}

/// The CSR row starts from the row lengths.
fn prefix_row_starts(row_len: &[u32]) -> Vec<u32> {
    let mut row_start = Vec::with_capacity(row_len.len() + 1);
    row_start.push(0u32);
    let mut at = 0u32;
    for &l in row_len {
        at += l;
        row_start.push(at);
    }
    row_start
}

/// The matrix's columns and values: per row the diagonal, then each column's terms summed
/// in triangle order, in chunks of `ROW_CHUNK` rows.
fn sum_rows(
    keys: &[u64],
    fill: &[u32],
    row_start: &[u32],
    tri_weights: &[[f64; 4]],
) -> (Vec<u32>, Vec<f64>) {
    use rayon::prelude::*;
    let n = row_start.len() - 1;
    let at = row_start[n];
    let mut col = vec![0u32; at as usize];
    let mut val = vec![0.0f64; at as usize];
    split_csr_rows(row_start, &mut col, &mut val)
        .into_par_iter()
        .with_min_len(PARALLEL_ROWS / ROW_CHUNK)
        .for_each(|(first, last, col, val)| {
            let mut at = 0;
            for i in first..last {
                let row = &keys[fill[i] as usize..fill[i + 1] as usize];
                at += sum_row(i, row, tri_weights, &mut col[at..], &mut val[at..]);
            }
        });
    (col, val)
}

/// Splits `col` and `val` at row boundaries (`row_start`) into pieces of `ROW_CHUNK` rows,
/// as `(first row, end row, col, val)`.
fn split_csr_rows<'a>(
    row_start: &[u32],
    col: &'a mut [u32],
    val: &'a mut [f64],
) -> Vec<(usize, usize, &'a mut [u32], &'a mut [f64])> {
    let n = row_start.len() - 1;
    let mut pieces = Vec::with_capacity(n / ROW_CHUNK + 1);
    let (mut col_rest, mut val_rest) = (col, val);
    for first in (0..n).step_by(ROW_CHUNK) {
        let last = (first + ROW_CHUNK).min(n);
        let len = (row_start[last] - row_start[first]) as usize;
        let (c, cr) = std::mem::take(&mut col_rest).split_at_mut(len);
        let (v, vr) = std::mem::take(&mut val_rest).split_at_mut(len);
        pieces.push((first, last, c, v));
        (col_rest, val_rest) = (cr, vr);
    }
    pieces
}

/// Writes row `i` from its sorted keys at the start of `col` and `val`; returns how many
/// entries it wrote.
#[inline]
fn sum_row(
    i: usize,
    row: &[u64],
    tri_weights: &[[f64; 4]],
    col: &mut [u32],
    val: &mut [f64],
) -> usize {
    col[0] = i as u32;
    let mut at = 1;
    let mut diag = 0.0;
    // An interior edge appears twice (once per triangle), summed in triangle order.
    for run in row.chunk_by(|a, b| key_column(*a) == key_column(*b)) {
        let mut w = key_weight(tri_weights, run[0]);
        for &e in &run[1..] {
            w += key_weight(tri_weights, e);
        }
        col[at] = key_column(run[0]);
        val[at] = -w;
        at += 1;
        diag += w;
    }
    val[0] = diag;
    at
}

/// Splits `keys` at row boundaries (`fill`) into pieces of about `ROW_CHUNK` rows, as
/// `(first row, end row, keys)`, for parallel work over whole rows.
fn split_rows<'a>(fill: &[u32], keys: &'a mut [u64]) -> Vec<(usize, usize, &'a mut [u64])> {
    let n = fill.len() - 1;
    let mut pieces = Vec::with_capacity(n / ROW_CHUNK + 1);
    let mut rest = keys;
    for first in (0..n).step_by(ROW_CHUNK) {
        let last = (first + ROW_CHUNK).min(n);
        let (piece, tail) =
            std::mem::take(&mut rest).split_at_mut((fill[last] - fill[first]) as usize);
        pieces.push((first, last, piece));
        rest = tail;
    }
    pieces
}

/// Clamps negative edge weights (positive off-diagonal entries of L, on edges whose opposite
/// angles sum to more than π) to zero and restores zero row sums. The result is a weakly
/// diagonally dominant M-matrix, so `M + αL` is positive definite for any α ≥ 0 even where the
/// cotangent clamp of needle triangles has made the exact stiffness slightly indefinite.
/// Returns the number of entries clamped (each edge counts twice).
pub(crate) fn clamp_negative_weights(stiffness: &mut SymmetricCsr) -> usize {
    let mut clamped = 0;
    for i in 0..stiffness.n() {
        let (s, e) = (
            stiffness.row_start[i] as usize,
            stiffness.row_start[i + 1] as usize,
        );
        let mut diag = 0.0;
        for v in &mut stiffness.val[s + 1..e] {
            if *v > 0.0 {
                *v = 0.0;
                clamped += 1;
            }
            diag -= *v;
        }
        stiffness.val[s] = diag;
    }
    clamped
}

/// The system matrix `M + α L` (`alpha = 1` when L already carries the coefficient).
///
/// Rows whose diagonal is not positive (an isolated vertex, or a vertex whose triangles are
/// all degenerate) become identity rows; `identity_rows` lists them so the right-hand side
/// can pin those vertices to their interpolated initial positions.
pub fn system_matrix(mass: &[f64], stiffness: SymmetricCsr, alpha: f64) -> SymmetricCsr {
    let mut a = stiffness;
    if alpha != 1.0 {
        a.val.iter_mut().for_each(|v| *v *= alpha);
    }
    for (i, m) in mass.iter().enumerate() {
        let d = a.row_start[i] as usize;
        a.val[d] += m;
        if a.val[d].is_nan() || a.val[d] <= 0.0 {
            let e = a.row_start[i + 1] as usize;
            a.val[d] = 1.0;
            a.val[d + 1..e].iter_mut().for_each(|v| *v = 0.0);
        }
    }
    a
}

/// Rows [`system_matrix`] turned into identity rows: exactly the vertices with zero mass
/// (their stiffness row and column are zero too, because every triangle around them was
/// skipped as degenerate, and a non-degenerate P1 stiffness diagonal is positive).
pub(crate) fn identity_rows(mass: &[f64]) -> Vec<bool> {
    mass.iter().map(|&m| m.is_nan() || m <= 0.0).collect()
}

/// The right-hand side `M x` of `(M + αL) x′ = M x`, except on the rows [`system_matrix`]
/// turns into identity rows, which keep `x` itself.
pub(crate) fn mass_rhs(mass: &[f64], x: &[DVec3]) -> Vec<[f64; 3]> {
    x.iter()
        .zip(identity_rows(mass))
        .zip(mass)
        .map(|((p, identity), m)| (*p * if identity { 1.0 } else { *m }).to_array())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn residual_squares_match_the_stored_residual_on_any_thread_count() {
        // A tridiagonal matrix with 20k rows, past the parallel threshold.
        let n: usize = 20_000;
        let mut a = SymmetricCsr {
            row_start: vec![0],
            col: Vec::new(),
            val: Vec::new(),
        };
        for i in 0..n {
            a.col.push(i as u32);
            a.val.push(2.5 + (i % 7) as f64 * 0.1);
            for j in [i.wrapping_sub(1), i + 1] {
                if j < n {
                    a.col.push(j as u32);
                    a.val.push(-1.0);
                }
            }
            a.row_start.push(a.col.len() as u32);
        }
        let x: Vec<[f64; 2]> = (0..n).map(|i| [(i as f64).sin(), 0.5]).collect();
        let b: Vec<[f64; 2]> = (0..n).map(|i| [(i as f64 * 0.3).cos(), 1.0]).collect();
        let mut ax = vec![[0.0; 2]; n];
        a.mul(&x, &mut ax);
        for k in 0..2 {
            let want: f64 = ax.iter().zip(&b).map(|(p, q)| (p[k] - q[k]).powi(2)).sum();
            let got = a.residual_squares(&x, &b)[k];
            assert!((got - want).abs() <= 1e-12 * want, "{got} vs {want}");
        }
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| a.residual_squares(&x, &b))
                .map(f64::to_bits)
        };
        assert_eq!(on(1), on(3));
    }
    use crate::mesh::cotangent;

    /// The former sequential scatter-and-sort assembly, kept as an oracle: cotangent stiffness matrix L (positive semi-definite, rows sum to zero) of `triangles`
    /// indexing `positions`, with optional per-triangle coefficients. Rows are sorted by column
    /// after the diagonal; assembly is a counting sort over the triangle corners, so it is linear
    /// and reads memory in order.
    fn scatter_stiffness(
        triangles: &[[u32; 3]],
        positions: &[DVec3],
        face_coefficient: Option<&[f64]>,
    ) -> SymmetricCsr {
        let n = positions.len();
        // Two directed entries per triangle corner.
        let mut fill: Vec<u32> = vec![0; n + 1];
        for t in triangles {
            for &i in t {
                fill[i as usize + 1] += 2;
            }
        }
        for i in 0..n {
            fill[i + 1] += fill[i];
        }
        // w[j]: ½ a_T cot of the angle at corner j+2, which is opposite edge (j, j+1). Computed per
        // triangle independently (in parallel on big meshes; same bits either way).
        let weights_of = |ti: usize| {
            let coef = face_coefficient.map_or(1.0, |c| c[ti]);
            half_cotangents(triangles[ti].map(|i| positions[i as usize]), coef).0
        };
        let tri_weights: Vec<[f64; 3]> = if triangles.len() < PARALLEL_ROWS {
            (0..triangles.len()).map(weights_of).collect()
        } else {
            use rayon::prelude::*;
            (0..triangles.len())
                .into_par_iter()
                .map(weights_of)
                .collect()
        };
        let mut entries: Vec<(u32, f64)> = vec![(0, 0.0); fill[n] as usize];
        let mut cursor = fill.clone();
        for (t, w) in triangles.iter().zip(&tri_weights) {
            for j in 0..3 {
                let (a, b) = (t[j], t[(j + 1) % 3]);
                for (row, col) in [(a, b), (b, a)] {
                    let c = &mut cursor[row as usize];
                    entries[*c as usize] = (col, w[j]);
                    *c += 1;
                }
            }
        }
        drop(tri_weights);
        // Each row by column (rows are independent: parallel on big meshes). The sort is stable,
        // so equal columns keep their triangle order and sum in the same order as before.
        {
            let mut rows: Vec<&mut [(u32, f64)]> = Vec::with_capacity(n);
            let mut rest: &mut [(u32, f64)] = &mut entries;
            for i in 0..n {
                let (row, tail) = rest.split_at_mut((fill[i + 1] - fill[i]) as usize);
                rows.push(row);
                rest = tail;
            }
            let sort = |row: &mut &mut [(u32, f64)]| row.sort_by_key(|e| e.0);
            if n < PARALLEL_ROWS {
                rows.iter_mut().for_each(sort);
            } else {
                use rayon::prelude::*;
                rows.par_iter_mut().for_each(sort);
            }
        }
        let mut row_start = Vec::with_capacity(n + 1);
        let mut col = Vec::with_capacity(n + entries.len() / 2);
        let mut val = Vec::with_capacity(col.capacity());
        row_start.push(0u32);
        for i in 0..n {
            let row = &entries[fill[i] as usize..fill[i + 1] as usize];
            let diag_at = val.len();
            col.push(i as u32);
            val.push(0.0);
            let mut diag = 0.0;
            let mut k = 0;
            while k < row.len() {
                let (c, mut w) = row[k];
                k += 1;
                // An interior edge appears twice (once per triangle); two terms add the same in
                // either order, so the sum is deterministic.
                while k < row.len() && row[k].0 == c {
                    w += row[k].1;
                    k += 1;
                }
                col.push(c);
                val.push(-w);
                diag += w;
            }
            val[diag_at] = diag;
            row_start.push(col.len() as u32);
        }
        SymmetricCsr {
            row_start,
            col,
            val,
        }
    }

    fn tetra_fan() -> (Vec<[u32; 3]>, Vec<DVec3>) {
        let p = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
        ];
        (vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]], p)
    }

    #[test]
    fn mass_sums_to_area_and_stiffness_is_symmetric_with_zero_row_sums() {
        let (m, p) = tetra_fan();
        let mass = lumped_mass(&m, &p);
        let area: f64 = m
            .iter()
            .map(|t| {
                0.5 * (p[t[1] as usize] - p[t[0] as usize])
                    .cross(p[t[2] as usize] - p[t[0] as usize])
                    .length()
            })
            .sum();
        assert!((mass.iter().sum::<f64>() - area).abs() < 1e-14);
        let l = cotangent_stiffness(&m, &p, None);
        for i in 0..l.n() {
            let (s, e) = (l.row_start[i] as usize, l.row_start[i + 1] as usize);
            assert_eq!(l.col[s] as usize, i);
            assert!(l.val[s..e].iter().sum::<f64>().abs() < 1e-14);
            for k in s + 1..e {
                let j = l.col[k] as usize;
                let back = (l.row_start[j] as usize..l.row_start[j + 1] as usize)
                    .find(|&q| l.col[q] as usize == i)
                    .unwrap();
                assert_eq!(l.val[k], l.val[back]);
            }
        }
        // Constants are in the kernel; a linear function's Dirichlet energy is |∇f|²·area on
        // a closed surface only through the boundary-free identity xᵀLx = Σ_T A_T |∇_T f|².
        let x: Vec<[f64; 1]> = p.iter().map(|q| [q.x]).collect();
        let mut lx = vec![[0.0]; 4];
        l.mul(&x, &mut lx);
        let energy: f64 = x.iter().zip(&lx).map(|(a, b)| a[0] * b[0]).sum();
        assert!(energy > 0.0);
    }

    #[test]
    fn face_coefficients_scale_the_stiffness() {
        let (m, p) = tetra_fan();
        let l1 = cotangent_stiffness(&m, &p, None);
        let l3 = cotangent_stiffness(&m, &p, Some(&[3.0; 4]));
        for (a, b) in l1.val.iter().zip(&l3.val) {
            assert!((3.0 * a - b).abs() < 1e-14);
        }
    }

    #[test]
    fn clamping_removes_negative_weights_and_keeps_zero_row_sums() {
        // An obtuse fan: the edge 0-1 is opposite two angles of about 150 degrees.
        let p = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.5, 0.1, 0.0),
            DVec3::new(0.5, -0.1, 0.0),
        ];
        let t = [[0, 1, 2], [1, 0, 3]];
        let mut l = cotangent_stiffness(&t, &p, None);
        assert!(l.val.iter().any(|&v| v > 0.0 && v != l.val[0]));
        assert_eq!(clamp_negative_weights(&mut l), 2);
        for i in 0..l.n() {
            let (s, e) = (l.row_start[i] as usize, l.row_start[i + 1] as usize);
            assert!(l.val[s + 1..e].iter().all(|&v| v <= 0.0));
            assert!(l.val[s..e].iter().sum::<f64>().abs() < 1e-14);
        }
    }

    #[test]
    fn zero_mass_rows_become_identity_rows() {
        let mass = [0.0, 1.0];
        let l = SymmetricCsr {
            row_start: vec![0, 1, 2],
            col: vec![0, 1],
            val: vec![0.0, 0.0],
        };
        let a = system_matrix(&mass, l, 2.0);
        assert_eq!(a.val, vec![1.0, 1.0]);
        assert_eq!(identity_rows(&mass), vec![true, false]);
    }

    #[test]
    fn shared_area_cotangents_match_the_per_corner_ones() {
        // Acute, obtuse, right, needle (clamped) and degenerate triangles.
        let tris = [
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.3, 0.8, 0.1]],
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 0.05, 0.0]],
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0]],
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 1e-7, 0.0]],
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
            [[0.2, -1.0, 3.0], [-0.7, 0.4, 2.5], [1.1, 0.9, -0.4]],
        ];
        for t in tris {
            let v = t.map(DVec3::from_array);
            let (w, area) = half_cotangents(v, 1.5);
            let exact = 0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length();
            let degenerate = is_degenerate(v[0], v[1], v[2], exact);
            assert_eq!(area, if degenerate { 0.0 } else { exact });
            for j in 0..3 {
                let o = v[(j + 2) % 3];
                let expect = if degenerate {
                    0.0
                } else {
                    0.75 * cotangent(v[j] - o, v[(j + 1) % 3] - o)
                };
                assert!(
                    (w[j] - expect).abs() <= 1e-12 * expect.abs().max(1.0),
                    "{t:?} corner {j}: {} vs {expect}",
                    w[j]
                );
            }
        }
    }

    #[test]
    fn parallel_assembly_matches_the_sequential_oracle_bit_for_bit() {
        // A jittered grid with degenerate, duplicated (non-manifold) and flipped triangles,
        // large enough to take the parallel paths, with and without face coefficients, on 1
        // and 3 threads.
        let k = 200;
        let (mut p, mut t) = crate::mesh::shapes::grid(k, |i, j| {
            let h = ((i * 7919 + j * 104_729) % 1000) as f64 / 1000.0;
            DVec3::new(i as f64 + 0.3 * h, j as f64 - 0.2 * h, h)
        });
        // Quad q's first triangle again, flipped, on every 37th diagonal: non-manifold edges.
        let flipped: Vec<[u32; 3]> = t
            .iter()
            .step_by(2)
            .enumerate()
            .filter(|(q, _)| (q % k + q / k) % 37 == 0)
            .map(|(_, f)| [f[0], f[2], f[1]])
            .collect();
        t.extend(flipped);
        p[5] = p[6]; // a zero-length edge: degenerate triangles
        let coef: Vec<f64> = (0..t.len()).map(|i| 0.5 + (i % 13) as f64 / 7.0).collect();
        let bits = |m: &SymmetricCsr| m.val.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        for c in [None, Some(&coef[..])] {
            let old = scatter_stiffness(&t, &p, c);
            let (mass, fused) = mass_and_stiffness(&t, &p, c);
            assert_eq!(bits(&fused), bits(&old));
            let mass_bits = |m: &[f64]| m.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(mass_bits(&mass), mass_bits(&lumped_mass(&t, &p)));
            for threads in [1, 3] {
                let new = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| cotangent_stiffness(&t, &p, c));
                assert_eq!(new.row_start, old.row_start);
                assert_eq!(new.col, old.col);
                assert_eq!(bits(&new), bits(&old));
            }
        }
    }
}
