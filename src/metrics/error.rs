//! Error metrics between a processed mesh M′ and a reference surface M (`docs/algorithms.md` §5,
//! after Ohtake–Belyaev–Seidel 2002 §4):
//!
//! ```text
//! E_v(M′) = sqrt( 1/(3 A(M′)) · Σ_{P′∈M′} A(P′) · dist(P′, M)² )
//! E_n(M′) = sqrt( 1/A(M′)     · Σ_{T′∈M′} A(T′) · ‖n(T) − n(T′)‖² )
//! ```
//!
//! A(P′) is the area of the triangles of M′ around P′ (so Σ A(P′) = 3 A(M′)), dist is the
//! exact distance to the closest triangle of M, and T is the triangle of M closest to the
//! centroid of T′. E_v is an area-weighted RMS distance in model units; E_n is dimensionless
//! (an RMS of unit-normal differences, at most 2).
//!
//! The symmetric Hausdorff distance reported next to them is **sampled**: it is
//! `max(h(M′→M), h(M→M′))` where `h(X→Y)` is the largest exact distance to the surface Y over
//! the vertices, edge midpoints and face centroids of X. It is therefore a lower bound of the
//! true Hausdorff distance; the gap is at most the distance between neighbouring samples
//! (about half an edge) and in practice far smaller for surfaces this close.
//!
//! Degenerate triangles of M (twice the area at most 1e-12 of the longest edge squared) are
//! left out of the closest-triangle queries: their normal is undefined, and they carry no
//! surface of their own. In E_v and E_n a triangle of M′ weighs by its area, so zero-area ones
//! count for nothing. Neither side's Hausdorff samples come from degenerate triangles, so a
//! mesh compared with a copy of itself that differs by rounding gives ~0 even where a
//! degenerate triangle stands alone. The M → M′ direction measures to all of M′'s triangles,
//! degenerate ones included.
//!
//! Queries run in parallel (rayon), but every per-element value lands in its own slot and the
//! sums and maxima are then folded sequentially in element order, so results are bit-for-bit
//! the same with any number of threads.

use super::distance::TriangleBvh;
use crate::mesh::Mesh;
use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;

/// Why two meshes cannot be compared.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum CompareError {
    /// The reference has no triangle with positive area, so it has no surface to measure to.
    #[error("the reference mesh has no triangle with positive area")]
    EmptyReference,
    /// The compared mesh has no area, so the area weights of E_v and E_n are undefined.
    #[error("the compared mesh has no triangle with positive area")]
    EmptyResult,
}

/// A triangle surface as flat arrays: positions and triangles indexing them.
#[derive(Clone, Copy, Debug)]
pub struct Surface<'a> {
    /// Vertex positions.
    pub positions: &'a [DVec3],
    /// Triangles (counter-clockwise seen from outside), indices into `positions`.
    pub triangles: &'a [[u32; 3]],
}

impl<'a> Surface<'a> {
    /// The surface of `positions` and `triangles`.
    pub fn new(positions: &'a [DVec3], triangles: &'a [[u32; 3]]) -> Self {
        Surface {
            positions,
            triangles,
        }
    }

    fn corners(&self, t: usize) -> [DVec3; 3] {
        self.triangles[t].map(|i| self.positions[i as usize])
    }

    /// Total area.
    pub fn area(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                crate::mesh::geometry::triangle_area(a, b, c)
            })
            .sum()
    }

    /// Mean length over the distinct edges (0 when there are none).
    pub fn mean_edge_length(&self) -> f64 {
        let edges = distinct_edges(self.triangles);
        if edges.is_empty() {
            return 0.0;
        }
        let sum: f64 = edges
            .iter()
            .map(|&(a, b)| self.positions[a as usize].distance(self.positions[b as usize]))
            .sum();
        sum / edges.len() as f64
    }

    /// Diagonal of the bounding box of the vertices that some triangle uses.
    pub fn bbox_diagonal(&self) -> f64 {
        let used = self
            .triangles
            .iter()
            .flat_map(|t| t.iter().map(|&i| self.positions[i as usize]));
        crate::mesh::BoundingBox::of(used).map_or(0.0, |b| b.diagonal())
    }
}

