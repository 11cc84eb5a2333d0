//! The distance field: one unsigned distance per vertex of a result to a reference surface,
//! for the pictures and tools that want to see where a mesh moved, not only how far at most.

use super::error::Reference;
use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;

/// The exact unsigned distance from each of `positions` to `reference`'s surface, in model
/// units, in the order of `positions` (pass a [`PolygonMesh`](crate::PolygonMesh)'s
/// `positions` to get its file's vertex order, unreferenced vertices included). A non-finite
/// position gives NaN. Computed in parallel, but each value depends on its point alone, so the
/// result is the same for every thread count.
pub fn vertex_distances(positions: &[DVec3], reference: &Reference) -> Vec<f64> {
    positions
        .par_iter()
        .map(|&p| {
            if p.is_finite() {
                reference.distance(p)
            } else {
                f64::NAN
            }
        })
        .collect()
}

/// Percentiles of a distance field.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FieldPercentiles {
    /// Median.
    pub p50: f64,
    /// 90th percentile.
    pub p90: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Largest value.
    pub max: f64,
}

impl FieldPercentiles {
    /// The nearest-rank percentiles of the finite `values` (the smallest value with at least
    /// p % of the values at or below it); `None` when no value is finite.
    pub fn of(values: &[f64]) -> Option<FieldPercentiles> {
        let mut sorted: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
        if sorted.is_empty() {
            return None;
        }
        sorted.sort_by(f64::total_cmp);
        let rank = |p: f64| {
            let k = (p / 100.0 * sorted.len() as f64).ceil() as usize;
            sorted[k.clamp(1, sorted.len()) - 1]
        };
        Some(FieldPercentiles {
            p50: rank(50.0),
            p90: rank(90.0),
            p99: rank(99.0),
            max: sorted[sorted.len() - 1],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::Surface;
    use crate::metrics::distance::point_triangle_distance_squared;

    /// A bumpy 5×5 grid: irregular enough that nearest triangles differ from point to point.
    fn bumpy_grid() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        crate::mesh::shapes::grid(5, |i, j| {
            let (x, y) = (i as f64 / 5.0, j as f64 / 5.0);
            DVec3::new(x, y, 0.1 * (7.0 * x).sin() * (5.0 * y).cos())
        })
    }

    #[test]
    fn field_equals_brute_force_distances_in_input_order() {
        let (p, t) = bumpy_grid();
        let reference = Reference::new(Surface::new(&p, &t)).unwrap();
        // Points around, above, below and on the surface, in a scrambled order.
        let queries: Vec<DVec3> = (0..200)
            .map(|k| {
                let f = k as f64;
                DVec3::new(
                    (f * 0.618).fract() * 1.6 - 0.3,
                    (f * 0.414).fract() * 1.6 - 0.3,
                    (f * 0.732).fract() * 0.8 - 0.4,
                )
            })
            .chain(p.iter().copied())
            .collect();
        let field = vertex_distances(&queries, &reference);
        assert_eq!(field.len(), queries.len());
        for (q, d) in queries.iter().zip(&field) {
            let brute = t
                .iter()
                .map(|tri| {
                    let [a, b, c] = tri.map(|i| p[i as usize]);
                    point_triangle_distance_squared(*q, a, b, c)
                })
                .fold(f64::INFINITY, f64::min)
                .sqrt();
            assert!((d - brute).abs() <= 1e-12, "{q}: {d} vs {brute}");
        }
        // The reference's own vertices lie on it.
        assert!(field[200..].iter().all(|&d| d < 1e-12));
    }

    #[test]
    fn non_finite_points_give_nan() {
        let (p, t) = bumpy_grid();
        let reference = Reference::new(Surface::new(&p, &t)).unwrap();
        let field = vertex_distances(&[DVec3::NAN, DVec3::ZERO], &reference);
        assert!(field[0].is_nan() && field[1].is_finite());
    }

    #[test]
    fn percentiles_are_nearest_rank_over_finite_values() {
        let values: Vec<f64> = (1..=200).rev().map(f64::from).chain([f64::NAN]).collect();
        let p = FieldPercentiles::of(&values).unwrap();
        assert_eq!((p.p50, p.p90, p.p99, p.max), (100.0, 180.0, 198.0, 200.0));
        assert_eq!(FieldPercentiles::of(&[f64::NAN]), None);
        let one = FieldPercentiles::of(&[0.5]).unwrap();
        assert_eq!((one.p50, one.max), (0.5, 0.5));
    }
}
