//! Flat arrays of a triangle mesh for the denoiser's hot loops: triangles as vertex slots,
//! face adjacency across interior edges, and per-face normals and areas.
//!
//! Two sources give the same arrays: the builder's corner table ([`FlatSurface::from_corners`],
//! what `meshpyr smooth` uses, so no half-edge record is ever made: those records cost several
//! times these arrays) and a half-edge [`Mesh`] ([`FlatSurface::new`]). Face `t` of the corner
//! table is face slot `t` of the mesh the builder would assemble from it, and vertex `i` its
//! vertex slot `i`, so both give the same surface, hence the same smoothing, bit for bit.
//!
//! Faces are numbered `0..n` in slot order; vertices keep their slot index, so position arrays
//! are indexed by [`SlotIndex::slot`] and dead slots simply stay unreferenced.

use crate::mesh::geometry::morton_codes;
use crate::mesh::{CornerTable, Mesh, SlotIndex};
use glam::DVec3;

/// "No neighbour" in [`FlatSurface::adjacency`].
pub(crate) const NO_FACE: u32 = u32::MAX;

/// Connectivity of a triangle mesh as flat arrays.
#[derive(Clone, Debug, Default)]
pub(crate) struct FlatSurface {
    /// Vertex slots of each triangle, counter-clockwise.
    pub triangles: Vec<[u32; 3]>,
    /// `adjacency[f][k]`: the face across edge `k` (from corner `k` to corner `k+1`) of `f`,
    /// or [`NO_FACE`] on a boundary edge.
    pub adjacency: Vec<[u32; 3]>,
    /// One more than the largest vertex slot: the length of slot-indexed arrays.
    pub vertex_slots: usize,
}

impl FlatSurface {
    /// Flattens `mesh`. Edges with a single face (boundaries, including the ones the builder
    /// cut when repairing non-manifold input) get no neighbour, so nothing crosses them.
    pub(crate) fn new(mesh: &Mesh) -> FlatSurface {
        let face_slots = mesh.faces().map(|f| f.slot() + 1).max().unwrap_or(0);
        let mut index = vec![NO_FACE; face_slots];
        for (i, f) in mesh.faces().enumerate() {
            index[f.slot()] = i as u32;
        }
        let mut triangles = Vec::with_capacity(mesh.n_faces());
        let mut adjacency = Vec::with_capacity(mesh.n_faces());
        for f in mesh.faces() {
            let h0 = mesh.face_halfedge(f);
            let hs = [h0, mesh.next(h0), mesh.prev(h0)];
            triangles.push(hs.map(|h| mesh.from_vertex(h).slot() as u32));
            adjacency.push(hs.map(|h| match mesh.face(mesh.twin(h)) {
                Some(g) => index[g.slot()],
                None => NO_FACE,
            }));
        }
        FlatSurface {
            triangles,
            adjacency,
            vertex_slots: mesh.vertices().map(|v| v.slot() + 1).max().unwrap_or(0),
        }
    }

    /// The surface of the builder's corner table with `vertices` mesh vertices (isolated ones
    /// included), the same as [`FlatSurface::new`] of the mesh assembled from it. Takes the
    /// table so that its arrays become the surface's in place where the allocator allows,
    /// one at a time otherwise: the peak stays at the table's size.
    pub(crate) fn from_corners(corners: CornerTable, vertices: usize) -> FlatSurface {
        let CornerTable {
            corner_vertex,
            mut mate,
        } = corners;
        let triangles = into_triples(corner_vertex);
        // The face across half-edge `c` is the triangle of its twin.
        for m in &mut mate {
            if *m != NO_FACE {
                *m /= 3;
            }
        }
        FlatSurface {
            triangles,
            adjacency: into_triples(mate),
            vertex_slots: vertices,
        }
    }

    /// Renumbers the faces along a Morton (Z-order) curve of their centroids at `positions`,
    /// so faces near on the surface are near in memory: the Dijkstra balls then stay in cache.
    /// Ties (equal codes) keep the previous order, so the result is deterministic.
    pub(crate) fn reorder_spatially(&mut self, positions: &[DVec3]) {
        let n = self.n_faces();
        if n < 2 {
            return;
        }
        let centroids: Vec<DVec3> = self
            .triangles
            .iter()
            .map(|t| t.iter().map(|&v| positions[v as usize]).sum::<DVec3>() / 3.0)
            .collect();
        let Some(codes) = morton_codes(&centroids) else {
            return;
        };
        drop(centroids);
        let mut keyed: Vec<(u64, u32)> = codes
            .into_iter()
            .enumerate()
            .map(|(i, code)| (code, i as u32))
            .collect();
        keyed.sort_unstable();
        let order: Vec<u32> = keyed.iter().map(|&(_, old)| old).collect();
        drop(keyed);
        let mut new_index = vec![0u32; n];
        for (new, &old) in order.iter().enumerate() {
            new_index[old as usize] = new as u32;
        }
        // One array at a time, the old one dropped before the next is made: this runs at
        // the denoiser's largest resident set besides the filter's.
        self.triangles = order
            .iter()
            .map(|&old| self.triangles[old as usize])
            .collect();
        self.adjacency = order
            .iter()
            .map(|&old| {
                self.adjacency[old as usize].map(|g| {
                    if g == NO_FACE {
                        g
                    } else {
                        new_index[g as usize]
                    }
                })
            })
            .collect();
    }

