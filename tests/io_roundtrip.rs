//! Round trips for every format and PLY encoding: bit-exact positions, faces, order and
//! attributes; write → read → write byte-identical.

mod common;

use common::*;
use glam::DVec3;
use meshpyr::io::{
    self, MeshFormat, PlyEncoding, WriteOptions, read_mesh, read_mesh_bytes, write_mesh_bytes,
};
use meshpyr::mesh::{Attribute, AttributeData, PolygonMesh, ScalarType};

#[test]
fn ply_rich_mesh_round_trips_in_every_encoding() {
    let m = rich_mesh();
    for enc in ENCODINGS {
        let r = trip(&m, MeshFormat::Ply, &ply(enc));
        assert_eq!(r, m, "{enc:?}");
        assert_eq!(position_bits(&r), position_bits(&m));
    }
}

#[test]
fn ply_double_positions_stay_double() {
    let mut m = rich_mesh();
    m.position_type = Some(ScalarType::F64);
    m.positions[0] = DVec3::new(0.1, 1e-300, std::f64::consts::PI);
    for enc in ENCODINGS {
        let bytes = write_mesh_bytes(&m, MeshFormat::Ply, &ply(enc)).unwrap();
        assert!(
            String::from_utf8_lossy(&bytes[..200]).contains("property double x"),
            "{enc:?}"
        );
        let r = trip(&m, MeshFormat::Ply, &ply(enc));
        assert_eq!(position_bits(&r), position_bits(&m), "{enc:?}");
        assert_eq!(r, m);
    }
}

#[test]
fn ply_untyped_positions_are_written_losslessly() {
    // All f32 values: float.
    let mut m = PolygonMesh::from_triangles(
        vec![DVec3::ZERO, DVec3::X, DVec3::new(0.0, 0.5, 0.0)],
        &[[0, 1, 2]],
    );
    let b = write_mesh_bytes(&m, MeshFormat::Ply, &Default::default()).unwrap();
    assert!(String::from_utf8_lossy(&b).contains("property float x"));
    let r = read_mesh_bytes(&b, MeshFormat::Ply).unwrap();
    assert_eq!(r.position_type, Some(ScalarType::F32));
    assert_eq!(position_bits(&r), position_bits(&m));
    // A value that is not an f32 value: double, exact.
    m.positions[2].y = 0.1;
    m.positions[0].x = 1e300;
    let b = write_mesh_bytes(&m, MeshFormat::Ply, &Default::default()).unwrap();
    assert!(String::from_utf8_lossy(&b).contains("property double x"));
    let r = read_mesh_bytes(&b, MeshFormat::Ply).unwrap();
    assert_eq!(position_bits(&r), position_bits(&m));
    // An explicit f32 type is honoured (rounding), but overflow is an error, not infinity.
    m.position_type = Some(ScalarType::F32);
    m.positions[0].x = 1.0;
    let r = read_mesh_bytes(
        &write_mesh_bytes(&m, MeshFormat::Ply, &Default::default()).unwrap(),
        MeshFormat::Ply,
    )
    .unwrap();
    assert_eq!(r.positions[2].y, 0.1f32 as f64);
    m.positions[0].x = 1e300;
    let e = write_mesh_bytes(&m, MeshFormat::Ply, &Default::default()).unwrap_err();
    assert!(
        e.to_string().contains("vertex 0 does not fit in float"),
        "{e}"
    );
}

#[test]
fn ply_default_is_binary_little_endian_with_uchar_int_faces() {
    let m = rich_mesh();
    let b = write_mesh_bytes(&m, MeshFormat::Ply, &WriteOptions::default()).unwrap();
    let head = String::from_utf8_lossy(&b[..400]);
    assert!(head.starts_with("ply\nformat binary_little_endian 1.0\ncomment made by a test\n"));
    assert!(head.contains("property list uchar int vertex_indices\n"));
}