/// A reference surface prepared for repeated comparisons: the hierarchy over its
/// non-degenerate triangles with their unit normals, and its scales.
#[derive(Clone, Debug)]
pub struct Reference {
    bvh: TriangleBvh,
    normals: Vec<DVec3>,
    bbox_diagonal: f64,
    mean_edge_length: f64,
}

impl Reference {
    /// Prepares `surface` as the reference M.
    pub fn new(surface: Surface<'_>) -> Result<Reference, CompareError> {
        let mut corners = Vec::with_capacity(surface.triangles.len());
        let mut normals = Vec::with_capacity(surface.triangles.len());
        for t in 0..surface.triangles.len() {
            let [a, b, c] = surface.corners(t);
            if let Some(n) = surface_normal(a, b, c) {
                corners.push([a, b, c]);
                normals.push(n);
            }
        }
        if corners.is_empty() {
            return Err(CompareError::EmptyReference);
        }
        Ok(Reference {
            bvh: TriangleBvh::from_corners(corners),
            normals,
            bbox_diagonal: surface.bbox_diagonal(),
            mean_edge_length: surface.mean_edge_length(),
        })
    }

    /// Prepares a half-edge mesh as the reference.
    pub fn from_mesh(mesh: &Mesh) -> Result<Reference, CompareError> {
        let (p, t) = mesh.to_triangles();
        Reference::new(Surface::new(&p, &t))
    }

    /// Bounding-box diagonal of the reference.
    pub fn bbox_diagonal(&self) -> f64 {
        self.bbox_diagonal
    }

    /// Mean edge length L of the reference.
    pub fn mean_edge_length(&self) -> f64 {
        self.mean_edge_length
    }

    /// Exact distance from `p` to the reference surface.
    pub fn distance(&self, p: DVec3) -> f64 {
        self.bvh.distance(p)
    }

    /// E_v and E_n of `result` against this reference (no Hausdorff; cheaper, for sweeps).
    pub fn errors(&self, result: Surface<'_>) -> Result<(f64, f64), CompareError> {
        let area = result.area();
        if area.is_nan() || area <= 0.0 {
            return Err(CompareError::EmptyResult);
        }
        // Squared distance of every vertex; vertices no triangle uses get zero weight below.
        let d2: Vec<f64> = result
            .positions
            .par_iter()
            .map(|&p| self.bvh.closest(p).map_or(0.0, |c| c.distance_squared))
            .collect();
        let per_face: Vec<(f64, f64)> = (0..result.triangles.len())
            .into_par_iter()
            .map(|t| {
                let [a, b, c] = result.corners(t);
                let cross = (b - a).cross(c - a);
                let area = 0.5 * cross.length();
                if area == 0.0 {
                    return (0.0, 0.0);
                }
                let centroid = (a + b + c) / 3.0;
                let n_ref = self
                    .bvh
                    .closest(centroid)
                    .map_or(DVec3::ZERO, |c| self.normals[c.triangle]);
                // Normalised exactly as the reference normals, so identical triangles give exactly 0.
                let dn = (n_ref - cross.normalize_or_zero()).length_squared();
                let dv: f64 = result.triangles[t].iter().map(|&i| d2[i as usize]).sum();
                (area * dv, area * dn)
            })
            .collect();
        // Σ_P′ A(P′) d(P′)² = Σ_T′ A(T′) Σ_{P′∈T′} d(P′)²; folded in face order.
        let (sv, sn) = per_face
            .iter()
            .fold((0.0, 0.0), |(sv, sn), &(v, n)| (sv + v, sn + n));
        Ok(((sv / (3.0 * area)).sqrt(), (sn / area).sqrt()))
    }

    /// Largest distance from the samples of `surface` (vertices used by a triangle, edge
    /// midpoints, face centroids) to the reference: the one-sided sampled Hausdorff distance.
    pub(crate) fn one_sided_hausdorff(&self, surface: Surface<'_>) -> f64 {
        one_sided(&self.bvh, surface)
    }