    /// Number of triangles.
    pub(crate) fn n_faces(&self) -> usize {
        self.triangles.len()
    }

    /// Mean length of the triangles' edges (interior edges counted twice, which weights
    /// them like the faces they bound); 0 without faces.
    pub(crate) fn mean_edge_length(&self, positions: &[DVec3]) -> f64 {
        let mut sum = 0.0;
        for t in &self.triangles {
            for k in 0..3 {
                sum += (positions[t[(k + 1) % 3] as usize] - positions[t[k] as usize]).length();
            }
        }
        if self.triangles.is_empty() {
            0.0
        } else {
            sum / (3 * self.triangles.len()) as f64
        }
    }

    /// Per face, its local edge length over `mean`: the mean length of its edges and those
    /// of the faces across them. Averaging over the neighbours keeps noise from deciding a
    /// face's scale; a face with no length of its own gets 1.
    pub(crate) fn local_length_factors(&self, positions: &[DVec3], mean: f64) -> Vec<f64> {
        let own: Vec<f64> = (0..self.triangles.len())
            .map(|f| {
                let [a, b, c] = self.triangles[f].map(|v| positions[v as usize]);
                ((b - a).length() + (c - b).length() + (a - c).length()) / 3.0
            })
            .collect();
        (0..self.triangles.len())
            .map(|f| {
                let (mut sum, mut count) = (own[f], 1.0);
                for &g in &self.adjacency[f] {
                    if let Some(&l) = own.get(g as usize) {
                        sum += l;
                        count += 1.0;
                    }
                }
                let factor = sum / count / mean;
                if factor > 0.0 && factor.is_finite() {
                    factor
                } else {
                    1.0
                }
            })
            .collect()
    }

    /// Unnormalised normal `(P1 − P0) × (P2 − P0)` of face `f` (twice the area, along n).
    #[inline]
    pub(crate) fn area_vector(&self, positions: &[DVec3], f: usize) -> DVec3 {
        let [a, b, c] = self.triangles[f].map(|v| positions[v as usize]);
        (b - a).cross(c - a)
    }

    /// Centroid of face `f`, the vertex of the dual mesh.
    #[inline]
    pub(crate) fn centroid(&self, positions: &[DVec3], f: usize) -> DVec3 {
        let [a, b, c] = self.triangles[f].map(|v| positions[v as usize]);
        (a + b + c) / 3.0
    }

    /// Per-face unit normals and areas at `positions`; see [`FaceFrames`].
    pub(crate) fn face_frames(&self, positions: &[DVec3]) -> FaceFrames {
        let n = self.n_faces();
        let mut frames = FaceFrames {
            normals: Vec::with_capacity(n),
            areas: Vec::with_capacity(n),
        };
        for f in 0..n {
            let (normal, area) = unit_normal(self.area_vector(positions, f));
            frames.normals.push(normal);
            frames.areas.push(area);
        }
        frames
    }
}

/// `flat` as triples, in place when its allocation holds a whole number of them.
fn into_triples(flat: Vec<u32>) -> Vec<[u32; 3]> {
    match bytemuck::allocation::try_cast_vec(flat) {
        Ok(triples) => triples,
        Err((_, flat)) => flat.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
    }
}

/// Unit normal and area of a face from its area vector `N = 2A n`. A face whose normal is not
/// representable (zero area, or so small that normalising would overflow) gets the zero
/// normal and zero area: it then carries no weight anywhere and never produces a NaN.
#[inline]
pub(crate) fn unit_normal(area_vector: DVec3) -> (DVec3, f64) {
    let len = area_vector.length();
    if len > f64::MIN_POSITIVE && len.is_finite() {
        (area_vector / len, 0.5 * len)
    } else {
        (DVec3::ZERO, 0.0)
    }
}