#[test]
fn ply_long_polygons_use_uint_counts() {
    let n = 300u32;
    let positions = (0..n)
        .map(|i| DVec3::new((i as f64).cos(), (i as f64).sin(), 0.0))
        .collect();
    let mut m = PolygonMesh::new();
    m.positions = positions;
    m.push_face(&(0..n).collect::<Vec<_>>());
    for enc in ENCODINGS {
        let r = trip(&m, MeshFormat::Ply, &ply(enc));
        assert_eq!(r.face(0), m.face(0));
    }
}

#[test]
fn real_ply_files_round_trip_bit_exactly() {
    for name in [
        "tetrahedron.ply",
        "cone20.ply",
        "cube_quad_poly.ply",
        "dodecahedron_poly.ply",
        "joint.ply",
        "planar_pymeshfix_vtk.ply",
    ] {
        let m = read_mesh(data(name)).unwrap();
        assert!(m.n_vertices() > 0 && m.n_faces() > 0);
        for enc in ENCODINGS {
            let r = trip(&m, MeshFormat::Ply, &ply(enc));
            assert_eq!(r, m, "{name} {enc:?}");
            assert_eq!(position_bits(&r), position_bits(&m));
        }
    }
    // Our binary LE output of a binary LE float/uchar-int file is the same body.
    let orig = data_bytes("cone20.ply");
    let m = read_mesh_bytes(&orig, MeshFormat::Ply).unwrap();
    let ours = write_mesh_bytes(&m, MeshFormat::Ply, &Default::default()).unwrap();
    let body = |b: &[u8]| {
        let i = b.windows(11).position(|w| w == b"end_header\n").unwrap();
        b[i + 11..].to_vec()
    };
    assert_eq!(body(&ours), body(&orig));
}

#[test]
fn vtk_obj_info_is_kept_as_a_comment() {
    let m = read_mesh(data("planar_pymeshfix_vtk.ply")).unwrap();
    assert_eq!(m.n_vertices(), 1403);
    assert_eq!(m.n_faces(), 2553);
    assert_eq!(
        m.comments,
        vec![
            "VTK generated PLY File".to_string(),
            "obj_info vtkPolyData points and polygons: vtk4.0".to_string()
        ]
    );
}

#[test]
fn obj_round_trip_keeps_positions_faces_and_attributes() {
    let mut m = PolygonMesh::new();
    m.positions = vec![
        DVec3::new(0.1, 0.2, 0.3),
        DVec3::new(1e-300, -0.0, 1e300),
        DVec3::new(std::f64::consts::PI, 2.0, -7.5),
        DVec3::new(5.0, 5.0, 5.0), // unreferenced
    ];
    m.push_face(&[0, 1, 2]);
    m.push_face(&[2, 1, 0, 3]);
    m.comments = vec!["hello".into()];
    let r = trip(&m, MeshFormat::Obj, &Default::default());
    assert_eq!(r, m);
    assert_eq!(position_bits(&r), position_bits(&m));

    // f32-typed positions are written with f32 shortest formatting and re-read bit-exactly.
    let tet = read_mesh(data("joint.ply")).unwrap();
    let r = trip(&tet, MeshFormat::Obj, &Default::default());
    assert_eq!(position_bits(&r), position_bits(&tet));
    assert_eq!(r.face_indices, tet.face_indices);
    assert_eq!(r.face_starts, tet.face_starts);

    // Colours, w, texture coordinates and normals survive when per-vertex.
    let f32col = |name: &str, v: Vec<f32>| Attribute {
        name: name.into(),
        data: AttributeData::F32(v),
    };
    m.vertex_attributes = vec![
        Attribute {
            name: "w".into(),
            data: AttributeData::F64(vec![1.0, 0.5, 2.0, 1.0]),
        },
        f32col("red", vec![0.1, 0.2, 0.3, 0.4]),
        f32col("green", vec![1.0, 0.0, 0.5, 0.25]),
        f32col("blue", vec![0.0, 1.0, 0.7, 0.125]),
        f32col("u", vec![0.0, 1.0, 0.5, 0.0]),
        f32col("v", vec![0.25, 0.75, 1.0, 0.0]),
        f32col("nx", vec![0.0, 1.0, 0.0, 0.0]),
        f32col("ny", vec![0.0, 0.0, 1.0, 0.0]),
        f32col("nz", vec![1.0, 0.0, 0.0, 0.0]),
    ];
    let r = trip(&m, MeshFormat::Obj, &Default::default());
    assert_eq!(r, m);
}

