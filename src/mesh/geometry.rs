//! Geometric quantities on a [`Mesh`]: normals, areas, angles, cotangent weights, bounds.

use super::halfedge::{FaceId, HalfedgeId, Mesh, VertexId};
use glam::DVec3;

/// Axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundingBox {
    /// Smallest corner.
    pub min: DVec3,
    /// Largest corner.
    pub max: DVec3,
}

impl BoundingBox {
    /// The box around `points`; `None` when there are none.
    pub fn of(points: impl IntoIterator<Item = DVec3>) -> Option<BoundingBox> {
        let mut it = points.into_iter();
        let first = it.next()?;
        let (min, max) = it.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p)));
        Some(BoundingBox { min, max })
    }

    /// The smallest box holding this one and `p`.
    pub(crate) fn including(self, p: DVec3) -> BoundingBox {
        BoundingBox {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// The longest side.
    pub fn max_side(&self) -> f64 {
        (self.max - self.min).max_element()
    }

    /// Length of the diagonal; the scale all relative tolerances refer to.
    pub fn diagonal(&self) -> f64 {
        (self.max - self.min).length()
    }

    /// The centre. Algorithms whose arithmetic cancels large coordinates (plane quadrics,
    /// energies of tiny differences) run relative to it, so that a scan far from the origin
    /// keeps its digits.
    pub fn centre(&self) -> DVec3 {
        0.5 * (self.min + self.max)
    }
}

/// Morton (Z-order) codes of `points` in their bounding cube, 21 bits per axis: points near in
/// space mostly get near codes, so sorting by code lays out nearby items near in memory.
/// The cube is that of the finite points; others get code 0. `None` when there are no finite
/// points or their extent is zero (no order helps then).
pub(crate) fn morton_codes(points: &[DVec3]) -> Option<Vec<u64>> {
    let b = BoundingBox::of(points.iter().copied().filter(|p| p.is_finite()))?;
    let extent = (b.max - b.min).max_element();
    if !(extent > 0.0 && extent.is_finite()) {
        return None;
    }
    let scale = ((1u64 << 21) - 1) as f64 / extent;
    Some(
        points
            .iter()
            .map(|&p| {
                // NaN clamps to NaN, which `as` turns into 0; infinities clamp.
                let q = ((p - b.min) * scale)
                    .to_array()
                    .map(|x| x.clamp(0.0, 2097151.0) as u64);
                spread3(q[0]) | spread3(q[1]) << 1 | spread3(q[2]) << 2
            })
            .collect(),
    )
}

/// Spreads the low 21 bits of `x` to every third bit (Morton interleaving).
fn spread3(x: u64) -> u64 {
    let mut x = x & 0x1f_ffff;
    x = (x | x << 32) & 0x1f_0000_0000_ffff;
    x = (x | x << 16) & 0x1f_0000_ff00_00ff;
    x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
    x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
    x = (x | x << 2) & 0x1249_2492_4924_9249;
    x
}

/// Area of the triangle `(a, b, c)`: half the length of `(b − a) × (c − a)`. Every area in the
/// crate goes through here, so a mesh's area is the same bits whichever module sums it.
#[inline]
pub(crate) fn triangle_area(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    0.5 * (b - a).cross(c - a).length()
}

/// Cotangent of the angle between `a` and `b`, clamped so that needle triangles do not give
/// infinite weights.
#[inline]
pub fn cotangent(a: DVec3, b: DVec3) -> f64 {
    let sin = a.cross(b).length();
    let cos = a.dot(b);
    const MAX_COT: f64 = 1e5;
    if sin <= cos.abs() / MAX_COT {
        return if cos >= 0.0 { MAX_COT } else { -MAX_COT };
    }
    cos / sin
}

impl Mesh {
    /// Bounding box of all vertices (isolated ones included); `None` for an empty mesh.
    pub fn bounding_box(&self) -> Option<BoundingBox> {
        BoundingBox::of(self.vertices.values().map(|r| r.position))
    }

    /// Diagonal of the bounding box (0 for an empty mesh).
    pub fn bbox_diagonal(&self) -> f64 {
        self.bounding_box().map_or(0.0, |b| b.diagonal())
    }

    /// Unnormalised face normal: twice the area times the unit normal.
    #[inline]
    pub(crate) fn face_area_normal(&self, f: FaceId) -> DVec3 {
        let [a, b, c] = self.face_positions(f);
        (b - a).cross(c - a)
    }

    /// Unit face normal (zero for a degenerate face).
    #[inline]
    pub fn face_normal(&self, f: FaceId) -> DVec3 {
        self.face_area_normal(f).normalize_or_zero()
    }

    /// Face area.
    #[inline]
    pub(crate) fn face_area(&self, f: FaceId) -> f64 {
        let [a, b, c] = self.face_positions(f);
        triangle_area(a, b, c)
    }

    /// Area-weighted vertex normal (zero for an isolated vertex or a flat-degenerate fan).
    pub fn vertex_normal(&self, v: VertexId) -> DVec3 {
        self.outgoing(v)
            .filter_map(|h| self.face(h))
            .map(|f| self.face_area_normal(f))
            .sum::<DVec3>()
            .normalize_or_zero()
    }

    /// Vector from the origin of `h` to its head.
    #[inline]
    pub(crate) fn edge_vector(&self, h: HalfedgeId) -> DVec3 {
        self.position(self.to_vertex(h)) - self.position(self.from_vertex(h))
    }

    /// Length of the edge of `h`.
    #[inline]
    pub(crate) fn edge_length(&self, h: HalfedgeId) -> f64 {
        self.edge_vector(h).length()
    }

    /// Mean length over all edges (0 when there are none).
    pub fn mean_edge_length(&self) -> f64 {
        let (sum, n) = self
            .edges()
            .fold((0.0, 0usize), |(s, n), h| (s + self.edge_length(h), n + 1));
        if n == 0 { 0.0 } else { sum / n as f64 }
    }

    /// Cotangent of the angle opposite `h` in its face (0 on a boundary half-edge).
    pub(crate) fn opposite_cotangent(&self, h: HalfedgeId) -> f64 {
        if self.is_boundary_halfedge(h) {
            return 0.0;
        }
        let o = self.position(self.to_vertex(self.next(h)));
        let a = self.position(self.from_vertex(h));
        let b = self.position(self.to_vertex(h));
        cotangent(a - o, b - o)
    }

    /// The cotangent weight of an edge, `(cot α + cot β) / 2` over its two opposite angles.
    pub(crate) fn cotangent_weight(&self, h: HalfedgeId) -> f64 {
        0.5 * (self.opposite_cotangent(h) + self.opposite_cotangent(self.twin(h)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morton_codes_interleave_the_axes() {
        assert_eq!(spread3(0b111), 0b1001001);
        // The cube's corners: x is the lowest bit of each triple, then y, then z.
        let top = (1u64 << 63) - 1;
        let codes = morton_codes(&[
            DVec3::ZERO,
            DVec3::X,
            DVec3::Y,
            DVec3::Z,
            DVec3::ONE,
            DVec3::splat(0.5),
        ])
        .expect("a non-degenerate cube");
        assert_eq!(
            codes[..5],
            [
                0,
                top & 0x1249_2492_4924_9249,
                (top & 0x1249_2492_4924_9249) << 1,
                (top & 0x1249_2492_4924_9249) << 2,
                top
            ]
        );
        // The centre comes after the corner at the origin and before the far corner.
        assert!(codes[0] < codes[5] && codes[5] < codes[4]);
        assert_eq!(morton_codes(&[]), None);
        assert_eq!(morton_codes(&[DVec3::ONE, DVec3::ONE]), None);
        // A point that is not finite gets a code instead of breaking the order.
        let codes = morton_codes(&[DVec3::ZERO, DVec3::ONE, DVec3::NAN, DVec3::INFINITY]);
        assert_eq!(codes, Some(vec![0, top, 0, top]));
    }
}
