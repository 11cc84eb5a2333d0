//! Exact closest points on a triangle surface: the point–triangle test (Ericson, *Real-Time
//! Collision Detection* §5.1.5, by Voronoi region) and a bounding-volume hierarchy over the
//! triangles for closest-triangle queries.
//!
//! The hierarchy is a binary tree over flat arrays, built top-down by splitting the centroids
//! at the median of the longest axis, with up to [`LEAF_SIZE`] triangles per leaf. A query
//! walks the nearer child first and prunes boxes farther than the best distance so far, so the
//! answer is exact (not approximate). Ties between equally close triangles go to the smallest
//! triangle index, which makes the answer independent of the tree's shape and traversal order.

use glam::DVec3;

/// Triangles per leaf of the hierarchy.
pub(crate) const LEAF_SIZE: usize = 4;

/// Which feature of the triangle the closest point lies on (Ericson's Voronoi regions).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Region {
    /// Corner `a`.
    VertexA,
    /// Corner `b`.
    VertexB,
    /// Corner `c`.
    VertexC,
    /// Edge `ab` (interior of the segment).
    EdgeAb,
    /// Edge `bc`.
    EdgeBc,
    /// Edge `ca`.
    EdgeCa,
    /// Interior of the face.
    Face,
}

/// The point of triangle `abc` closest to `p`, and the region it lies in.
///
/// Exact for every triangle, degenerate ones included: a triangle collapsed to a segment or a
/// point falls into the vertex and edge regions (the face branch is only reached with a
/// positive denominator), so the result is the closest point of the segment or point.
pub(crate) fn closest_point_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> (DVec3, Region) {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, Region::VertexA);
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, Region::VertexB);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + v * ab, Region::EdgeAb);
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, Region::VertexC);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + w * ac, Region::EdgeCa);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + w * (c - b), Region::EdgeBc);
    }
    let sum = va + vb + vc;
    if sum.is_nan() || sum <= 0.0 {
        // Rounding on an (almost) degenerate triangle can leave every edge test marginally
        // failed; the closest point is then on one of the edges, so take the best of the three.
        return closest_on_edges(p, a, b, c);
    }
    // Inside the face: project onto the plane. The barycentric form `a + v·ab + w·ac` with
    // `v = vb / sum` loses `ε / sin²θ` of an edge length to cancellation in the products of
    // dots (9e-11 of the edge on a sliver of the CAD anchor, sin θ = 5e-4); the projection
    // loses about `ε / sin θ`.
    let n = ab.cross(ac);
    let nn = n.length_squared();
    if nn.is_nan() || nn <= 0.0 {
        return closest_on_edges(p, a, b, c);
    }
    (p - n * (n.dot(ap) / nn), Region::Face)
}

fn closest_on_segment(p: DVec3, a: DVec3, b: DVec3) -> DVec3 {
    let d = b - a;
    let l2 = d.length_squared();
    if l2 <= 0.0 {
        return a;
    }
    a + d * ((p - a).dot(d) / l2).clamp(0.0, 1.0)
}

fn closest_on_edges(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> (DVec3, Region) {
    [
        (closest_on_segment(p, a, b), Region::EdgeAb),
        (closest_on_segment(p, b, c), Region::EdgeBc),
        (closest_on_segment(p, c, a), Region::EdgeCa),
    ]
    .into_iter()
    .min_by(|x, y| p.distance_squared(x.0).total_cmp(&p.distance_squared(y.0)))
    .unwrap_or((a, Region::VertexA))
}

/// Squared distance from `p` to triangle `abc`.
#[inline]
#[cfg(test)]
pub(crate) fn point_triangle_distance_squared(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    p.distance_squared(closest_point_on_triangle(p, a, b, c).0)
}

/// The answer of a closest-triangle query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Closest {
    /// Index of the closest triangle in the array the hierarchy was built from.
    pub triangle: usize,
    /// The closest point on the surface.
    pub point: DVec3,
    /// Squared distance from the query point to `point`.
    pub distance_squared: f64,
}