#[test]
fn obj_reader_handles_the_syntax_zoo() {
    let src = b"# header comment\r\n#second\r\nmtllib a.mtl\r\no obj\r\ng g1\r\n\
        v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nv 1 1 0\r\nv 9 9 9\r\n\
        vt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\nvn 0 0 1\n\
        usemtl m\ns off\ng g2\n\
        f 1/1/1 2/2/1 3/3/1\n\
        f -2/-1/-1 \\\n -3/-2/-1 -4/-3/-1 # trailing comment\n\
        l 1 2\np 5\n";
    let m = read_mesh_bytes(src, MeshFormat::Obj).unwrap();
    assert_eq!(
        m.n_vertices(),
        5,
        "unreferenced vertex 5 kept, no re-indexing per group"
    );
    assert_eq!(
        m.faces().collect::<Vec<_>>(),
        vec![&[0, 1, 2][..], &[3, 2, 1]]
    );
    assert_eq!(
        m.comments,
        vec!["header comment".to_string(), "second".to_string()]
    );
    // Four vt for five v: per corner, every line kept with each corner's index.
    assert!(m.vertex_attributes.is_empty());
    let uv = m.corner_attribute("texcoord").unwrap();
    assert_eq!(uv.indices, [0, 1, 2, 3, 2, 1]);
    assert_eq!(
        uv.columns[0].data,
        AttributeData::F32(vec![0.0, 1.0, 0.0, 1.0])
    );
    assert_eq!(m.corner_attribute("normal").unwrap().indices, [0; 6]);
    assert_eq!(m.materials.libraries, ["a.mtl"]);
    assert_eq!(m.materials.list[0].name, "m");
    assert_eq!(m.group_names, ["g1", "g2"]);
    assert_eq!(m.object_names, ["obj"]);
    let column = |name: &str| m.face_attribute(name).unwrap().data.clone();
    assert_eq!(column("obj_group"), AttributeData::I32(vec![1, 1]));
    assert_eq!(column("texnumber"), AttributeData::I32(vec![0, 0]));
    assert_eq!(column("obj_smoothing"), AttributeData::I32(vec![0, 0]));
    assert_eq!(m.position_type, Some(ScalarType::F32)); // short decimals: float data
}

#[test]
fn obj_conflicting_corner_normals_are_kept_per_corner() {
    let m = read_mesh(data("cube_degenerate_om.obj")).unwrap();
    assert_eq!(m.n_vertices(), 8);
    assert_eq!(m.n_faces(), 14);
    assert_eq!(m.face(10), &[1, 5, 7, 7, 1]);
    assert!(m.vertex_attributes.is_empty());
    let normals = m.corner_attribute("normal").unwrap();
    assert_eq!(normals.indices.len(), m.face_indices.len());
    assert_eq!(normals.n_valued(), m.face_indices.len());
    let again = read_mesh_bytes(
        &write_mesh_bytes(&m, MeshFormat::Obj, &Default::default()).unwrap(),
        MeshFormat::Obj,
    )
    .unwrap();
    assert_eq!(again.corner_attributes, m.corner_attributes);
}

#[test]
fn obj_vertex_colours_are_read() {
    let m = read_mesh_bytes(b"v 0 0 0 1 0.5 0\nv 1 0 0 0 0 1\n", MeshFormat::Obj).unwrap();
    assert_eq!(
        m.vertex_attribute("green").unwrap().data,
        AttributeData::F32(vec![0.5, 0.0])
    );
    // Mixed presence: colours dropped, positions kept.
    let m = read_mesh_bytes(b"v 0 0 0 1 0.5 0\nv 1 0 0\n", MeshFormat::Obj).unwrap();
    assert!(m.vertex_attributes.is_empty());
    assert_eq!(m.n_vertices(), 2);
}

