//! The readers' fuzzing and corpus-replay harness.

use super::{MeshFormat, PlyEncoding, WriteOptions, gz, read_mesh_bytes, write_mesh_bytes};
use crate::mesh::PolygonMesh;

/// Fuzzing and corpus-replay harness: parses `bytes` as `format`; when that succeeds, writes
/// the mesh (every PLY encoding, both STL flavours), re-reads it and asserts that writing the
/// re-read mesh gives identical bytes, and that PLY encodings agree with each other.
///
/// Panics only on a reader/writer inconsistency (a bug), never because the input is bad.
pub(crate) fn fuzz_read(format: MeshFormat, bytes: &[u8]) {
    let Ok(mesh) = read_mesh_bytes(bytes, format) else {
        return;
    };
    if let Err(e) = mesh.check() {
        panic!("the reader returned a mesh that breaks the invariants: {e}");
    }
    // A gzipped file's comments are dropped while inflating: the reader must not notice.
    if let Some(squeezed) = gz::squeeze(bytes, format, 4096) {
        let again = read_mesh_bytes(&squeezed, format)
            .unwrap_or_else(|e| panic!("the comment squeezer broke a readable file: {e}"));
        assert!(
            again.comments == mesh.comments
                && again.face_indices == mesh.face_indices
                && again.face_starts == mesh.face_starts
                && again.n_vertices() == mesh.n_vertices(),
            "the comment squeezer changed the mesh"
        );
    }
    let option_sets: Vec<WriteOptions> = match format {
        MeshFormat::Ply => vec![
            WriteOptions {
                ply_encoding: PlyEncoding::BinaryLittleEndian,
                ..Default::default()
            },
            WriteOptions {
                ply_encoding: PlyEncoding::BinaryBigEndian,
                ..Default::default()
            },
            WriteOptions {
                ply_encoding: PlyEncoding::Ascii,
                ..Default::default()
            },
        ],
        MeshFormat::Stl => vec![
            WriteOptions::default(),
            WriteOptions {
                stl_binary: false,
                ..Default::default()
            },
        ],
        _ => vec![WriteOptions::default()],
    };
    let mut canonical: Option<Vec<u8>> = None;
    for opts in &option_sets {
        let first = write_mesh_bytes(&mesh, format, opts)
            .unwrap_or_else(|e| panic!("writing a mesh the reader accepted failed: {e}"));
        let again = read_mesh_bytes(&first, format)
            .unwrap_or_else(|e| panic!("re-reading our own output failed ({opts:?}): {e}"));
        // Geometry survives the trip bit for bit (STL output is welded on reading, and the
        // STL reader's meshes are already welded).
        let bits = |m: &PolygonMesh| -> Vec<[u64; 3]> {
            m.positions
                .iter()
                .map(|p| p.to_array().map(f64::to_bits))
                .collect()
        };
        assert!(bits(&again) == bits(&mesh), "positions changed ({opts:?})");
        assert!(
            again.face_starts == mesh.face_starts && again.face_indices == mesh.face_indices,
            "faces changed ({opts:?})"
        );
        let second = write_mesh_bytes(&again, format, opts)
            .unwrap_or_else(|e| panic!("writing the re-read mesh failed: {e}"));
        assert!(
            first == second,
            "write → read → write is not byte-identical ({opts:?})"
        );
        if format != MeshFormat::Ply {
            continue;
        }
        // All PLY encodings must decode to the same mesh: compare via the LE encoding, with
        // NaN payloads made canonical (ASCII writes every NaN as `NaN`).
        let le =
            write_mesh_bytes(&canonical_nans(&again), format, &option_sets[0]).expect("re-encode");
        match &canonical {
            None => canonical = Some(le),
            Some(c) => assert!(*c == le, "PLY encodings disagree ({opts:?})"),
        }
    }
}

/// `mesh` with every NaN attribute value replaced by the canonical NaN.
fn canonical_nans(mesh: &PolygonMesh) -> PolygonMesh {
    use crate::mesh::{AttributeData, ElementProperty};
    fn fix(d: &mut AttributeData) {
        match d {
            AttributeData::F32(v) => v
                .iter_mut()
                .filter(|x| x.is_nan())
                .for_each(|x| *x = f32::NAN),
            AttributeData::F64(v) => v
                .iter_mut()
                .filter(|x| x.is_nan())
                .for_each(|x| *x = f64::NAN),
            _ => {}
        }
    }
    let mut m = mesh.clone();
    m.vertex_attributes
        .iter_mut()
        .for_each(|a| fix(&mut a.data));
    m.face_attributes.iter_mut().for_each(|a| fix(&mut a.data));
    for a in &mut m.corner_attributes {
        a.columns.iter_mut().for_each(|c| fix(&mut c.data));
    }
    for l in &mut m.face_lists {
        l.items
            .iter_mut()
            .filter(|x| x.is_nan())
            .for_each(|x| *x = f64::NAN);
    }
    for e in &mut m.extra_elements {
        for p in &mut e.properties {
            match p {
                ElementProperty::Scalar(a) => fix(&mut a.data),
                ElementProperty::List(l) => l
                    .items
                    .iter_mut()
                    .filter(|x| x.is_nan())
                    .for_each(|x| *x = f64::NAN),
            }
        }
    }
    m
}