#[derive(Clone, Copy, Debug)]
struct Node {
    min: DVec3,
    max: DVec3,
    /// Leaf: first entry in `order`. Inner node: index of the left child (the right child
    /// follows the left subtree, at `right`).
    start: u32,
    /// Leaf: number of triangles (> 0). Inner node: 0.
    count: u32,
    /// Inner node: index of the right child.
    right: u32,
}

impl Node {
    #[inline]
    fn distance_squared(&self, p: DVec3) -> f64 {
        let d = (self.min - p).max(p - self.max).max(DVec3::ZERO);
        d.length_squared()
    }
}

/// A bounding-volume hierarchy over triangles for exact closest-point queries; see the module
/// docs.
#[derive(Clone, Debug)]
pub(crate) struct TriangleBvh {
    /// Corners of each triangle, in the order they were given.
    corners: Vec<[DVec3; 3]>,
    /// Triangle indices in leaf order.
    order: Vec<u32>,
    nodes: Vec<Node>,
}

impl TriangleBvh {
    /// Builds the hierarchy over `triangles` indexing `positions`. Indices out of range are the
    /// caller's bug (mesh triangles are always in range) and panic.
    pub(crate) fn new(positions: &[DVec3], triangles: &[[u32; 3]]) -> TriangleBvh {
        let corners: Vec<[DVec3; 3]> = triangles
            .iter()
            .map(|t| t.map(|i| positions[i as usize]))
            .collect();
        Self::from_corners(corners)
    }

    /// Builds the hierarchy over triangles given by their corners.
    pub(crate) fn from_corners(corners: Vec<[DVec3; 3]>) -> TriangleBvh {
        let centroids: Vec<DVec3> = corners.iter().map(|t| (t[0] + t[1] + t[2]) / 3.0).collect();
        let mut order: Vec<u32> = (0..corners.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * corners.len() / LEAF_SIZE + 1);
        if !corners.is_empty() {
            build(&corners, &centroids, &mut order, 0, &mut nodes);
        }
        TriangleBvh {
            corners,
            order,
            nodes,
        }
    }

    /// The closest point to `p` on any triangle (`None` when there are no triangles). Exact;
    /// ties go to the smallest triangle index.
    pub(crate) fn closest(&self, p: DVec3) -> Option<Closest> {
        if self.nodes.is_empty() {
            return None;
        }
        let mut best = Closest {
            triangle: usize::MAX,
            point: p,
            distance_squared: f64::INFINITY,
        };
        // The stack holds at most two entries per tree level, and a median split has about
        // log2(n/4) levels, so 64 inline entries cover any mesh without a heap allocation.
        let mut stack: smallvec::SmallVec<[(u32, f64); 64]> = smallvec::SmallVec::new();
        stack.push((0, self.nodes[0].distance_squared(p)));
        while let Some((ni, nd)) = stack.pop() {
            // `>` rather than `>=`: an equally distant box may hold a smaller triangle index.
            if nd > best.distance_squared {
                continue;
            }
            let node = &self.nodes[ni as usize];
            if node.count > 0 {
                let s = node.start as usize;
                for &t in &self.order[s..s + node.count as usize] {
                    let [a, b, c] = self.corners[t as usize];
                    let (q, _) = closest_point_on_triangle(p, a, b, c);
                    let d = p.distance_squared(q);
                    let t = t as usize;
                    if d < best.distance_squared
                        || (d == best.distance_squared && t < best.triangle)
                    {
                        best = Closest {
                            triangle: t,
                            point: q,
                            distance_squared: d,
                        };
                    }
                }
            } else {
                let (l, r) = (ni + 1, node.right);
                let dl = self.nodes[l as usize].distance_squared(p);
                let dr = self.nodes[r as usize].distance_squared(p);
                // Push the farther child first so the nearer one is searched first.
                if dl <= dr {
                    stack.push((r, dr));
                    stack.push((l, dl));
                } else {
                    stack.push((l, dl));
                    stack.push((r, dr));
                }
            }
        }
        (best.triangle != usize::MAX).then_some(best)
    }