#[test]
fn off_round_trips_and_variants() {
    for name in [
        "cube_quad.off",
        "tetrahedron.off",
        "cone20.off",
        "sphere_highval.off",
    ] {
        let m = read_mesh(data(name)).unwrap();
        let r = trip(&m, MeshFormat::Off, &Default::default());
        assert_eq!(r, m, "{name}");
        assert_eq!(position_bits(&r), position_bits(&m));
    }
    let m = read_mesh(data("cube_quad.off")).unwrap();
    assert_eq!(
        (m.n_vertices(), m.n_faces(), m.face(0)),
        (8, 6, &[0, 3, 7, 4][..])
    );
    let m = read_mesh(data("sphere_highval.off")).unwrap();
    assert_eq!(m.comments[0], "Output of a CGAL tool");

    // Per-face colours are kept.
    let m = read_mesh(data("mushroom_quad.off")).unwrap();
    assert_eq!((m.n_vertices(), m.n_faces()), (226, 240));
    let names: Vec<_> = m.face_attributes.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["red", "green", "blue"]);
    assert_eq!(trip(&m, MeshFormat::Off, &Default::default()), m);

    // COFF / NOFF / STOFF vertex data, counts on the header line, comments, CRLF.
    let src = b"STCNOFF 3 2 0 # counts here\r\n\
        0 0 0  0 0 1  1 0 0 1  0 0\r\n\
        \r\n\
        1 0 0  0 0 1  0 1 0 0.5  1 0\r\n\
        0 1 0  0 0 1  0 0 1 1  0 1 # comment\r\n\
        3 0 1 2 1 0 0\r\n\
        3 2 1 0 0 1 0\r\n";
    let m = read_mesh_bytes(src, MeshFormat::Off).unwrap();
    let names: Vec<_> = m
        .vertex_attributes
        .iter()
        .map(|a| a.name.as_str())
        .collect();
    assert_eq!(
        names,
        ["nx", "ny", "nz", "red", "green", "blue", "alpha", "u", "v"]
    );
    assert_eq!(
        m.vertex_attribute("alpha").unwrap().data,
        AttributeData::F32(vec![1.0, 0.5, 1.0])
    );
    assert_eq!(m.face_attributes.len(), 3);
    assert_eq!(trip(&m, MeshFormat::Off, &Default::default()), m);

    // Headerless OFF (counts first).
    let m = read_mesh_bytes(b"3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", MeshFormat::Off).unwrap();
    assert_eq!(m.n_faces(), 1);
}

#[test]
fn stl_binary_and_ascii_weld_and_round_trip() {
    let a = read_mesh(data("back_to_back_scad.stl")).unwrap();
    assert_eq!((a.n_vertices(), a.n_faces()), (6, 10));
    assert_eq!(a.position_type, Some(ScalarType::F32));
    let b = read_mesh(data("spider_assimp.stl")).unwrap();
    assert_eq!((b.n_vertices(), b.n_faces()), (722, 1368));
    for m in [a, b] {
        for binary in [true, false] {
            let opts = WriteOptions {
                stl_binary: binary,
                ..Default::default()
            };
            let r = trip(&m, MeshFormat::Stl, &opts);
            assert_eq!(r, m);
        }
    }
    // The welded STL agrees with the converted PLY of the same model (first-occurrence order).
    let stl = read_mesh(data("back_to_back_scad.stl")).unwrap();
    let first = stl.positions[..3].to_vec();
    assert_eq!(
        first,
        [
            DVec3::ZERO,
            DVec3::new(0.0, 4.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0)
        ]
    );
}

#[test]
fn stl_writer_triangulates_polygons_and_recomputes_normals() {
    let m = read_mesh(data("cube_quad.off")).unwrap();
    let b = write_mesh_bytes(&m, MeshFormat::Stl, &Default::default()).unwrap();
    assert_eq!(b.len(), 84 + 50 * 12);
    assert!(!b.starts_with(b"solid"));
    let r = read_mesh_bytes(&b, MeshFormat::Stl).unwrap();
    assert_eq!((r.n_vertices(), r.n_faces()), (8, 12));
    // First facet normal of the first quad (0 3 7 4 of the cube): −y.
    let n: Vec<f32> = (0..3)
        .map(|k| f32::from_le_bytes(b[84 + 4 * k..88 + 4 * k].try_into().unwrap()))
        .collect();
    assert_eq!(n, [0.0, -1.0, 0.0]);
}

