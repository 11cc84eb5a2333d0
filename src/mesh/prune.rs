//! An explicit repair for scans with floating debris: drop the connected pieces that are small
//! compared with the whole.
//!
//! Reconstructions (marching cubes, vrip, Poisson) often leave dozens of tiny closed blobs
//! around the object. The progressive mesh keeps every component, so each blob costs at least
//! a tetrahedron at every level, and at 1 % of the faces they can hold most of the budget.
//! Dropping them changes the topology, which is why it is never done unless asked for.

use super::union_find::UnionFind;
use super::{BoundingBox, PolygonMesh};

/// What [`prune_small_components`] removed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Pruned {
    /// Components dropped.
    pub components: usize,
    /// Components in the input (pieces joined by shared vertex indices).
    pub of_components: usize,
    /// Polygons dropped.
    pub faces: usize,
}

/// `mesh` without the components (polygons joined by shared vertex indices) whose
/// bounding-box diagonal is below `min_fraction` of the whole mesh's. The largest component is
/// always kept. Vertices, their attributes and the order of the kept polygons are unchanged
/// (dropped pieces leave unreferenced vertices); per-face attributes follow their polygons.
pub fn prune_small_components(mesh: &PolygonMesh, min_fraction: f64) -> (PolygonMesh, Pruned) {
    let n = mesh.positions.len();
    let mut sets = UnionFind::new(n);
    for f in mesh.faces() {
        for w in f.windows(2) {
            sets.union(w[0], w[1]);
        }
    }
    let face_root: Vec<Option<u32>> = mesh
        .faces()
        .map(|f| f.first().map(|&v| sets.find(v)))
        .collect();
    let mut boxes: Vec<Option<BoundingBox>> = vec![None; n];
    for f in mesh.faces() {
        let Some(&first) = f.first() else { continue };
        let r = sets.find(first) as usize;
        for &v in f {
            let p = mesh.positions[v as usize];
            boxes[r] = Some(match boxes[r] {
                Some(b) => b.including(p),
                None => BoundingBox { min: p, max: p },
            });
        }
    }
    let whole = boxes
        .iter()
        .flatten()
        .copied()
        .reduce(|a, b| a.including(b.min).including(b.max));
    let Some(whole) = whole else {
        return (mesh.clone(), Pruned::default());
    };
    let of_components = boxes.iter().flatten().count();
    let largest = (0..n)
        .filter_map(|r| boxes[r].map(|b| (b.diagonal(), r)))
        .max_by(|a, b| a.0.total_cmp(&b.0).then(b.1.cmp(&a.1)))
        .map(|(_, r)| r);
    let bound = min_fraction * whole.diagonal();
    let keep_root =
        |r: usize| Some(r) == largest || boxes[r].is_some_and(|b| b.diagonal() >= bound);
    let kept: Vec<u32> = (0..mesh.n_faces() as u32)
        .filter(|&f| face_root[f as usize].is_some_and(|r| keep_root(r as usize)))
        .collect();
    let out = mesh.with_faces(&kept);
    let components = (0..n)
        .filter(|&r| boxes[r].is_some() && !keep_root(r))
        .count();
    let pruned = Pruned {
        components,
        of_components,
        faces: mesh.n_faces() - kept.len(),
    };
    (out, pruned)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// A big triangle pair and a small far-away triangle, with a per-face attribute.
    fn big_and_small() -> PolygonMesh {
        let p = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(10.0, 0.0, 0.0),
            DVec3::new(10.0, 10.0, 0.0),
            DVec3::new(0.0, 10.0, 0.0),
            DVec3::new(20.0, 20.0, 0.0),
            DVec3::new(20.1, 20.0, 0.0),
            DVec3::new(20.0, 20.1, 0.0),
        ];
        let mut m = PolygonMesh::from_triangles(p, &[[0, 1, 2], [4, 5, 6], [0, 2, 3]]);
        m.face_attributes.push(super::super::Attribute {
            name: "label".into(),
            data: super::super::AttributeData::I32(vec![7, 8, 9]),
        });
        m
    }

    #[test]
    fn pieces_below_the_fraction_go_and_the_rest_keeps_its_order() {
        let (out, pruned) = prune_small_components(&big_and_small(), 0.05);
        assert_eq!(
            pruned,
            Pruned {
                components: 1,
                of_components: 2,
                faces: 1
            }
        );
        assert_eq!(out.face_indices, vec![0, 1, 2, 0, 2, 3]);
        assert_eq!(out.positions.len(), 7);
        assert_eq!(
            out.face_attributes[0].data,
            super::super::AttributeData::I32(vec![7, 9])
        );
    }

    #[test]
    fn the_largest_piece_stays_and_zero_keeps_everything() {
        let (out, pruned) = prune_small_components(&big_and_small(), 2.0);
        assert_eq!(pruned.components, 1);
        assert_eq!(out.n_faces(), 2);
        let (out, pruned) = prune_small_components(&big_and_small(), 0.0);
        assert_eq!(pruned.components, 0);
        assert_eq!(out.n_faces(), 3);
    }
}