    /// Compares `result` against this reference: E_v, E_n, the sampled symmetric Hausdorff
    /// distance, and each relative to the reference's scales.
    pub fn compare(
        &self,
        result: Surface<'_>,
        reference: Surface<'_>,
    ) -> Result<Comparison, CompareError> {
        let (e_v, e_n) = self.errors(result)?;
        let result_bvh = TriangleBvh::new(result.positions, result.triangles);
        let forward = self.one_sided_hausdorff(result);
        let backward = one_sided(&result_bvh, reference);
        let hausdorff = forward.max(backward);
        let diag = self.bbox_diagonal;
        let rel = |x: f64| if diag > 0.0 { x / diag } else { f64::NAN };
        let l = self.mean_edge_length;
        Ok(Comparison {
            e_v,
            e_n,
            hausdorff,
            hausdorff_result_to_reference: forward,
            hausdorff_reference_to_result: backward,
            e_v_rel: rel(e_v),
            e_n_rel: e_n,
            hausdorff_rel: rel(hausdorff),
            bbox_diagonal: diag,
            mean_edge_length: l,
            e_v_over_l: if l > 0.0 { e_v / l } else { f64::NAN },
        })
    }
}

/// The distinct undirected edges of `triangles` as `(smaller, larger)` vertex pairs, sorted.
fn distinct_edges(triangles: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let mut edges: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges
}

/// Twice-area below which a triangle counts as degenerate, relative to its longest edge
/// squared: far above rounding, so a triangle degenerate in one mesh and off by rounding in
/// its copy (a filtered or reloaded mesh) is treated alike in both.
const DEGENERATE_RATIO: f64 = 1e-12;

/// The unit normal of triangle `(a, b, c)`, or `None` when it is degenerate (twice its area at
/// most [`DEGENERATE_RATIO`] times its longest edge squared) or not finite.
fn surface_normal(a: DVec3, b: DVec3, c: DVec3) -> Option<DVec3> {
    let cross = (b - a).cross(c - a);
    let longest2 = (b - a)
        .length_squared()
        .max((c - b).length_squared())
        .max((a - c).length_squared());
    let double_area = cross.length();
    let sound = double_area > DEGENERATE_RATIO * longest2 && double_area.is_finite();
    // Normalised as `errors` normalises the compared triangles: identical ones give exactly 0.
    sound.then(|| cross.normalize_or_zero())
}

fn one_sided(target: &TriangleBvh, samples: Surface<'_>) -> f64 {
    // Samples come from the triangles a reference would keep (nonzero normal), so that both
    // sides measure the same surface: a zero-area triangle off by itself (a repaired sliver's
    // leftover) would otherwise be sampled on one side and missing on the other.
    let tris: Vec<[u32; 3]> = (0..samples.triangles.len())
        .filter(|&t| {
            let [a, b, c] = samples.corners(t);
            surface_normal(a, b, c).is_some()
        })
        .map(|t| samples.triangles[t])
        .collect();
    let tris = &tris[..];
    // Each sample once: the vertices some triangle uses, the midpoint of every distinct
    // edge, and every centroid (visiting them per face would query vertices six times).
    let mut used = vec![false; samples.positions.len()];
    for &i in tris.iter().flatten() {
        used[i as usize] = true;
    }
    let edges = distinct_edges(tris);
    let p = samples.positions;
    let points: Vec<DVec3> = (0..p.len())
        .filter(|&i| used[i])
        .map(|i| p[i])
        .chain(
            edges
                .iter()
                .map(|&(a, b)| (p[a as usize] + p[b as usize]) * 0.5),
        )
        .chain(tris.iter().map(|t| {
            let [a, b, c] = t.map(|i| p[i as usize]);
            (a + b + c) / 3.0
        }))
        .collect();
    let d2: Vec<f64> = points
        .par_iter()
        .map(|&q| {
            target
                .closest(q)
                .map_or(f64::INFINITY, |c| c.distance_squared)
        })
        .collect();
    d2.iter().copied().fold(0.0, f64::max).sqrt()
}

