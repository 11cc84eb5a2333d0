//! The finest faces of an input whose repair copied vertices, read off the input and the
//! replayed hierarchy instead of running the builder's repair again.
//!
//! A scan straight from a scanner is a triangle mesh that is manifold but for a few pinched
//! vertices, which the builder splits into one copy per fan (`mesh::build`, step 3). Such a
//! file cannot take the clean path (its order has the copies' extra entries; nor can a
//! polygon mesh, whose triangles come from the builder's fans), and running the
//! builder's whole repair on the finest level to find where the copies went was most of
//! loading its hierarchy beyond the replay. But the file holds the answer: the replay rebuilt
//! the finest faces, and a copy sits exactly where the vertex it copies does. So each input
//! triangle is mapped to PM indices; one that touches a vertex with copies (by position) is
//! matched against the replay over every choice of copies and both orientations (the builder
//! may flip a triangle, swapping its last two corners), and must match exactly one face there.
//! When every triangle has its face and together they are exactly the replay's faces, they are
//! the builder's: the builder's face for a triangle is always among its candidates, and there
//! is only one. Anything else (ambiguous triangles, triangles flipped elsewhere, a copy whose
//! vertex cannot be told) sends the caller to the builder.

use crate::mesh::{PolygonMesh, SourceMap};
use crate::pm::{FaceBuckets, FlatReplay};
use glam::DVec3;

/// The input's triangles in PM indices, as far as they are known before the replay.
pub(super) struct CopiedFaces {
    /// Per triangle of the fan-triangulated input (without those with a repeated index, as
    /// the builder drops them): its corners in PM indices, the input vertices' own.
    faces: Vec<[u32; 3]>,
    /// The input polygon of each triangle.
    face_source: Vec<u32>,
    /// The triangles with a corner at a position that has copies, and their input vertices:
    /// their faces are found on the replay.
    pending: Vec<(u32, [u32; 3])>,
    /// Each copy's position bits and PM index, sorted.
    copies: Vec<([u64; 3], u32)>,
}

fn bits(p: DVec3) -> [u64; 3] {
    p.to_array().map(f64::to_bits)
}

/// The input's triangles mapped to PM indices through `mesh_to_pm` (the inverse of the file's
/// vertex order, a permutation; the entries past the input's vertices are the copies), with
/// the copies found by the PM's `positions`; `None` when the order does not cover the input.
pub(super) fn copied_faces(
    input: &PolygonMesh,
    mesh_to_pm: &[u32],
    positions: &[DVec3],
) -> Option<CopiedFaces> {
    let n_input = input.positions.len();
    if mesh_to_pm.len() < n_input {
        return None;
    }
    let pm_of = |v: u32| {
        mesh_to_pm
            .get(v as usize)
            .copied()
            .filter(|&p| p != u32::MAX)
    };
    let mut copies = Vec::with_capacity(mesh_to_pm.len() - n_input);
    for s in n_input..mesh_to_pm.len() {
        let p = pm_of(s as u32)?;
        copies.push((bits(*positions.get(p as usize)?), p));
    }
    copies.sort_unstable();
    let has_copies = |v: u32| {
        let key = bits(input.positions[v as usize]);
        copies
            .get(copies.partition_point(|c| c.0 < key))
            .is_some_and(|c| c.0 == key)
    };
    let mut faces = Vec::with_capacity(input.n_triangles());
    let mut face_source = Vec::with_capacity(input.n_triangles());
    let mut pending = Vec::new();
    for (fi, poly) in input.faces().enumerate() {
        for k in 1..poly.len().saturating_sub(1) {
            let t = [poly[0], poly[k], poly[k + 1]];
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                continue;
            }
            if t.iter().any(|&v| has_copies(v)) {
                pending.push((faces.len() as u32, t));
            }
            faces.push([pm_of(t[0])?, pm_of(t[1])?, pm_of(t[2])?]);
            face_source.push(fi as u32);
        }
    }
    Some(CopiedFaces {
        faces,
        face_source,
        pending,
        copies,
    })
}