    /// Distance from `p` to the surface (infinite when there are no triangles).
    pub(crate) fn distance(&self, p: DVec3) -> f64 {
        self.closest(p)
            .map_or(f64::INFINITY, |c| c.distance_squared.sqrt())
    }
}

/// Builds the subtree over `order[..]` (which starts at `offset` in the full order array),
/// appending nodes in depth-first order; returns the subtree's root index.
fn build(
    corners: &[[DVec3; 3]],
    centroids: &[DVec3],
    order: &mut [u32],
    offset: usize,
    nodes: &mut Vec<Node>,
) -> u32 {
    let (mut min, mut max) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let (mut cmin, mut cmax) = (min, max);
    for &t in order.iter() {
        for q in corners[t as usize] {
            min = min.min(q);
            max = max.max(q);
        }
        let c = centroids[t as usize];
        cmin = cmin.min(c);
        cmax = cmax.max(c);
    }
    let index = nodes.len() as u32;
    nodes.push(Node {
        min,
        max,
        start: offset as u32,
        count: order.len() as u32,
        right: 0,
    });
    if order.len() <= LEAF_SIZE {
        return index;
    }
    let extent = cmax - cmin;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = order.len() / 2;
    // Ties by index keep the split (and so the tree) deterministic.
    order.select_nth_unstable_by(mid, |&a, &b| {
        centroids[a as usize][axis]
            .total_cmp(&centroids[b as usize][axis])
            .then(a.cmp(&b))
    });
    let (left, right) = order.split_at_mut(mid);
    build(corners, centroids, left, offset, nodes);
    let r = build(corners, centroids, right, offset + mid, nodes);
    let node = &mut nodes[index as usize];
    node.count = 0;
    node.right = r;
    index
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Small deterministic generator so the tests need no extra dependency.
    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((self.0 >> 11) as f64) / ((1u64 << 53) as f64) * 2.0 - 1.0
        }
        fn vec(&mut self, s: f64) -> DVec3 {
            DVec3::new(self.next(), self.next(), self.next()) * s
        }
    }

    /// Minimum over a dense barycentric sample of the triangle plus its exact edges.
    fn brute_force(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
        let mut best = f64::INFINITY;
        let n = 200;
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                let q = a + (b - a) * u + (c - a) * v;
                best = best.min(p.distance_squared(q));
            }
        }
        for (s, e) in [(a, b), (b, c), (c, a)] {
            best = best.min(p.distance_squared(closest_on_segment(p, s, e)));
        }
        best
    }

    #[test]
    fn every_voronoi_region_matches_brute_force() {
        let a = DVec3::new(0.0, 0.0, 0.0);
        let b = DVec3::new(2.0, 0.0, 0.0);
        let c = DVec3::new(0.5, 1.5, 0.0);
        let cases = [
            (DVec3::new(-1.0, -1.0, 0.3), Region::VertexA),
            (DVec3::new(3.0, -0.5, -0.2), Region::VertexB),
            (DVec3::new(0.5, 2.5, 0.7), Region::VertexC),
            (DVec3::new(1.0, -1.0, 0.5), Region::EdgeAb),
            (DVec3::new(1.8, 1.2, -0.4), Region::EdgeBc),
            (DVec3::new(-0.5, 0.8, 0.1), Region::EdgeCa),
            (DVec3::new(0.8, 0.4, 0.9), Region::Face),
            (DVec3::new(0.8, 0.4, -0.9), Region::Face),
        ];
        for (p, region) in cases {
            let (q, r) = closest_point_on_triangle(p, a, b, c);
            assert_eq!(r, region, "{p}");
            let d = p.distance_squared(q);
            let bf = brute_force(p, a, b, c);
            assert!(d <= bf + 1e-12, "{p}: {d} vs {bf}");
            assert!(bf - d < 1e-4, "{p}: {d} vs {bf}");
        }
        // Random points and triangles: never farther than the brute force, and close to it.
        let mut rng = Lcg(7);
        for _ in 0..200 {
            let (a, b, c, p) = (rng.vec(1.0), rng.vec(1.0), rng.vec(1.0), rng.vec(2.0));
            let d = point_triangle_distance_squared(p, a, b, c);
            let bf = brute_force(p, a, b, c);
            assert!(d <= bf + 1e-12 && bf - d < 1e-3 * (1.0 + bf), "{d} vs {bf}");
        }
    }

    #[test]
    fn degenerate_triangles_are_segments_and_points() {
        let a = DVec3::ZERO;
        let b = DVec3::new(2.0, 0.0, 0.0);
        // Collapsed to a segment (c on ab).
        let c = DVec3::new(1.0, 0.0, 0.0);
        let p = DVec3::new(0.5, 1.0, 1.0);
        assert!((point_triangle_distance_squared(p, a, b, c) - 2.0).abs() < 1e-14);
        let p = DVec3::new(3.0, 0.0, 1.0);
        assert!((point_triangle_distance_squared(p, a, b, c) - 2.0).abs() < 1e-14);
        // Collapsed to a point.
        let p = DVec3::new(1.0, 2.0, 2.0);
        assert!((point_triangle_distance_squared(p, a, a, a) - 9.0).abs() < 1e-14);
        // Two equal corners.
        assert!((point_triangle_distance_squared(p, a, b, b) - 8.0).abs() < 1e-14);
    }

    #[test]
    fn points_on_a_sliver_are_their_own_closest_points() {
        // The CAD anchor's thinnest triangle (sin θ ≈ 5e-4, edges ≈ 0.1–0.3): the barycentric
        // face formula put points of the face 9e-11 away from themselves, enough for
        // `compare` to see a mesh 1.7e-11 of its diagonal away from its own copy.
        let mut rng = Lcg(5);
        for _ in 0..200 {
            let a = rng.vec(1.0);
            let dir = rng.vec(1.0).normalize();
            let side = dir.any_orthonormal_vector();
            let b = a + dir * 0.3;
            let c = a
                + dir * (0.1 + 0.2 * rng.next().abs())
                + side * 1e-4 * (0.5 + 0.5 * rng.next().abs());
            let (u, v) = (0.5 * rng.next().abs(), 0.5 * rng.next().abs());
            let p = a + (b - a) * u + (c - a) * v;
            let (q, _) = closest_point_on_triangle(p, a, b, c);
            assert!(q.distance(p) < 1e-13, "{:e}", q.distance(p));
        }
    }

    #[test]
    fn bvh_matches_linear_scan_and_breaks_ties_by_index() {
        let mut rng = Lcg(11);
        let corners: Vec<[DVec3; 3]> = (0..300)
            .map(|_| {
                let c = rng.vec(5.0);
                [c + rng.vec(0.3), c + rng.vec(0.3), c + rng.vec(0.3)]
            })
            .collect();
        let bvh = TriangleBvh::from_corners(corners.clone());
        for _ in 0..300 {
            let p = rng.vec(7.0);
            let got = bvh.closest(p).unwrap();
            let (best_i, best_d) = corners
                .iter()
                .enumerate()
                .map(|(i, t)| (i, point_triangle_distance_squared(p, t[0], t[1], t[2])))
                .fold((usize::MAX, f64::INFINITY), |acc, x| {
                    if x.1 < acc.1 { x } else { acc }
                });
            assert_eq!(got.distance_squared, best_d);
            assert_eq!(got.triangle, best_i);
        }
        // Two copies of one triangle: the first wins.
        let t = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let mut many = vec![[DVec3::splat(9.0); 3]; 10];
        many.push(t);
        many.push(t);
        let bvh = TriangleBvh::from_corners(many);
        assert_eq!(bvh.closest(DVec3::new(0.2, 0.2, 1.0)).unwrap().triangle, 10);
        assert!(
            TriangleBvh::from_corners(vec![])
                .closest(DVec3::ZERO)
                .is_none()
        );
    }
}
