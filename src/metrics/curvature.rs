//! Discrete curvature operators and the statistics used to compare subdivision schemes.
//!
//! Per interior vertex i, with barycentric area `A_i = Σ_{T∋i} A(T)/3`, cotangent weights
//! `w_ij = ½(cot θ_ij + cot θ'_ij)` and the area-weighted normal `n_i`:
//!
//! ```text
//! H_i = (Σ_j w_ij (x_i − x_j)) · n_i / (2 A_i)     mean curvature, (κ1+κ2)/2, > 0 on a sphere
//! K_i = (2π − Σ_{T∋i} θ_i^T) / A_i                  Gauss curvature (angle defect)
//! ```
//!
//! Boundary and isolated vertices get NaN: both formulas need a closed fan.
//! The statistics make the curvatures dimensionless with the radius of the sphere of the same
//! total area, `R = √(area/4π)`, so meshes of different size (for example a shrunken MCM
//! surface and a Loop surface) compare fairly.

use crate::mesh::{Mesh, SlotIndex, VertexId};
use glam::DVec3;
use std::collections::VecDeque;

fn slot_len(mesh: &Mesh) -> usize {
    mesh.vertices().map(|v| v.slot() + 1).max().unwrap_or(0)
}

fn barycentric_area(mesh: &Mesh, v: VertexId) -> f64 {
    mesh.vertex_faces(v)
        .iter()
        .map(|&f| mesh.face_area(f) / 3.0)
        .sum()
}

/// Discrete mean curvature per vertex slot (NaN on boundary, isolated or zero-area vertices).
pub(crate) fn mean_curvature(mesh: &Mesh) -> Vec<f64> {
    let mut out = vec![f64::NAN; slot_len(mesh)];
    for v in mesh.vertices() {
        if mesh.is_boundary_vertex(v) {
            continue;
        }
        let p = mesh.position(v);
        let lap: DVec3 = mesh
            .outgoing(v)
            .map(|h| mesh.cotangent_weight(h) * (p - mesh.position(mesh.to_vertex(h))))
            .sum();
        let area = barycentric_area(mesh, v);
        if area > 0.0 {
            out[v.slot()] = lap.dot(mesh.vertex_normal(v)) / (2.0 * area);
        }
    }
    out
}

/// Discrete Gauss curvature (angle defect over barycentric area) per vertex slot (NaN on
/// boundary, isolated or zero-area vertices).
pub fn gauss_curvature(mesh: &Mesh) -> Vec<f64> {
    let mut out = vec![f64::NAN; slot_len(mesh)];
    for v in mesh.vertices() {
        if mesh.is_boundary_vertex(v) {
            continue;
        }
        let p = mesh.position(v);
        let angle_sum: f64 = mesh
            .outgoing(v)
            .map(|h| {
                let a = mesh.position(mesh.to_vertex(h)) - p;
                let b = mesh.position(mesh.to_vertex(mesh.next(h))) - p;
                a.cross(b).length().atan2(a.dot(b))
            })
            .sum();
        let area = barycentric_area(mesh, v);
        if area > 0.0 {
            out[v.slot()] = (2.0 * std::f64::consts::PI - angle_sum) / area;
        }
    }
    out
}

/// Radius of the sphere with the mesh's total area, the length scale of the statistics.
pub(crate) fn equal_area_radius(mesh: &Mesh) -> f64 {
    let area: f64 = mesh.faces().map(|f| mesh.face_area(f)).sum();
    (area / (4.0 * std::f64::consts::PI)).sqrt()
}

/// Curvature statistics of a whole mesh (interior vertices only), dimensionless.
#[derive(Clone, Debug, PartialEq)]
pub struct CurvatureStats {
    /// Area-weighted mean of `H·R`.
    pub mean_curvature_mean: f64,
    /// Area-weighted variance of `H·R`.
    pub mean_curvature_variance: f64,
    /// Area-weighted RMS of `(H_i − mean_{j~i} H_j)·R` over vertices whose neighbours all have
    /// a curvature: the high-frequency part of H (oscillation), insensitive to the global
    /// shape that the variance also measures.
    pub mean_curvature_roughness: f64,
    /// Largest `|K|·R²`.
    pub gauss_curvature_max_abs: f64,
    /// Number of vertices that entered the statistics.
    pub vertices: usize,
}