#[test]
fn cross_format_conversions_keep_geometry() {
    let m = read_mesh(data("dodecahedron_poly.ply")).unwrap();
    for f in [MeshFormat::Obj, MeshFormat::Off, MeshFormat::Ply] {
        let b = write_mesh_bytes(&m, f, &Default::default()).unwrap();
        let r = read_mesh_bytes(&b, f).unwrap();
        assert_eq!(position_bits(&r), position_bits(&m), "{f}");
        assert_eq!(r.face_indices, m.face_indices);
        assert_eq!(r.face_starts, m.face_starts);
    }
}

#[test]
fn file_api_and_format_detection() {
    let dir = tempfile::tempdir().unwrap();
    let m = rich_mesh();
    for ext in ["ply", "PLY", "obj", "Off", "stl"] {
        let p = dir.path().join(format!("m.{ext}"));
        io::write_mesh(&p, &m).unwrap();
        let r = read_mesh(&p).unwrap();
        assert!(r.n_vertices() > 0, "{ext}");
    }
    let p = dir.path().join("m.ply");
    io::write_mesh_with(&p, &m, &ply(PlyEncoding::Ascii)).unwrap();
    assert!(
        std::fs::read(&p)
            .unwrap()
            .starts_with(b"ply\nformat ascii 1.0\n")
    );
    assert_eq!(read_mesh(&p).unwrap(), m);
    assert_eq!(
        MeshFormat::from_path(std::path::Path::new("a/b.StL")).unwrap(),
        MeshFormat::Stl
    );
}

#[test]
fn text_precision_rule_keeps_f32_and_f64_data_exact() {
    // f32 data → shortest f32 text → read back as the same f32 values.
    let mut m = PolygonMesh::from_triangles(
        vec![
            DVec3::new(0.1f32 as f64, 9.9653f32 as f64, -1.4305352f32 as f64),
            DVec3::new(1e-40f32 as f64, 3.4e38f32 as f64, 0.0),
            DVec3::new(1.0, 2.0, 3.0),
        ],
        &[[0, 1, 2]],
    );
    m.position_type = Some(ScalarType::F32);
    for f in [MeshFormat::Obj, MeshFormat::Off] {
        let b = write_mesh_bytes(&m, f, &Default::default()).unwrap();
        assert!(
            String::from_utf8_lossy(&b).contains("0.1 9.9653 -1.4305352"),
            "{f}"
        );
        let r = trip(&m, f, &Default::default());
        assert_eq!(position_bits(&r), position_bits(&m), "{f}");
        assert_eq!(r.position_type, Some(ScalarType::F32));
    }
    // f64 data whose shortest text looks like float data: one coordinate gets 17 digits.
    m.position_type = None;
    m.positions = vec![
        DVec3::new(0.1, 0.5, 2.0),
        DVec3::new(0.25, 0.3, 1.0),
        DVec3::ONE,
    ];
    for f in [MeshFormat::Obj, MeshFormat::Off] {
        let b = write_mesh_bytes(&m, f, &Default::default()).unwrap();
        let s = String::from_utf8_lossy(&b);
        assert!(s.contains("1.0000000000000001e-1 0.5 2"), "{s}");
        let r = trip(&m, f, &Default::default());
        assert_eq!(position_bits(&r), position_bits(&m), "{f}");
        assert_eq!(r.position_type, None);
    }
    // Long decimals are double data and are kept exactly.
    let r = read_mesh_bytes(b"v 0.1234567891 0 0\nv 1 0 0\n", MeshFormat::Obj).unwrap();
    assert_eq!(r.position_type, None);
    assert_eq!(r.positions[0].x, 0.1234567891);
}
