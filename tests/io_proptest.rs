//! Property tests: random polygon meshes with random attributes round-trip through every
//! writer/reader pair; random bytes never panic.

mod common;

use common::*;
use glam::DVec3;
use meshpyr::fuzzing::fuzz_read;
use meshpyr::io::{MeshFormat, WriteOptions, read_mesh_bytes, write_mesh_bytes};
use meshpyr::mesh::{
    Attribute, AttributeData, ElementProperty, ExtraElement, ListProperty, PolygonMesh, ScalarType,
};
use proptest::collection::vec;
use proptest::prelude::*;

fn finite_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        any::<f32>().prop_filter("finite", |x| x.is_finite()),
        -10.0f32..10.0,
        Just(0.0f32),
        Just(-0.0f32),
    ]
}

fn finite_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        any::<f64>().prop_filter("finite", |x| x.is_finite()),
        -10.0f64..10.0,
        Just(-0.0f64),
    ]
}

fn column(t: ScalarType, n: usize) -> BoxedStrategy<AttributeData> {
    match t {
        ScalarType::I8 => vec(any::<i8>(), n).prop_map(AttributeData::I8).boxed(),
        ScalarType::U8 => vec(any::<u8>(), n).prop_map(AttributeData::U8).boxed(),
        ScalarType::I16 => vec(any::<i16>(), n).prop_map(AttributeData::I16).boxed(),
        ScalarType::U16 => vec(any::<u16>(), n).prop_map(AttributeData::U16).boxed(),
        ScalarType::I32 => vec(any::<i32>(), n).prop_map(AttributeData::I32).boxed(),
        ScalarType::U32 => vec(any::<u32>(), n).prop_map(AttributeData::U32).boxed(),
        ScalarType::F32 => vec(finite_f32(), n).prop_map(AttributeData::F32).boxed(),
        ScalarType::F64 => vec(finite_f64(), n).prop_map(AttributeData::F64).boxed(),
    }
}

fn scalar_type() -> impl Strategy<Value = ScalarType> {
    prop_oneof![
        Just(ScalarType::I8),
        Just(ScalarType::U8),
        Just(ScalarType::I16),
        Just(ScalarType::U16),
        Just(ScalarType::I32),
        Just(ScalarType::U32),
        Just(ScalarType::F32),
        Just(ScalarType::F64),
    ]
}

fn attributes(prefix: &'static str, n: usize) -> impl Strategy<Value = Vec<Attribute>> {
    vec(scalar_type(), 0..4).prop_flat_map(move |types| {
        types
            .into_iter()
            .enumerate()
            .map(|(k, t)| {
                column(t, n).prop_map(move |data| Attribute {
                    name: format!("{prefix}{k}"),
                    data,
                })
            })
            .collect::<Vec<_>>()
    })
}

/// A list item value valid for its type.
fn item(t: ScalarType) -> BoxedStrategy<f64> {
    match t {
        ScalarType::I8 => any::<i8>().prop_map(f64::from).boxed(),
        ScalarType::U8 => any::<u8>().prop_map(f64::from).boxed(),
        ScalarType::I16 => any::<i16>().prop_map(f64::from).boxed(),
        ScalarType::U16 => any::<u16>().prop_map(f64::from).boxed(),
        ScalarType::I32 => any::<i32>().prop_map(f64::from).boxed(),
        ScalarType::U32 => any::<u32>().prop_map(f64::from).boxed(),
        ScalarType::F32 => finite_f32().prop_map(f64::from).boxed(),
        ScalarType::F64 => finite_f64().boxed(),
    }
}

fn extra_element(k: usize) -> impl Strategy<Value = ExtraElement> {
    (0usize..4, scalar_type(), scalar_type()).prop_flat_map(move |(rows, st, it)| {
        let count_type = prop_oneof![Just(ScalarType::U8), Just(ScalarType::I32)];
        (column(st, rows), vec(vec(item(it), 0..4), rows), count_type).prop_map(
            move |(col, lists, count_type)| {
                let mut starts = vec![0u32];
                let mut items = Vec::new();
                for l in lists {
                    items.extend(l);
                    starts.push(items.len() as u32);
                }
                ExtraElement {
                    name: format!("extra{k}"),
                    rows,
                    properties: vec![
                        ElementProperty::Scalar(Attribute {
                            name: "s".into(),
                            data: col,
                        }),
                        ElementProperty::List(ListProperty {
                            name: "l".into(),
                            count_type,
                            item_type: it,
                            starts,
                            items,
                        }),
                    ],
                }
            },
        )
    })
}