/// Computes [`CurvatureStats`]. Returns all-zero statistics for a mesh without interior
/// vertices.
pub fn curvature_stats(mesh: &Mesh) -> CurvatureStats {
    let r = equal_area_radius(mesh);
    let h = mean_curvature(mesh);
    let k = gauss_curvature(mesh);
    let (mut wsum, mut hsum) = (0.0, 0.0);
    let mut items = Vec::new();
    for v in mesh.vertices() {
        let hv = h[v.slot()];
        if hv.is_finite() {
            let a = barycentric_area(mesh, v);
            wsum += a;
            hsum += a * hv * r;
            items.push((v, a));
        }
    }
    if wsum <= 0.0 {
        return CurvatureStats {
            mean_curvature_mean: 0.0,
            mean_curvature_variance: 0.0,
            mean_curvature_roughness: 0.0,
            gauss_curvature_max_abs: 0.0,
            vertices: 0,
        };
    }
    let mean = hsum / wsum;
    let var = items
        .iter()
        .map(|&(v, a)| a * (h[v.slot()] * r - mean).powi(2))
        .sum::<f64>()
        / wsum;
    let (mut rw, mut rsum) = (0.0, 0.0);
    for &(v, a) in &items {
        let nb: Vec<f64> = mesh
            .neighbors(v)
            .iter()
            .map(|u| h[u.slot()])
            .collect::<Vec<_>>();
        if nb.is_empty() || nb.iter().any(|x| !x.is_finite()) {
            continue;
        }
        let avg = nb.iter().sum::<f64>() / nb.len() as f64;
        rw += a;
        rsum += a * ((h[v.slot()] - avg) * r).powi(2);
    }
    let kmax = items
        .iter()
        .map(|&(v, _)| (k[v.slot()] * r * r).abs())
        .filter(|x| x.is_finite())
        .fold(0.0, f64::max);
    CurvatureStats {
        mean_curvature_mean: mean,
        mean_curvature_variance: var,
        mean_curvature_roughness: if rw > 0.0 { (rsum / rw).sqrt() } else { 0.0 },
        gauss_curvature_max_abs: kmax,
        vertices: items.len(),
    }
}

/// Gauss-curvature sign behaviour in the vertex rings around chosen centres.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RingSignStats {
    /// Rings examined (centres × rings per centre, rings with a boundary or NaN skipped).
    pub rings: usize,
    /// Rings holding both clearly positive and clearly negative K ("hybrid" rings, the
    /// defect shown in Peters–Karčiauskas' Fig. 2(d)).
    pub hybrid_rings: usize,
    /// Sign changes counted cyclically around the rings, summed.
    pub sign_changes: usize,
}

