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

    /// Adds `s` times `o` (planes only: a rim's planes carry no face weight).
    #[inline]
    pub(crate) fn add_scaled(&mut self, o: &Quadric, s: f64) {
        for k in 0..6 {
            self.a[k] += s * o.a[k];
        }
        for k in 0..3 {
            self.b[k] += s * o.b[k];
        }
        self.c += s * o.c;
        self.weight += s * o.weight;
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

/// The quadrics of a decimation: per vertex its faces' planes (and regulariser), and apart from
/// them the boundary constraint planes of the boundary vertices, so that each pass can weigh the
/// rims for its level ([`Quadrics::rim_scale`]).
#[derive(Clone, Debug)]
pub(crate) struct Quadrics {
    /// Face planes and point regulariser of every vertex.
    pub faces: Vec<Quadric>,
    /// Index into `rims` of every vertex, `NO_RIM` for interior ones.
    rim_slot: Vec<u32>,
    /// Boundary planes, one quadric per boundary vertex.
    rims: Vec<Quadric>,
    /// The factor the rims count with in this pass's costs.
    pub rim_scale: f64,
}

const NO_RIM: u32 = u32::MAX;

impl Quadrics {
    /// `faces` per vertex, and the boundary planes `(vertex, plane)` added to their vertices.
    pub(crate) fn new(faces: Vec<Quadric>, boundary_planes: &[(u32, Quadric)]) -> Quadrics {
        let mut rim_slot = vec![NO_RIM; faces.len()];
        let mut rims: Vec<Quadric> = Vec::new();
        for (v, q) in boundary_planes {
            let slot = &mut rim_slot[*v as usize];
            if *slot == NO_RIM {
                *slot = rims.len() as u32;
                rims.push(Quadric::default());
            }
            rims[*slot as usize].add(q);
        }
        Quadrics {
            faces,
            rim_slot,
            rims,
            rim_scale: 1.0,
        }
    }

    pub(crate) fn rim(&self, v: u32) -> Option<&Quadric> {
        match self.rim_slot[v as usize] {
            NO_RIM => None,
            s => Some(&self.rims[s as usize]),
        }
    }

    /// The merged quadric of `a` and `b` as this pass weighs it.
    #[inline]
    pub(crate) fn merged(&self, a: u32, b: u32) -> Quadric {
        let mut q = self.faces[a as usize].sum(&self.faces[b as usize]);
        for x in [a, b] {
            if let Some(r) = self.rim(x) {
                q.add_scaled(r, self.rim_scale);
            }
        }
        q
    }

    /// After the collapse `u → v`: `v` carries `u`'s planes too.
    #[inline]
    pub(crate) fn absorb(&mut self, u: u32, v: u32) {
        let qu = self.faces[u as usize];
        self.faces[v as usize].add(&qu);
        let Some(&ru) = self.rim(u) else { return };
        // A boundary vertex only collapses onto a boundary vertex, but one whose rim edges
        // were all degenerate has no planes of its own yet.
        match self.rim_slot[v as usize] {
            NO_RIM => {
                self.rim_slot[v as usize] = self.rims.len() as u32;
                self.rims.push(ru);
            }
            s => self.rims[s as usize].add(&ru),
        }
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

    #[test]
    fn rims_count_with_the_pass_scale_and_follow_their_vertex() {
        // Vertex 0 and 1 on a rim (a plane x = 0 each), vertex 2 interior; every vertex has the
        // face plane z = 0 with unit weight.
        let face = Quadric::from_plane(DVec3::Z, DVec3::ZERO, 1.0, 1.0);
        let rim = Quadric::from_plane(DVec3::X, DVec3::ZERO, 10.0, 0.0);
        let mut q = Quadrics::new(vec![face; 3], &[(0, rim), (1, rim)]);
        let p = DVec3::new(1.0, 0.0, 0.0);
        // Merged: two face planes (weight 2, distance 0) and two rims at distance 1.
        assert!((q.merged(0, 1).error(p) - 10.0).abs() < 1e-12);
        assert!((q.merged(0, 2).error(p) - 5.0).abs() < 1e-12);
        q.rim_scale = 0.3;
        assert!((q.merged(0, 1).error(p) - 3.0).abs() < 1e-12);
        assert_eq!(q.merged(2, 2).error(p), 0.0);
        // Along the rim, 0 → 1: vertex 1 carries both rims and both faces.
        q.absorb(0, 1);
        q.rim_scale = 1.0;
        assert!((q.faces[1].weight - 2.0).abs() < 1e-12);
        assert!((q.merged(1, 2).error(p) - 20.0 / 3.0).abs() < 1e-12);
        // An interior vertex onto a rim one adds no rim.
        q.absorb(2, 1);
        assert!((q.merged(1, 1).error(p) - 2.0 * 20.0 / 6.0).abs() < 1e-12);
    }
}