/// The result of [`compare`]. `*_rel` values are divided by the reference's bounding-box
/// diagonal; E_n is already dimensionless, so `e_n_rel` equals `e_n` (kept so every metric has
/// a `_rel` key).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Comparison {
    /// E_v: area-weighted RMS distance from the result's vertices to the reference surface.
    pub e_v: f64,
    /// E_n: area-weighted RMS of the normal difference to the closest reference triangle.
    pub e_n: f64,
    /// Sampled symmetric Hausdorff distance (see the module docs).
    pub hausdorff: f64,
    /// One side of `hausdorff`: result samples to the reference surface.
    pub hausdorff_result_to_reference: f64,
    /// The other side: reference samples to the result surface.
    pub hausdorff_reference_to_result: f64,
    /// E_v / bbox diagonal.
    pub e_v_rel: f64,
    /// Equal to `e_n` (dimensionless).
    pub e_n_rel: f64,
    /// Hausdorff / bbox diagonal.
    pub hausdorff_rel: f64,
    /// Bounding-box diagonal of the reference (vertices used by triangles).
    pub bbox_diagonal: f64,
    /// Mean edge length L of the reference.
    pub mean_edge_length: f64,
    /// E_v / L.
    pub e_v_over_l: f64,
}

/// Compares `result` (M′) against `reference` (M); see the module docs for the definitions.
pub fn compare(result: &Mesh, reference: &Mesh) -> Result<Comparison, CompareError> {
    let (rp, rt) = result.to_triangles();
    let (mp, mt) = reference.to_triangles();
    let reference_surface = Surface::new(&mp, &mt);
    Reference::new(reference_surface)?.compare(Surface::new(&rp, &rt), reference_surface)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An n×n grid of the unit square at height z, two triangles per cell.
    fn grid(n: usize, z: f64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        crate::mesh::shapes::grid(n, |i, j| {
            DVec3::new(i as f64 / n as f64, j as f64 / n as f64, z)
        })
    }

    #[test]
    fn identical_meshes_have_zero_error() {
        let (p, t) = grid(6, 0.0);
        let s = Surface::new(&p, &t);
        let c = Reference::new(s).unwrap().compare(s, s).unwrap();
        assert_eq!(c.e_v, 0.0);
        assert_eq!(c.e_n, 0.0);
        // Centroids and midpoints are reconstructed from barycentric coordinates: rounding only.
        assert!(c.hausdorff < 1e-15, "{}", c.hausdorff);
        // 2·6·7 axis edges of length 1/6 and 36 diagonals of length √2/6.
        let mean = (84.0 + 36.0 * 2f64.sqrt()) / 6.0 / 120.0;
        assert!((c.mean_edge_length - mean).abs() < 1e-15);
    }

    #[test]
    fn offset_plane_gives_the_offset() {
        let (p, t) = grid(4, 0.0);
        // A different tessellation inside the reference's footprint, lifted by 0.03.
        let (mut q, u) = grid(7, 0.03);
        for x in &mut q {
            x.x = 0.1 + 0.8 * x.x;
            x.y = 0.1 + 0.8 * x.y;
        }
        let r = Reference::new(Surface::new(&p, &t)).unwrap();
        let c = r
            .compare(Surface::new(&q, &u), Surface::new(&p, &t))
            .unwrap();
        assert!((c.e_v - 0.03).abs() < 1e-15, "{}", c.e_v);
        assert_eq!(c.e_n, 0.0);
        assert!((c.hausdorff_result_to_reference - 0.03).abs() < 1e-15);
        // The reference reaches 0.1 beyond the smaller patch: back distance √(0.1²·2+0.03²).
        let back = (0.02f64 + 0.0009).sqrt();
        assert!((c.hausdorff_reference_to_result - back).abs() < 1e-12);
        assert!((c.hausdorff - back).abs() < 1e-12);
        assert!((c.e_v_rel - 0.03 / 2f64.sqrt()).abs() < 1e-12);
        assert!((c.e_v_over_l - 0.03 / r.mean_edge_length()).abs() < 1e-15);
    }

    #[test]
    fn flipped_normals_and_tilt_give_the_normal_error() {
        let (p, t) = grid(3, 0.0);
        let flipped: Vec<[u32; 3]> = t.iter().map(|x| [x[0], x[2], x[1]]).collect();
        let r = Reference::new(Surface::new(&p, &t)).unwrap();
        let (_, e_n) = r.errors(Surface::new(&p, &flipped)).unwrap();
        assert!((e_n - 2.0).abs() < 1e-15);
        // Tilted by angle θ about the x axis: ‖n − n′‖ = 2 sin(θ/2) everywhere.
        let th = 0.2f64;
        let q: Vec<DVec3> = p
            .iter()
            .map(|x| DVec3::new(x.x, x.y * th.cos(), x.y * th.sin() * 0.01))
            .collect();
        let (_, e_n) = r.errors(Surface::new(&q, &t)).unwrap();
        let expect = 2.0 * ((th.sin() * 0.01 / th.cos()).atan() / 2.0).sin();
        assert!((e_n - expect).abs() < 1e-12, "{e_n} vs {expect}");
    }

    #[test]
    fn hausdorff_is_symmetric() {
        let (p, t) = grid(5, 0.0);
        let (mut q, u) = grid(3, 0.0);
        // A bump in the middle of the second mesh.
        for x in &mut q {
            if (x.x - 1.0 / 3.0).abs() < 1e-9 && (x.y - 1.0 / 3.0).abs() < 1e-9 {
                x.z = 0.25;
            }
        }
        let (a, b) = (Surface::new(&p, &t), Surface::new(&q, &u));
        let ab = Reference::new(b).unwrap().compare(a, b).unwrap();
        let ba = Reference::new(a).unwrap().compare(b, a).unwrap();
        assert_eq!(ab.hausdorff, ba.hausdorff);
        assert_eq!(
            ab.hausdorff_result_to_reference,
            ba.hausdorff_reference_to_result
        );
        // The bump's tip is a vertex of the second mesh, 0.25 above the plane.
        assert_eq!(ab.hausdorff, 0.25);
    }

    #[test]
    fn a_lone_degenerate_triangle_off_by_rounding_does_not_count() {
        // A grid plus a separate triangle with two corners snapped together (2 → 1 unit away);
        // its copy has them 1e-15 apart, as after a filter with unit gains.
        let (mut p, mut t) = grid(3, 0.0);
        let n = p.len() as u32;
        p.extend([DVec3::new(3.0, 0.0, 0.0), DVec3::new(4.0, 0.0, 0.0)]);
        p.push(p[n as usize + 1]);
        t.push([n, n + 1, n + 2]);
        let mut q = p.clone();
        q[n as usize + 2].y += 1e-15;
        let (a, b) = (Surface::new(&p, &t), Surface::new(&q, &t));
        for (x, y) in [(a, b), (b, a)] {
            let c = Reference::new(y).unwrap().compare(x, y).unwrap();
            assert!(c.hausdorff < 1e-12, "{c:?}");
        }
    }

    #[test]
    fn empty_inputs_are_errors() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::X * 2.0];
        let t = vec![[0, 1, 2]];
        assert_eq!(
            Reference::new(Surface::new(&p, &t)).unwrap_err(),
            CompareError::EmptyReference
        );
        let (g, gt) = grid(2, 0.0);
        let r = Reference::new(Surface::new(&g, &gt)).unwrap();
        assert_eq!(
            r.errors(Surface::new(&p, &t)).unwrap_err(),
            CompareError::EmptyResult
        );
    }

    #[test]
    fn mesh_entry_point_agrees_with_flat_arrays() {
        let (p, t) = grid(4, 0.0);
        let (q, u) = grid(4, 0.01);
        let a = Mesh::from_triangles(&q, &u).unwrap().mesh;
        let b = Mesh::from_triangles(&p, &t).unwrap().mesh;
        let c = compare(&a, &b).unwrap();
        assert!((c.e_v - 0.01).abs() < 1e-15);
        assert!((c.hausdorff - 0.01).abs() < 1e-15);
    }
}