/// Walks rings 1..=`rings` (graph distance) around each centre, orders each ring by angle
/// in the centre's tangent plane and counts sign changes of `gauss[slot]` cyclically.
/// Values with `|K|·R² ≤ zero_tolerance` are treated as zero and skipped (flat spots are not
/// oscillation).
pub fn ring_sign_changes(
    mesh: &Mesh,
    gauss: &[f64],
    centres: &[VertexId],
    rings: usize,
    zero_tolerance: f64,
) -> RingSignStats {
    let r = equal_area_radius(mesh);
    let mut stats = RingSignStats::default();
    let mut dist = vec![usize::MAX; slot_len(mesh)];
    for &c in centres {
        // BFS to distance `rings`.
        let mut seen: Vec<VertexId> = vec![c];
        dist[c.slot()] = 0;
        let mut queue = VecDeque::from([c]);
        let mut by_ring: Vec<Vec<VertexId>> = vec![Vec::new(); rings + 1];
        while let Some(v) = queue.pop_front() {
            let d = dist[v.slot()];
            if d == rings {
                continue;
            }
            for u in mesh.neighbors(v) {
                if dist[u.slot()] == usize::MAX {
                    dist[u.slot()] = d + 1;
                    seen.push(u);
                    by_ring[d + 1].push(u);
                    queue.push_back(u);
                }
            }
        }
        let n = mesh.vertex_normal(c);
        let p = mesh.position(c);
        let t1 = n.any_orthonormal_vector();
        let t2 = n.cross(t1);
        for ring in by_ring.iter().skip(1) {
            let values: Option<Vec<(f64, f64)>> = ring
                .iter()
                .map(|&u| {
                    let k = gauss[u.slot()];
                    let d = mesh.position(u) - p;
                    k.is_finite()
                        .then(|| (d.dot(t2).atan2(d.dot(t1)), k * r * r))
                })
                .collect();
            let Some(mut values) = values else { continue };
            if values.is_empty() {
                continue;
            }
            values.sort_by(|a, b| a.0.total_cmp(&b.0));
            let signs: Vec<bool> = values
                .iter()
                .filter(|(_, k)| k.abs() > zero_tolerance)
                .map(|&(_, k)| k > 0.0)
                .collect();
            stats.rings += 1;
            if signs.is_empty() {
                continue;
            }
            let changes = (0..signs.len())
                .filter(|&i| signs[i] != signs[(i + 1) % signs.len()])
                .count();
            stats.sign_changes += changes;
            if changes > 0 {
                stats.hybrid_rings += 1;
            }
        }
        for v in seen {
            dist[v.slot()] = usize::MAX;
        }
    }
    stats
}

#[cfg(test)]
mod tests {
    use super::*;

    fn icosphere(levels: usize) -> Mesh {
        let (p, f) = crate::mesh::shapes::icosphere(levels);
        Mesh::from_triangles(&p, &f).unwrap().mesh
    }

    #[test]
    fn unit_sphere_has_unit_curvatures_and_gauss_bonnet_holds() {
        let m = icosphere(3);
        let h = mean_curvature(&m);
        let k = gauss_curvature(&m);
        for v in m.vertices() {
            assert!((h[v.slot()] - 1.0).abs() < 0.2, "{}", h[v.slot()]);
            // Barycentric areas are only first-order accurate on the uneven icosphere.
            assert!((k[v.slot()] - 1.0).abs() < 0.2, "{}", k[v.slot()]);
        }
        // Σ K_i A_i = 2πχ exactly for the angle defect.
        let total: f64 = m
            .vertices()
            .map(|v| k[v.slot()] * barycentric_area(&m, v))
            .sum();
        assert!((total - 4.0 * std::f64::consts::PI).abs() < 1e-9);
        let s = curvature_stats(&m);
        assert!((s.mean_curvature_mean - 1.0).abs() < 0.02);
        assert!(s.mean_curvature_variance < 1e-3);
        let r = ring_sign_changes(&m, &k, &[m.vertices().next().unwrap()], 3, 1e-2);
        assert_eq!(r.rings, 3);
        assert_eq!(r.sign_changes, 0);
    }

    #[test]
    fn a_saddle_ring_is_hybrid_and_boundaries_give_nan() {
        // Monkey-saddle-like bumps: z alternates around a ring of 6.
        let mut p = vec![DVec3::ZERO];
        for i in 0..6 {
            let a = i as f64 * std::f64::consts::PI / 3.0;
            p.push(DVec3::new(
                a.cos(),
                a.sin(),
                if i % 2 == 0 { 0.3 } else { -0.3 },
            ));
        }
        let t: Vec<[u32; 3]> = (0..6).map(|i| [0, 1 + i, 1 + (i + 1) % 6]).collect();
        let m = Mesh::from_triangles(&p, &t).unwrap().mesh;
        let k = gauss_curvature(&m);
        assert!(k[0] < 0.0);
        assert!(k[1].is_nan());
        assert!(mean_curvature(&m)[1].is_nan());
    }
}