/// Random polygon mesh: positions of the given type, polygons of 1..8 corners (plus empty
/// ones when `allow_empty`), attributes, extra elements, comments.
fn mesh(pos_type: Option<ScalarType>, allow_empty: bool) -> impl Strategy<Value = PolygonMesh> {
    (1usize..12, 0usize..10).prop_flat_map(move |(nv, nf)| {
        let p = match pos_type {
            Some(ScalarType::F32) => vec([finite_f32(), finite_f32(), finite_f32()], nv)
                .prop_map(|v| {
                    v.into_iter()
                        .map(|c| DVec3::from_array(c.map(f64::from)))
                        .collect::<Vec<_>>()
                })
                .boxed(),
            _ => vec([finite_f64(), finite_f64(), finite_f64()], nv)
                .prop_map(|v| v.into_iter().map(DVec3::from_array).collect::<Vec<_>>())
                .boxed(),
        };
        let min = if allow_empty { 0 } else { 1 };
        (
            p,
            vec(vec(0..nv as u32, min..8), nf),
            attributes("va", nv),
            attributes("fa", nf),
            vec(0usize..2, 0..3),
            vec("[a-zA-Z0-9 _.,-]{0,16}", 0..3),
        )
            .prop_flat_map(move |(positions, faces, va, fa, extras, comments)| {
                let extras: Vec<_> = extras
                    .iter()
                    .enumerate()
                    .map(|(k, _)| extra_element(k))
                    .collect();
                extras.prop_map(move |extras| {
                    let mut m = PolygonMesh::new();
                    m.positions = positions.clone();
                    m.position_type = pos_type;
                    for f in &faces {
                        m.push_face(f);
                    }
                    m.vertex_attributes = va.clone();
                    m.face_attributes = fa.clone();
                    m.extra_elements = extras;
                    m.comments = comments.clone();
                    m
                })
            })
    })
}

/// Same geometry (bit for bit) and faces.
fn same_geometry(a: &PolygonMesh, b: &PolygonMesh) -> bool {
    position_bits(a) == position_bits(b)
        && a.face_starts == b.face_starts
        && a.face_indices == b.face_indices
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn ply_round_trip_f32(m in mesh(Some(ScalarType::F32), true)) {
        for enc in ENCODINGS {
            let r = trip(&m, MeshFormat::Ply, &ply(enc));
            prop_assert_eq!(&r, &m);
            prop_assert!(same_geometry(&r, &m));
        }
    }

    #[test]
    fn ply_round_trip_f64(m in mesh(Some(ScalarType::F64), true)) {
        for enc in ENCODINGS {
            let r = trip(&m, MeshFormat::Ply, &ply(enc));
            prop_assert_eq!(&r, &m);
            prop_assert!(same_geometry(&r, &m));
        }
    }

    #[test]
    fn obj_round_trip(m in mesh(None, false), f32pos in any::<bool>()) {
        let mut m = m;
        if f32pos {
            m.position_type = Some(ScalarType::F32);
            for p in &mut m.positions {
                *p = p.as_vec3().as_dvec3();
            }
            if m.positions.iter().any(|p| !p.is_finite()) {
                return Ok(());
            }
        }
        let r = trip(&m, MeshFormat::Obj, &WriteOptions::default());
        prop_assert!(same_geometry(&r, &m));
        prop_assert_eq!(&r.comments, &m.comments);
    }

    #[test]
    fn off_round_trip(m in mesh(None, true)) {
        let r = trip(&m, MeshFormat::Off, &WriteOptions::default());
        prop_assert!(same_geometry(&r, &m));
        prop_assert_eq!(&r.comments, &m.comments);
    }

    #[test]
    fn stl_round_trip(m in mesh(Some(ScalarType::F32), false), binary in any::<bool>()) {
        let opts = WriteOptions { stl_binary: binary, ..Default::default() };
        let b = write_mesh_bytes(&m, MeshFormat::Stl, &opts).unwrap();
        let r = read_mesh_bytes(&b, MeshFormat::Stl).unwrap();
        prop_assert_eq!(r.n_faces(), m.n_triangles());
        // Each triangle's corners are the original f32 coordinates.
        let mut k = 0;
        for f in m.faces() {
            for j in 2..f.len() {
                let want = [f[0], f[j - 1], f[j]].map(|v| m.positions[v as usize]);
                let got = r.face(k).iter().map(|&v| r.positions[v as usize]).collect::<Vec<_>>();
                prop_assert_eq!(got, want.to_vec());
                k += 1;
            }
        }
        // The welded mesh is a fixed point.
        let again = trip(&r, MeshFormat::Stl, &opts);
        prop_assert_eq!(again, r);
    }

    #[test]
    fn random_bytes_never_panic(bytes in vec(any::<u8>(), 0..300), f in 0usize..4) {
        let format = [MeshFormat::Obj, MeshFormat::Ply, MeshFormat::Off, MeshFormat::Stl][f];
        fuzz_read(format, &bytes);
    }

    #[test]
    fn random_ply_bodies_never_panic(body in vec(any::<u8>(), 0..200), enc in 0usize..3) {
        let head = format!(
            "ply\nformat {} 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             property float z\nproperty uchar red\nelement face 2\n\
             property list uchar int vertex_indices\nelement e 2\nproperty list uchar short l\n\
             end_header\n",
            ["ascii", "binary_little_endian", "binary_big_endian"][enc]
        );
        let mut b = head.into_bytes();
        b.extend(body);
        fuzz_read(MeshFormat::Ply, &b);
    }
}