/// Per-face geometry, indexed like [`FlatSurface::triangles`].
#[derive(Clone, Debug, Default)]
pub(crate) struct FaceFrames {
    /// Unit normals (zero for a degenerate face).
    pub normals: Vec<DVec3>,
    /// Areas (zero for a degenerate face).
    pub areas: Vec<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn adjacency_is_symmetric_and_stops_at_boundaries() {
        // Two triangles sharing the diagonal of a unit square.
        let p = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
        let built = Mesh::from_triangles(&p, &[[0, 1, 2], [0, 2, 3]]).expect("valid mesh");
        let s = FlatSurface::new(&built.mesh);
        assert_eq!(s.n_faces(), 2);
        assert_eq!(s.vertex_slots, 4);
        for f in 0..2 {
            let across: Vec<u32> = s.adjacency[f]
                .iter()
                .copied()
                .filter(|&g| g != NO_FACE)
                .collect();
            assert_eq!(across, vec![1 - f as u32]);
        }
        let frames = s.face_frames(&built.mesh.positions());
        assert_eq!(frames.normals, vec![DVec3::Z, DVec3::Z]);
        assert_eq!(frames.areas, vec![0.5, 0.5]);
        assert!(
            (s.mean_edge_length(&built.mesh.positions()) - (4.0 + 2.0 * 2f64.sqrt()) / 6.0).abs()
                < 1e-15
        );
    }

    #[test]
    fn spatial_reordering_keeps_the_surface() {
        let mut p = Vec::new();
        let mut t = Vec::new();
        for j in 0..6u32 {
            for i in 0..6u32 {
                p.push(DVec3::new(
                    i as f64,
                    j as f64,
                    ((i * 7 + j * 3) % 5) as f64 * 0.1,
                ));
            }
        }
        for j in 0..5u32 {
            for i in 0..5u32 {
                let a = j * 6 + i;
                t.push([a, a + 1, a + 7]);
                t.push([a, a + 7, a + 6]);
            }
        }
        let built = Mesh::from_triangles(&p, &t).expect("valid grid");
        let mut s = FlatSurface::new(&built.mesh);
        let before = s.clone();
        s.reorder_spatially(&built.mesh.positions());
        assert_ne!(s.triangles, before.triangles, "the order changed");
        let mut a = s.triangles.clone();
        let mut b = before.triangles.clone();
        a.sort_unstable();
        b.sort_unstable();
        assert_eq!(a, b, "same triangles");
        // Adjacency still names the face sharing each edge.
        for (f, t) in s.triangles.iter().enumerate() {
            for k in 0..3 {
                let g = s.adjacency[f][k];
                if g != NO_FACE {
                    let u = s.triangles[g as usize];
                    assert!(u.contains(&t[k]) && u.contains(&t[(k + 1) % 3]));
                }
            }
        }
    }

    #[test]
    fn degenerate_faces_get_zero_normals() {
        assert_eq!(unit_normal(DVec3::ZERO), (DVec3::ZERO, 0.0));
        assert_eq!(unit_normal(DVec3::splat(f64::INFINITY)), (DVec3::ZERO, 0.0));
        let (n, a) = unit_normal(DVec3::new(0.0, 0.0, 1e-100));
        assert_eq!(n, DVec3::Z);
        assert!(a > 0.0);
    }

    #[test]
    fn local_length_factors_follow_the_sampling() {
        // A strip of unit squares, then a strip ten times finer along x, side by side.
        let mut p = Vec::new();
        let mut t = Vec::new();
        let mut quad = |p: &mut Vec<DVec3>, x0: f64, w: f64| {
            let i = p.len() as u32;
            p.extend([
                DVec3::new(x0, 0.0, 0.0),
                DVec3::new(x0 + w, 0.0, 0.0),
                DVec3::new(x0 + w, w, 0.0),
                DVec3::new(x0, w, 0.0),
            ]);
            t.extend([[i, i + 1, i + 2], [i, i + 2, i + 3]]);
        };
        quad(&mut p, 0.0, 1.0);
        quad(&mut p, 5.0, 0.1);
        let built = Mesh::from_triangles(&p, &t).expect("valid mesh");
        let s = FlatSurface::new(&built.mesh);
        let pos = built.mesh.positions();
        let mean = s.mean_edge_length(&pos);
        let f = s.local_length_factors(&pos, mean);
        // Each face averages with its one neighbour, which has its size.
        let coarse = (2.0 + 2f64.sqrt()) / 3.0 / mean;
        for (face, &factor) in f.iter().enumerate() {
            let expected = if s.triangles[face][0] < 4 {
                coarse
            } else {
                0.1 * coarse
            };
            assert!(
                (factor - expected).abs() < 1e-12,
                "{face}: {factor} vs {expected}"
            );
        }
    }
}
