//! Stored normals that follow the geometry: after a command moves vertices, the normals a file
//! stores (per vertex `nx`,`ny`,`nz`; per corner the `normal` attribute) are recomputed from
//! the new surface, so a renderer that uses them lights the new shape, not the old one.
//!
//! Normals are area-weighted: the sum of the vector areas (Newell) of the polygons around a
//! vertex. A file's hard edges stay hard: corners of one vertex whose stored normals differed
//! (the two sides of a crease, or of a smoothing-group border) form separate clusters, and
//! each cluster gets the normal of its own polygons. Only the normals of vertices whose
//! surroundings moved are recomputed; every other one keeps its stored bits.

use std::collections::HashMap;

use glam::DVec3;

use super::corners::NORMAL;
use super::polygon::{AttributeData, PolygonMesh};

impl PolygonMesh {
    /// Recomputes the stored normals around the vertices whose positions differ from `before`
    /// (the positions the normals were stored for; same length as the mesh's).
    pub fn refresh_normals(&mut self, before: &[DVec3]) {
        if before.len() != self.positions.len() {
            return;
        }
        let moved: Vec<bool> = self
            .positions
            .iter()
            .zip(before)
            .map(|(a, b)| a != b)
            .collect();
        if !moved.contains(&true) {
            return;
        }
        let face_moved: Vec<bool> = self
            .faces()
            .map(|f| f.iter().any(|&v| moved[v as usize]))
            .collect();
        let areas: Vec<DVec3> = self
            .faces()
            .map(|f| vector_area(&self.positions, f))
            .collect();
        self.refresh_vertex_normals(&face_moved, &areas);
        self.refresh_corner_normals(&face_moved, &areas);
    }

    /// Whether the mesh stores normals that [`Self::refresh_normals`] would recompute: a
    /// caller that moves positions in place keeps the old ones only then.
    pub fn stores_normals(&self) -> bool {
        self.has_vertex_normals() || self.corner_normals_slot().is_some()
    }

    /// Whether `nx`,`ny`,`nz` are all float vertex columns (integer ones are not normals to
    /// recompute).
    fn has_vertex_normals(&self) -> bool {
        ["nx", "ny", "nz"]
            .iter()
            .all(|n| is_float(self.vertex_attribute(n).map(|a| &a.data)))
    }

    /// The index of the corner attribute [`NORMAL`] when it has three float columns.
    fn corner_normals_slot(&self) -> Option<usize> {
        let k = self
            .corner_attributes
            .iter()
            .position(|a| a.name == NORMAL)?;
        let a = &self.corner_attributes[k];
        (a.columns.len() == 3 && a.columns.iter().all(|c| is_float(Some(&c.data)))).then_some(k)
    }

    /// The per-vertex `nx`,`ny`,`nz` of every vertex of a moved face.
    fn refresh_vertex_normals(&mut self, face_moved: &[bool], areas: &[DVec3]) {
        if !self.has_vertex_normals() {
            return;
        }
        let names = ["nx", "ny", "nz"];
        let mut sum = vec![DVec3::ZERO; self.n_vertices()];
        let mut touched = vec![false; self.n_vertices()];
        for (f, face) in self.faces().enumerate() {
            for &v in face {
                sum[v as usize] += areas[f];
                touched[v as usize] |= face_moved[f];
            }
        }
        for a in &mut self.vertex_attributes {
            let Some(k) = names.iter().position(|n| *n == a.name) else {
                continue;
            };
            for v in (0..sum.len()).filter(|&v| touched[v]) {
                set(&mut a.data, v, sum[v].normalize_or_zero()[k]);
            }
        }
    }

