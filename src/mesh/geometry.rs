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

    /// Length of the diagonal; the scale all relative tolerances refer to.
    pub fn diagonal(&self) -> f64 {
        (self.max - self.min).length()
    }
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
    pub fn face_area_normal(&self, f: FaceId) -> DVec3 {
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
    pub fn face_area(&self, f: FaceId) -> f64 {
        0.5 * self.face_area_normal(f).length()
    }

    /// Face centroid.
    #[inline]
    pub fn face_centroid(&self, f: FaceId) -> DVec3 {
        let [a, b, c] = self.face_positions(f);
        (a + b + c) / 3.0
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
    pub fn edge_vector(&self, h: HalfedgeId) -> DVec3 {
        self.position(self.to_vertex(h)) - self.position(self.from_vertex(h))
    }

    /// Length of the edge of `h`.
    #[inline]
    pub fn edge_length(&self, h: HalfedgeId) -> f64 {
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
    pub fn opposite_cotangent(&self, h: HalfedgeId) -> f64 {
        if self.is_boundary_halfedge(h) {
            return 0.0;
        }
        let o = self.position(self.to_vertex(self.next(h)));
        let a = self.position(self.from_vertex(h));
        let b = self.position(self.to_vertex(h));
        cotangent(a - o, b - o)
    }

    /// The cotangent weight of an edge, `(cot α + cot β) / 2` over its two opposite angles.
    pub fn cotangent_weight(&self, h: HalfedgeId) -> f64 {
        0.5 * (self.opposite_cotangent(h) + self.opposite_cotangent(self.twin(h)))
    }
}
