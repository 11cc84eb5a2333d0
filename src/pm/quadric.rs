//! Area-weighted plane quadrics (Garland–Heckbert), stored as 10 sums plus the total weight.
//!
//! `Q = Σ w·[n; d][n; d]ᵀ` for planes `n·x + d = 0`. The error of a position is the weighted
//! sum of squared plane distances divided by the total face weight, i.e. a mean squared
//! distance in length² — the same normalisation meshoptimizer uses, so thresholds are
//! distances and do not scale with the mesh resolution.
//!
//! Each vertex also carries a small point quadric ([`POINT_REGULARISATION`]) that makes moving
//! it cost a little in every direction, not only off its planes.

use glam::DVec3;

/// Weight of the point quadric `|x - p|²` each vertex gets, relative to its face weight, so that
/// its normalised error grows by `POINT_REGULARISATION · |x - p|²` (scale-free: a fraction of the
/// squared distance moved). Without it every collapse inside a planar region costs exactly 0 and
/// the order among them is the arbitrary slot order: flat parts of CAD models and the staircases of
/// marching-cubes meshes then collapse into long slivers, and the area-normalised error later
/// underrates collapses that drag such a sliver's vertex across a crease (Hausdorff errors of
/// several times meshoptimizer's on fandisk). With it ties go to the shortest edges, keeping the
/// triangles compact. Merged vertices sum their point quadrics, so the term also measures how far
/// a survivor is from the vertices it absorbed. meshoptimizer's `fillVertexQuadrics` does the same
/// with a weight of 1e-7, which in its single-precision unit-cube coordinates is already above the
/// rounding noise of flat regions; in double precision a smaller weight only breaks exact ties, and
/// this larger one measured better overall (it costs a little on smooth meshes at 1 %).
pub(crate) const POINT_REGULARISATION: f64 = 1e-4;

/// A symmetric 4×4 quadric: `xᵀAx + 2bᵀx + c`, plus the summed face weight it was built from.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Quadric {
    /// Upper triangle of A: a00, a01, a02, a11, a12, a22.
    pub a: [f64; 6],
    /// The linear part b.
    pub b: [f64; 3],
    /// The constant c.
    pub c: f64,
    /// Sum of the face weights (areas) that contributed; boundary constraint planes add 0.
    pub weight: f64,
}

impl Quadric {
    /// The quadric of the plane through `point` with unit normal `n`, scaled by `scale`, counting
    /// `weight` towards the normalisation.
    pub(crate) fn from_plane(n: DVec3, point: DVec3, scale: f64, weight: f64) -> Quadric {
        let d = -n.dot(point);
        Quadric {
            a: [
                scale * n.x * n.x,
                scale * n.x * n.y,
                scale * n.x * n.z,
                scale * n.y * n.y,
                scale * n.y * n.z,
                scale * n.z * n.z,
            ],
            b: [scale * n.x * d, scale * n.y * d, scale * n.z * d],
            c: scale * d * d,
            weight,
        }
    }

    /// The area-weighted plane quadric of the triangle `(pa, pb, pc)` (counting its area towards
    /// the normalisation), or `None` for a zero-area or non-finite triangle, which has no plane.
    #[inline]
    pub(crate) fn of_triangle(pa: DVec3, pb: DVec3, pc: DVec3) -> Option<Quadric> {
        let nrm = (pb - pa).cross(pc - pa);
        let len = nrm.length();
        if len.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) || !len.is_finite() {
            return None;
        }
        let area = 0.5 * len;
        Some(Quadric::from_plane(nrm / len, pa, area, area))
    }

    /// The point quadric `scale·|x - p|²`, counting nothing towards the normalisation (a
    /// regulariser, not a face).
    pub(crate) fn from_point(p: DVec3, scale: f64) -> Quadric {
        Quadric {
            a: [scale, 0.0, 0.0, scale, 0.0, scale],
            b: [-scale * p.x, -scale * p.y, -scale * p.z],
            c: scale * p.length_squared(),
            weight: 0.0,
        }
    }

    /// Componentwise sum.
    #[inline]
    pub(crate) fn add(&mut self, o: &Quadric) {
        for k in 0..6 {
            self.a[k] += o.a[k];
        }
        for k in 0..3 {
            self.b[k] += o.b[k];
        }
        self.c += o.c;
        self.weight += o.weight;
    }

    /// The sum of two quadrics.
    #[inline]
    pub(crate) fn sum(&self, o: &Quadric) -> Quadric {
        let mut q = *self;
        q.add(o);
        q
    }

    /// `xᵀAx + 2bᵀx + c`: the weighted sum of squared plane distances (length⁴ with area weights).
    #[inline]
    pub(crate) fn raw(&self, p: DVec3) -> f64 {
        let a = &self.a;
        let (x, y, z) = (p.x, p.y, p.z);
        x * (a[0] * x + 2.0 * (a[1] * y + a[2] * z + self.b[0]))
            + y * (a[3] * y + 2.0 * (a[4] * z + self.b[1]))
            + z * (a[5] * z + 2.0 * self.b[2])
            + self.c
    }

    /// The normalised error at `p`: [`Quadric::raw`] divided by the face weight (a mean squared
    /// distance, length²). Never negative or NaN for finite input.
    #[inline]
    pub(crate) fn error(&self, p: DVec3) -> f64 {
        let r = self.raw(p).max(0.0);
        let e = if self.weight > 0.0 {
            r / self.weight
        } else {
            r
        };
        if e.is_nan() { f64::MAX } else { e }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_quadric_measures_squared_distance() {
        let n = DVec3::new(1.0, 2.0, 2.0).normalize();
        let q = Quadric::from_plane(n, DVec3::new(1.0, 0.0, 0.0), 2.0, 2.0);
        let p = DVec3::new(0.3, -1.0, 4.0);
        let dist = n.dot(p - DVec3::new(1.0, 0.0, 0.0));
        assert!((q.raw(p) - 2.0 * dist * dist).abs() < 1e-12);
        assert!((q.error(p) - dist * dist).abs() < 1e-12);
        assert!(q.error(DVec3::new(1.0, 0.0, 0.0)).abs() < 1e-15);
    }

    #[test]
    fn sums_add_errors() {
        let q1 = Quadric::from_plane(DVec3::X, DVec3::ZERO, 1.0, 1.0);
        let q2 = Quadric::from_plane(DVec3::Y, DVec3::ZERO, 3.0, 3.0);
        let p = DVec3::new(1.0, 1.0, 5.0);
        let s = q1.sum(&q2);
        assert!((s.raw(p) - (q1.raw(p) + q2.raw(p))).abs() < 1e-12);
        assert!((s.error(p) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn point_quadric_measures_squared_distance_without_weight() {
        let c = DVec3::new(1.0, -2.0, 0.5);
        let q = Quadric::from_point(c, 3.0);
        assert_eq!(q.weight, 0.0);
        let p = DVec3::new(0.0, 1.0, 2.5);
        assert!((q.raw(p) - 3.0 * (p - c).length_squared()).abs() < 1e-12);
        assert!(q.raw(c).abs() < 1e-12);
    }
}