    /// The corner `normal` attribute: clusters of corners of one vertex sharing a stored
    /// normal get the normal of their polygons; the pool gets a row per cluster that moved.
    fn refresh_corner_normals(&mut self, face_moved: &[bool], areas: &[DVec3]) {
        let Some(k) = self.corner_normals_slot() else {
            return;
        };
        let mut attr = std::mem::take(&mut self.corner_attributes[k]);
        // Cluster: (vertex, stored value's bits); its summed vector area, and whether it moved.
        let mut clusters: HashMap<(u32, [u64; 3]), (DVec3, bool, u32)> = HashMap::new();
        let key = |attr: &super::CornerAttribute, c: usize, v: u32| {
            attr.row(c).map(|r| {
                let x = |i: usize| attr.columns[i].data.get_f64(r).to_bits();
                (v, [x(0), x(1), x(2)])
            })
        };
        for f in 0..self.n_faces() {
            for c in self.face_starts[f] as usize..self.face_starts[f + 1] as usize {
                if let Some(k) = key(&attr, c, self.face_indices[c]) {
                    let e = clusters.entry(k).or_insert((DVec3::ZERO, false, u32::MAX));
                    e.0 += areas[f];
                    e.1 |= face_moved[f];
                }
            }
        }
        for c in 0..attr.indices.len() {
            let Some(k) = key(&attr, c, self.face_indices[c]) else {
                continue;
            };
            let (normal, moved, row) = clusters.get_mut(&k).expect("every corner was counted");
            if !*moved {
                continue;
            }
            if *row == u32::MAX {
                *row = attr.pool_len() as u32;
                for (i, col) in attr.columns.iter_mut().enumerate() {
                    col.data.push_f64(normal.normalize_or_zero()[i]);
                }
            }
            attr.indices[c] = *row;
        }
        drop_unused_rows(&mut attr);
        self.corner_attributes[k] = attr;
    }
}

/// The vector area of a polygon (Newell): its normal times twice its area.
fn vector_area(p: &[DVec3], face: &[u32]) -> DVec3 {
    let mut n = DVec3::ZERO;
    for (i, &a) in face.iter().enumerate() {
        let b = face[(i + 1) % face.len()];
        n += p[a as usize].cross(p[b as usize]);
    }
    n
}

fn is_float(d: Option<&AttributeData>) -> bool {
    matches!(d, Some(AttributeData::F32(_) | AttributeData::F64(_)))
}

/// Sets a float column's row `i` to `x`.
fn set(d: &mut AttributeData, i: usize, x: f64) {
    match d {
        AttributeData::F32(v) => v[i] = x as f32,
        AttributeData::F64(v) => v[i] = x,
        _ => {}
    }
}

/// Removes pool rows no corner refers to any more, keeping the order of the others.
fn drop_unused_rows(attr: &mut super::CornerAttribute) {
    let mut used = vec![false; attr.pool_len()];
    for &i in attr.indices.iter().filter(|&&i| i != super::NO_VALUE) {
        used[i as usize] = true;
    }
    if used.iter().all(|&u| u) {
        return;
    }
    let kept: Vec<u32> = (0..used.len() as u32)
        .filter(|&r| used[r as usize])
        .collect();
    let mut new_row = vec![super::NO_VALUE; used.len()];
    for (n, &r) in kept.iter().enumerate() {
        new_row[r as usize] = n as u32;
    }
    for i in attr.indices.iter_mut().filter(|i| **i != super::NO_VALUE) {
        *i = new_row[*i as usize];
    }
    for c in &mut attr.columns {
        *c = c.gathered(&kept);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::CornerAttribute;

    /// Two triangles folded at 90° along the edge 0–1, with a hard edge there: each face's
    /// corners have the face's own normal.
    fn folded() -> PolygonMesh {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        let mut m = PolygonMesh::from_triangles(p, &[[0, 1, 2], [1, 0, 3]]);
        m.corner_attributes.push(CornerAttribute::from_rows(
            NORMAL,
            ["nx", "ny", "nz"],
            &[[0.0, 0.0, 1.0], [0.0, 1.0, 0.0]],
            vec![0, 0, 0, 1, 1, 1],
        ));
        m
    }

    #[test]
    fn a_moved_fold_keeps_its_hard_edge_and_unmoved_normals_keep_their_bits() {
        let mut m = folded();
        let before = m.positions.clone();
        m.refresh_normals(&before);
        assert_eq!(m, folded(), "nothing moved, nothing changes");
        m.positions[3] = DVec3::new(0.0, -1.0, 1.0);
        m.refresh_normals(&before);
        let n = m.corner_attribute(NORMAL).unwrap();
        let value = |c: usize| DVec3::from_slice(&n.value(c).unwrap());
        assert_eq!(
            value(0),
            DVec3::Z,
            "the unmoved face's corners keep their normal"
        );
        let tilted = DVec3::new(0.0, 1.0, 1.0).normalize();
        for c in 3..6 {
            assert!(value(c).angle_between(tilted) < 1e-6, "{}", value(c));
        }
        assert_eq!(
            n.pool_len(),
            4,
            "a row per moved cluster (vertex), the unused one dropped"
        );
    }
}