impl CopiedFaces {
    /// The finest faces in PM indices (the builder's, face for face) and the map back onto
    /// the input, or `None` when they cannot be told without the builder. `pm_to_mesh` is the
    /// file's vertex order, `positions` the PM's.
    pub(super) fn resolve(
        self,
        n_input: usize,
        replay: &FlatReplay,
        pm_to_mesh: &[u32],
        positions: &[DVec3],
    ) -> Option<(Vec<[u32; 3]>, SourceMap)> {
        let CopiedFaces {
            mut faces,
            face_source,
            pending,
            copies,
        } = self;
        let n_total = positions.len();
        // The input vertex of every copy, from the triangles that use it.
        let mut copy_source = vec![u32::MAX; n_total.checked_sub(n_input)?];
        for (t, corners) in pending {
            let (face, chosen) = unique_face(faces[t as usize], &copies, positions, replay)?;
            for (&w, &p) in corners.iter().zip(&chosen) {
                let slot = *pm_to_mesh.get(p as usize)? as usize;
                match slot.checked_sub(n_input) {
                    None if slot == w as usize => {}
                    None => return None,
                    Some(copy) => {
                        let source = copy_source.get_mut(copy)?;
                        if *source != u32::MAX && *source != w {
                            return None;
                        }
                        *source = w;
                    }
                }
            }
            faces[t as usize] = face;
        }
        if copy_source.contains(&u32::MAX) || !replay.has_faces(&FaceBuckets::new(&faces, n_total))
        {
            return None;
        }
        let mut vertex_source: Vec<u32> = (0..n_input as u32).collect();
        vertex_source.extend(copy_source);
        let source = SourceMap {
            vertex_source,
            face_source,
            input_vertices: n_input,
        };
        Some((faces, source))
    }
}

/// The one face of the replay that a triangle (`direct`: its corners in PM indices, the input
/// vertices' own) can be, each corner the vertex itself or a copy at its position, in either
/// orientation: the face as the builder lists it (a flipped triangle has its last two corners
/// swapped), and the PM vertex at each of the triangle's corners. `None` unless exactly one
/// matches.
fn unique_face(
    direct: [u32; 3],
    copies: &[([u64; 3], u32)],
    positions: &[DVec3],
    replay: &FlatReplay,
) -> Option<([u32; 3], [u32; 3])> {
    let candidates = direct.map(|p| {
        let key = bits(positions[p as usize]);
        let from = copies.partition_point(|c| c.0 < key);
        let same = copies[from..].iter().take_while(|c| c.0 == key);
        std::iter::once(p)
            .chain(same.map(|c| c.1))
            .collect::<Vec<u32>>()
    });
    let mut found = None;
    for &x in &candidates[0] {
        for &y in &candidates[1] {
            for &z in &candidates[2] {
                for face in [[x, y, z], [x, z, y]] {
                    if replay.has_face(face) {
                        if found.is_some() {
                            return None;
                        }
                        found = Some((face, [x, y, z]));
                    }
                }
            }
        }
    }
    found
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Mesh, PolygonMesh};
    use crate::pm::{PmOptions, ProgressiveMesh};
    use crate::progress::NoProgress;

    fn data(name: &str) -> PolygonMesh {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
        crate::io::read_mesh(path.join(name)).unwrap()
    }

    /// Faces in PM indices and the map back onto the input.
    type ReadOff = Option<(Vec<[u32; 3]>, SourceMap)>;

    /// The faces and map back read off the input and the replay, as a reader finds them.
    fn read_off(input: &PolygonMesh) -> (ReadOff, ProgressiveMesh) {
        let built = Mesh::from_polygons(input).unwrap();
        let pm = ProgressiveMesh::build(&built.mesh, &PmOptions::default(), &NoProgress).unwrap();
        let positions = pm.original_positions();
        let n_base = pm.n_base_vertices();
        let base = pm.level_triangles(n_base);
        let mut replay = FlatReplay::new(&positions[..n_base], &base, pm.splits().len()).unwrap();
        for s in pm.splits() {
            replay.apply(s).unwrap();
        }
        let found = copied_faces(input, pm.mesh_to_pm(), positions)
            .and_then(|c| c.resolve(input.positions.len(), &replay, pm.pm_to_mesh(), positions));
        (found, pm)
    }

    #[test]
    fn copied_vertices_and_polygons_give_the_builders_faces_without_the_builder() {
        for name in [
            "planar_pymeshfix_vtk.ply",
            "cube_quad_poly.ply",
            "joint.ply",
        ] {
            let input = data(name);
            let (found, pm) = read_off(&input);
            let (faces, source) = found.unwrap_or_else(|| panic!("{name}: not read off"));
            assert_eq!(faces, pm.finest_faces(), "{name}");
            assert_eq!(
                source,
                Mesh::from_polygons(&input).unwrap().source,
                "{name}"
            );
        }
    }

    #[test]
    fn triangles_the_builder_flipped_or_could_have_placed_elsewhere_go_to_the_builder() {
        // Flipped triangles, solids touching along edges, detached vertices.
        for name in [
            "spider_assimp.ply",
            "back_to_back_scad.stl",
            "snowden_lo.ply",
        ] {
            let input = data(name);
            let (found, pm) = read_off(&input);
            // Read off only when it is the builder's, face for face.
            if let Some((faces, source)) = found {
                assert_eq!(faces, pm.finest_faces(), "{name}");
                assert_eq!(
                    source,
                    Mesh::from_polygons(&input).unwrap().source,
                    "{name}"
                );
            }
        }
        let (found, _) = read_off(&data("spider_assimp.ply"));
        assert!(
            found.is_none(),
            "flipped triangles are the builder's to tell"
        );
    }
}
